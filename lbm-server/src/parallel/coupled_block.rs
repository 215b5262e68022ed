//! The coupled step of one rank's block ([`BlockLattice::step_coupled_with`]): every rank steps
//! the same particles (rank 0 sends them their states: `coupled/ranks.rs`), in the whole lattice's
//! coordinates, over its own cells; the halo exchange overlaps the update of the block's interior
//! (the step's fluid kernels split by region, `lbm/imb/by_region.rs`), or follows the whole step
//! where `[parallel] overlap = false` (a CPU driver's default); each rank other than 0 sends rank 0 its share of the loads
//! (`lbm/imb/share.rs`: the loads of the particles whose box it holds alone, the covered cells it
//! holds of those across a cut), from which rank 0 makes every particle's load in the single
//! process's order (`lbm/imb/gathered.rs`): the same bits as one process.

use super::block::BlockLattice;
use super::communicator::Communicator;
use super::decomposition::Decomposition;
use super::halo::Halo;
use crate::lbm::geometry::Setup;
use crate::lbm::imb::{ImbBlock, ImbOptions, SolidParticles};

/// The coupling's `options` for the block `d` of the lattice `whole`: on several ranks, where the
/// block lies (its own cells covered alone, the particles in the whole lattice's coordinates).
pub(super) fn block_options(options: ImbOptions, d: &Decomposition, whole: &Setup) -> ImbOptions {
    if d.ranks() == 1 {
        return options;
    }
    let own_lo = d.origin;
    let own_hi: [usize; 3] = std::array::from_fn(|a| d.origin[a] + d.size[a]);
    let (interior_lo, interior_hi) = Halo::interior(d, d.local_n());
    ImbOptions {
        block: Some(ImbBlock {
            whole: whole.n,
            periodic: std::array::from_fn(|a| whole.periodic(a)),
            own_lo,
            own_hi,
            base: std::array::from_fn(|a| own_lo[a] as i64 - d.lo(a) as i64),
            interior_lo,
            interior_hi,
        }),
        ..options
    }
}

/// The bytes a rank sent rank 0 for the particles' loads (its shares), over its coupled steps.
#[derive(Debug, Clone, Copy, Default)]
pub struct SharesSent {
    pub bytes: u64,
    pub steps: u64,
}

impl SharesSent {
    /// Bytes per coupled step, the mean over the steps (0 before the first).
    pub fn per_step(&self) -> usize {
        self.bytes.checked_div(self.steps).unwrap_or(0) as usize
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
        let overlapped = self.overlaps();
        let Some(halo) = &mut self.halo else {
            return self.lattice.step_coupled_with(particles, out, load);
        };
        let step = match overlapped {
            true => self.lattice.step_coupled_unread(
                particles,
                Some(&mut |lattice| halo.step_overlapped(lattice, comm)),
            )?,
            false => {
                let step = self.lattice.step_coupled_unread(particles, None)?;
                halo.exchange(&self.lattice, comm);
                step
            }
        };
        let share = match comm.rank() {
            0 => Vec::new(),
            _ => self.lattice.share(&step)?,
        };
        self.shares_sent.bytes += share.len() as u64;
        self.shares_sent.steps += 1;
        let shares = comm.gather(&share);
        if comm.rank() != 0 {
            out.clear();
            return Ok(());
        }
        self.lattice.loads_from_shares(&step, &shares, out, load)
    }
}
