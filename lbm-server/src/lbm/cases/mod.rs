//! Analytic validation cases of the lattice (lattice units). Each returns what it measured, so the
//! tests assert on it and `lbm-server validate` writes it to validation/lbm/REPORT.md.

mod array;
mod channel;
mod conservation;
mod decay;
mod sphere;
mod stability;
mod weighted_array;

pub use array::*;
pub use channel::*;
pub use conservation::*;
pub use decay::*;
pub use sphere::*;
pub use stability::*;
pub use weighted_array::*;

use crate::lbm::geometry::Setup;
use crate::lbm::gpu::{Gpu, GpuLattice, Health};
use crate::lbm::imb::ImbOptions;
use std::sync::Arc;

/// Steps for a diffusive start-up to decay by e^-k: k L^2 / (pi^2 nu).
fn relaxation_steps(length: f64, nu: f64, k: f64) -> u64 {
    (k * length * length / (std::f64::consts::PI.powi(2) * nu)).ceil() as u64 + 100
}

/// The mean velocity along x through the plane x of an n^3 lattice's `fields` (the volumetric
/// flux over its area); a moving sphere must not cut the plane (the fluid inside an immersed
/// boundary moves with it, so the plane would count it).
fn plane_flux(fields: &[[f32; 4]], n: usize, x: usize) -> f64 {
    (0..n * n).map(|k| fields[x + k * n][1] as f64).sum::<f64>() / (n * n) as f64
}

/// A lattice coupled to particles, with the default health limits.
fn coupled_lattice(gpu: &Arc<Gpu>, setup: &Setup, options: ImbOptions) -> GpuLattice {
    GpuLattice::new(gpu.clone(), setup.clone(), Health::default(), Some(options)).expect("lattice")
}
