//! The coupled step of a decomposed lattice's block with its fluid kernels split by region
//! ([`GpuLattice::coupled_passes_by_region`]), so that the halo exchange overlaps the update of
//! the block's interior as in a fluid-only step (`crate::parallel::halo`, `Halo::step_overlapped`).
//!
//! Every pass other than the fluid kernels runs over the covered cells or the particles, not by
//! region, and keeps its place in the step: skipped, the covered cells collide (and the loads go
//! back) before the fluid kernels, whose regions then skip them, and the cover mask is cleared
//! after the last region; fused, `cover` goes first, the fluid kernels (which give the covered
//! cells their solid term) by region, then `reduce` and the loads. The slots the exchange reads and
//! writes are the shell's, updated by region 0 or, skipped, by `collide_covered` before it, and
//! every pass keeps its parity, so the step leaves the bits of the step in one piece. The redo
//! cannot be split so: its `store_covered` overwrites the covered cells' slots after the fluid
//! kernels, wherever they lie, some of them the shell's that the exchange has already sent.

use super::passes::StepPasses;
use super::step::Split;
use crate::lbm::gpu::GpuLattice;
use crate::lbm::imb::CoveredCells;

/// The fluid kernels of one step split by region, the halo exchanged between them: they submit
/// every region and end the step (`Halo::step_overlapped`).
pub type FluidByRegion<'a> = &'a mut dyn FnMut(&mut GpuLattice);

impl GpuLattice {
    /// Whether a step of this lattice may be split by region (its fluid kernels run by
    /// [`FluidByRegion`]): without particles, or with the covered cells skipped or fused, not
    /// redone (the module's account).
    pub fn splits_by_region(&self) -> bool {
        self.regions() > 0 && self.options.is_none_or(|_| self.way().mode != CoveredCells::Redo)
    }

    /// The coupled step's device passes over the `n` particles with `passes` (this step's; staged
    /// before), the fluid kernels run by `fluid`: the loads' bytes and the submission of their copy
    /// for the host.
    pub(super) fn coupled_passes_by_region(
        &mut self,
        n: u32,
        passes: &StepPasses,
        fluid: FluidByRegion,
    ) -> (u64, wgpu::SubmissionIndex) {
        let split: Split = &mut |_, encoder| encoder;
        let encoder = self.gpu.device.create_command_encoder(&Default::default());
        let encoder = self.encode_cover(encoder, &passes.cover, n, split);
        let Some(covered) = &passes.covered else {
            // Fused: the solid term in the fluid kernels, the loads reduced after them.
            self.gpu.queue.submit([encoder.finish()]);
            fluid(self);
            let encoder = self.gpu.device.create_command_encoder(&Default::default());
            let encoder = self.encode_reduce(encoder, passes, n, split);
            return self.submit_with_loads(encoder, n);
        };
        assert!(covered.store.is_none(), "the redo's step is not split by region");
        let encoder = self.encode_covered_collision(encoder, covered, split);
        let encoder = self.encode_reduce(encoder, passes, n, split);
        let loads = self.submit_with_loads(encoder, n);
        fluid(self);
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        self.clear_cover_mask(&mut encoder);
        self.gpu.queue.submit([encoder.finish()]);
        loads
    }
}
