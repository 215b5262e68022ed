//! The fluid side of a run with particles: the GPU lattice coupled to them by the immersed moving
//! boundary (a scene with particles must have a `[lattice]`; `run/prepare.rs` refuses one
//! without).
//!
//! - `fluid_side.rs`: [`FluidSide`], made for a scene, stepped with the DEM's states into their
//!   loads; its health checks in `health.rs`, its field outputs in `field_outputs.rs`, the ways its
//!   covered cells take their solid term in `ways.rs`.
//! - `ranks.rs`: on several ranks, rank 0 leads the others' fluid sides step by step
//!   ([`follow`]).
//! - `states.rs`: the DEM's states as the lattice's particles (lattice units, drawn radius).
//! - `accuracy.rs`: the immersed boundary's accuracy as validation/lbm/REPORT.md measured it;
//!   `radius_correction.rs`: `coupling.radius_correction` drawn from it; `warnings.rs`: what a
//!   scene's lattice is warned of by it.

mod accuracy;
mod field_outputs;
mod fluid_side;
mod health;
mod radius_correction;
mod ranks;
mod states;
mod warnings;
mod ways;

pub use fluid_side::FluidSide;
pub(crate) use radius_correction::calibrated_drawn_larger;
pub use ranks::follow;
