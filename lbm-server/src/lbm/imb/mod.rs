//! Host side of the immersed moving boundary (shaders/imb.wgsl; seed eq. 7-11): the coupling's
//! settings, which cells a particle covers, the records that cross to the device and back, the
//! coupling's buffers and kernels, the host's passes over the particles and their loads, and the
//! coupled step that returns each particle's force and torque (with its timed variants).
//!
//! The step maps the particles' solid fractions onto the cells (`cover`), collides the fluid with
//! the solid term where they cover it (in the fluid kernels or before them), and reduces each
//! particle's force and torque from its cells (the table of passes at step.rs's `coupled_step`).

mod block;
mod box_ranks;
mod by_region;
mod chunks;
mod coupling;
mod cover;
mod gathered;
mod loads;
mod options;
mod passes;
mod records;
mod share;
mod staging;
mod step;
mod timing;

pub use block::ImbBlock;
#[cfg(test)]
pub use box_ranks::{BoxRanks, StepBoxes};
#[cfg(test)]
pub(super) use chunks::CHUNK;
pub(super) use coupling::Coupling;
#[cfg(test)]
pub(crate) use cover::box_edge;
pub use cover::{covered_fraction, solid_reach};
pub use options::{CoveredCells, ImbOptions, SolidCollision};
pub(super) use passes::Passes;
pub use records::{Load, LostCovers, SolidParticle, SolidParticles};
#[cfg(test)]
pub(super) use staging::into_lattice;
