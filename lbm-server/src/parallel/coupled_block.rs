//! The coupled step of one rank's block ([`BlockLattice::step_coupled_with`]): every rank steps
//! the same particles (rank 0 sends them their states: `coupled/ranks.rs`), in the whole lattice's
//! coordinates, over its own cells; the halo is exchanged after the whole step (not overlapped:
//! the redo's passes over the covered cells write into the shell's slots after the fluid kernels,
//! docs/imb.md); every rank's pairs (each particle's
//! momentum per cell of its box) are gathered at rank 0, which reduces the loads from them in the
//! single process's order (`lbm/imb/gathered.rs`): the same bits as one process.

use super::block::BlockLattice;
use super::communicator::Communicator;
use super::decomposition::Decomposition;
use crate::lbm::geometry::Setup;
use crate::lbm::imb::{merge_pairs, ImbBlock, ImbOptions, SolidParticles};

/// The coupling's `options` for the block `d` of the lattice `whole`: on several ranks, where the
/// block lies (its own cells covered alone, the particles in the whole lattice's coordinates).
pub(super) fn block_options(options: ImbOptions, d: &Decomposition, whole: &Setup) -> ImbOptions {
    if d.ranks() == 1 {
        return options;
    }
    let own_lo = d.origin;
    let own_hi: [usize; 3] = std::array::from_fn(|a| d.origin[a] + d.size[a]);
    ImbOptions {
        block: Some(ImbBlock {
            whole: whole.n,
            periodic: std::array::from_fn(|a| whole.periodic(a)),
            own_lo,
            own_hi,
            base: std::array::from_fn(|a| own_lo[a] as i64 - d.lo(a) as i64),
        }),
        ..options
    }
}

impl BlockLattice {
    /// One coupled step with `particles` (the same on every rank), and at rank 0 `load(j, load of
    /// j)` for each particle j in `out` (replaced; emptied elsewhere). On one rank the single
    /// process's step.
    pub fn step_coupled_with<P: SolidParticles + ?Sized, T: Send>(
        &mut self,
        particles: &P,
        out: &mut Vec<T>,
        load: impl Fn(usize, crate::lbm::imb::Load) -> T + Sync,
        comm: &dyn Communicator,
    ) -> Result<(), String> {
        let Some(halo) = &mut self.halo else {
            return self.lattice.step_coupled_with(particles, out, load);
        };
        self.lattice.step_coupled_unread(particles)?;
        halo.exchange(&self.lattice, comm);
        let pieces = comm.gather(&self.lattice.step_pairs());
        if comm.rank() != 0 {
            out.clear();
            return Ok(());
        }
        self.lattice.reduce_gathered(&merge_pairs(&pieces), out, load)
    }
}
