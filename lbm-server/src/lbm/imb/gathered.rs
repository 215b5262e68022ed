//! The coupled step of one block of a lattice decomposed over ranks (`crate::parallel`): the
//! step's passes as on one process, each particle's load reduced from the block's own pairs
//! ([`GpuLattice::step_coupled_unread`]); what a rank other than 0 sends rank 0 of it
//! ([`GpuLattice::share`], `share.rs`); and at rank 0 the loads from every rank's share
//! ([`GpuLattice::loads_from_shares`]).
//!
//! Each cell of a particle's box belongs to one block, and the other blocks hold a zero pair
//! there (w = 0: not covered). Where one block holds all of a box's cells, its pairs are the
//! single process's, pair for pair, and its `reduce` and `sum_loads` give the single process's
//! load bit for bit: its rank sends the load. Where a box crosses a cut, each rank sends the
//! covered cells it holds, and rank 0 reduces the load from them beside its own in the single
//! process's order (partial loads per rank, added afterwards, would not be the same bits).

use super::box_ranks::{BoxRanks, StepBoxes};
use super::by_region::FluidByRegion;
use super::loads::convert_loads;
use super::passes::StepPasses;
use super::records::{GpuLoad, Load, SolidParticles, PAIR_BYTES};
use super::share::{share_of, Share};
use super::step::Split;
use crate::lbm::gpu::GpuLattice;

/// A block's coupled step whose loads are not read yet: where the particles' boxes lie among the
/// blocks, and the bytes and submission of the block's loads copied for the host.
pub struct BlockStep {
    boxes: StepBoxes,
    loads: (u64, wgpu::SubmissionIndex),
}

impl GpuLattice {
    /// The coupled step's passes with the particles (whole-lattice coordinates), all submitted:
    /// the block's covers, its covered cells' collision, the reduce of its own pairs (the covers
    /// cleared), the loads copied for the host, and the fluid kernels, in one piece or, with
    /// `by_region`, split by region with the halo exchanged between them (`by_region.rs`); the
    /// loads are not read.
    pub fn step_coupled_unread<P: SolidParticles + ?Sized>(
        &mut self,
        particles: &P,
        by_region: Option<FluidByRegion>,
    ) -> Result<BlockStep, String> {
        let block = self.options.and_then(|o| o.block).expect("a block's coupling");
        let (n, passes) = self.stage(particles)?;
        let loads = match by_region {
            Some(fluid) => self.coupled_passes_by_region(n, &passes, fluid),
            None => self.coupled_passes(n, &passes),
        };
        Ok(BlockStep {
            boxes: StepBoxes::of(particles, block),
            loads,
        })
    }

    /// The coupled step's device passes over the `n` particles with `passes` (this step's), in
    /// one piece as on one process: the loads' bytes and the submission of their copy for the host.
    fn coupled_passes(&mut self, n: u32, passes: &StepPasses) -> (u64, wgpu::SubmissionIndex) {
        let split: Split = &mut |_, encoder| encoder;
        let encoder = self.gpu.device.create_command_encoder(&Default::default());
        let encoder = self.encode_cover(encoder, &passes.cover, n, split);
        let encoder = self.encode_collision(encoder, passes, split);
        let encoder = self.encode_reduce(encoder, passes, n, split);
        let loads = self.submit_with_loads(encoder, n);
        self.submit_fluid_after_loads(passes, split);
        loads
    }

    /// What this rank (not 0) sends rank 0 of the step `step` (`share.rs`): the loads of the
    /// particles whose box it holds alone, the covered cells it holds of those across a cut.
    pub fn share(&self, step: &BlockStep) -> Result<Vec<u8>, String> {
        let rank = step.boxes.rank();
        let loads = match step.boxes.ranks().any(|r| r == BoxRanks::One(rank)) {
            true => self.block_loads(step)?,
            false => Vec::new(),
        };
        let pairs = self.pairs_to_last_several(step);
        Ok(share_of(&step.boxes, rank, &loads, &pairs))
    }

    /// At rank 0, after the step `step`: `load(j, load of j)` for each particle j in `out`
    /// (replaced), from every rank's `shares` (rank order; rank 0's not read): the boxes across a
    /// cut reduced by `reduce` and `sum_loads` from every rank's covered cells, as on one process.
    pub fn loads_from_shares<T: Send>(
        &mut self,
        step: &BlockStep,
        shares: &[Vec<u8>],
        out: &mut Vec<T>,
        load: impl Fn(usize, Load) -> T + Sync,
    ) -> Result<(), String> {
        let shares: Vec<Share> = (shares.iter().enumerate().skip(1))
            .map(|(rank, bytes)| Share { bytes, rank })
            .collect();
        let mut loads = match step.boxes.any_several() {
            true => {
                let mut pairs = self.pairs_to_last_several(step);
                shares.iter().for_each(|s| s.place_pairs(&step.boxes, &mut pairs));
                self.reduce_pairs(&pairs)?
            }
            false => self.block_loads(step)?,
        };
        shares.iter().for_each(|s| s.place_loads(&step.boxes, &mut loads));
        convert_loads(&loads, out, &load)
    }

    /// The loads this block reduced from its own pairs in the step `step`.
    fn block_loads(&self, step: &BlockStep) -> Result<Vec<GpuLoad>, String> {
        self.loads_of(step.loads.clone())
    }

    /// The loads of the submission `with_loads` (`bytes` of them), once on the host.
    fn loads_of(&self, (bytes, with_loads): (u64, wgpu::SubmissionIndex)) -> Result<Vec<GpuLoad>, String> {
        let mut loads = Vec::new();
        self.read_loads(bytes, with_loads, &mut |l| {
            loads.extend_from_slice(l);
            Ok(())
        })?;
        Ok(loads)
    }

    /// The block's pairs of the step `step` up to the last box across a cut (none where no box
    /// crosses one).
    fn pairs_to_last_several(&self, step: &BlockStep) -> Vec<[f32; 4]> {
        let bytes = step.boxes.pairs_to_last_several() * PAIR_BYTES;
        if bytes == 0 {
            return Vec::new();
        }
        let coupling = self.imb.as_ref().expect("coupling");
        bytemuck::pod_collect_to_vec(&self.gpu.read_buffer(&coupling.pairs, bytes))
    }

    /// The step's particles' loads reduced again by `reduce` and `sum_loads`, from `pairs` (the
    /// first of the step's).
    fn reduce_pairs(&mut self, pairs: &[[f32; 4]]) -> Result<Vec<GpuLoad>, String> {
        let coupling = self.imb.as_ref().expect("coupling");
        let n = coupling.staged.0;
        self.gpu
            .queue
            .write_buffer(&coupling.pairs, 0, bytemuck::cast_slice(pairs));
        let passes = self.step_passes()?;
        let encoder = self.gpu.device.create_command_encoder(&Default::default());
        let encoder = self.encode_reduce(encoder, &passes, n, &mut |_, encoder| encoder);
        self.loads_of(self.submit_with_loads(encoder, n))
    }
}
