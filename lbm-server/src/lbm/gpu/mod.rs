//! The lattice on the GPU (wgpu): the device, the lattice's state and its ways of stepping, the
//! buffers and bindings its kernels share, its parameters, the cell list, the step loop (AA
//! pattern), a step split into regions (a decomposed lattice's overlapped halo exchange), the
//! health check and the state a checkpoint holds.

mod bindings;
mod cell_list;
mod device;
mod halo;
mod health;
mod params;
mod region;
mod snapshot;
mod state;
mod step;
mod way;

pub use bindings::fits_device;
pub(in crate::lbm) use bindings::storage_buffer;
#[cfg(test)]
pub(in crate::lbm) use cell_list::CellList;
pub use device::Gpu;
#[cfg(test)]
pub(in crate::lbm) use device::ListLayout;
pub use halo::{HaloKernels, HaloLayer};
pub use health::{furthest_out_of_bounds, out_of_bounds, Health, Unhealthy};
pub(in crate::lbm) use params::vec4;
pub use snapshot::RawState;
pub use state::{equilibrium_field, total_mass, GpuLattice};
