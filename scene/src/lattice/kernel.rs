//! `lattice.kernel`: which fluid kernels step the lattice (lbm-server's `lbm/kernel.rs` holds
//! what each builds); "auto" leaves the choice to the run's start-up trial
//! (lbm-server/src/trials.rs).

/// The fluid kernels of a lattice: the quads' kernels, split by cell class into branch-free
/// dispatches over a cell list, built for CPU drivers such as lavapipe; or the per-cell kernel,
/// built for GPUs. Both leave the same populations bit for bit.
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

impl std::fmt::Display for Kernel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
