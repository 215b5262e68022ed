//! Which fluid kernels step the lattice (`lattice.kernel`): the quads' kernels, split by cell
//! class into branch-free dispatches over a cell list (four-cell quads where the storage is FP32
//! and the solid term is not fused), built for CPU drivers such as lavapipe; or the per-cell
//! kernel (shaders/cells.wgsl), one invocation per cell of the grid in one dispatch, built for
//! GPUs. Both leave the same populations bit for bit (the same arithmetic), so a run may change
//! kernels between any two steps: its start-up trial (trials.rs) times them on the device.

/// The fluid kernels of a lattice.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Kernel {
    /// By cell class over a cell list (interior, wrapping, boundary), four-cell quads where they
    /// apply (lbm.wgsl, quads.wgsl).
    #[default]
    Quads,
    /// One invocation per cell, one dispatch per step (cells.wgsl).
    Cells,
}

impl Kernel {
    pub const ALL: [Kernel; 2] = [Kernel::Quads, Kernel::Cells];

    /// The name in scenes and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Kernel::Quads => "quads",
            Kernel::Cells => "cells",
        }
    }

    pub fn named(name: &str) -> Option<Kernel> {
        Kernel::ALL.into_iter().find(|k| k.name() == name)
    }

    /// The name a run's first line and `bench` give it.
    pub fn describe(self) -> &'static str {
        match self {
            Kernel::Quads => "kernels by cell class (quads)",
            Kernel::Cells => "a thread per cell (cells)",
        }
    }
}
