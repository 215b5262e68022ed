//! The lattice-Boltzmann fluid: D3Q19 on the GPU (wgpu), with an f64 reference for the tests.

pub mod cases;
pub mod d3q19;
pub mod geometry;
pub mod gpu;
pub mod imb;
pub mod kernel;
pub mod mrt;
pub mod random;
#[cfg(test)]
pub mod reference;
pub mod storage;
#[cfg(test)]
mod storage_tests;
#[cfg(test)]
pub(crate) mod tests;
pub mod unroll;
