//! Which fluid kernels step the lattice (`lattice.kernel`): the quads' kernels, split by cell
//! class into branch-free dispatches over a cell list (four-cell quads where the storage is FP32
//! and the solid term is not fused), built for CPU drivers such as lavapipe; or the per-cell
//! kernel (shaders/cells.wgsl), one invocation per cell of the grid in one dispatch, built for
//! GPUs. Both leave the same populations bit for bit (the same arithmetic), so a run may change
//! kernels between any two steps: its start-up trial (trials.rs) times them on the device.

pub use scene::lattice::Kernel;
