//! The coupled step of a decomposed lattice's block with its fluid kernels split by region
//! ([`GpuLattice::coupled_passes_by_region`]), so that the halo exchange overlaps the update of
//! the block's interior as in a fluid-only step (`crate::parallel::halo`, `Halo::step_overlapped`).
//!
//! Every pass other than the fluid kernels runs over the covered cells or the particles, not by
//! region, and keeps its place in the step: skipped, the covered cells collide (and the loads go
//! back) before the fluid kernels, whose regions then skip them, and the cover mask is cleared
//! after the last region; fused, `cover` goes first, the fluid kernels (which give the covered
//! cells their solid term) by region, then `reduce` and the loads. Redone, the covered cells
//! collide and the loads go back before the fluid kernels, as skipped, and `store_covered`, which
//! writes each covered cell's populations over the fluid kernels' in the slots of that cell's
//! update, goes in two parts: the shell's covered cells right after the shell's update (region 0)
//! and before the exchange reads the shell, the others at the step's end, after the interior's
//! update. The slots the exchange reads and writes are the shell's, updated by region 0 (and,
//! skipped or redone, by the covered cells' passes beside it), and every pass keeps its parity,
//! so the step leaves the bits of the step in one piece.

use super::passes::StepPasses;
use super::step::Split;
use crate::lbm::gpu::GpuLattice;

/// The fluid kernels of one step split by region, the halo exchanged between them: they submit
/// every region and end the step (`Halo::step_overlapped`).
pub type FluidByRegion<'a> = &'a mut dyn FnMut(&mut GpuLattice);

impl GpuLattice {
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
        let encoder = self.encode_covered_collision(encoder, covered, split);
        let encoder = self.encode_reduce(encoder, passes, n, split);
        let loads = self.submit_with_loads(encoder, n);
        if covered.store.is_some() {
            let parts = covered.store_parts.clone();
            self.imb.as_mut().expect("coupling").store_by_region =
                Some(parts.expect("the redo's store in parts on a block"));
            fluid(self);
            assert!(
                self.imb.as_ref().is_some_and(|c| c.store_by_region.is_none()),
                "the split step stored the covered cells"
            );
            return loads;
        }
        fluid(self);
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        self.clear_cover_mask(&mut encoder);
        self.gpu.queue.submit([encoder.finish()]);
        loads
    }

    /// After the shell's fluid update (region 0) in `encoder`, in a redo's step split by region:
    /// the store of the shell's covered cells, before the exchange reads the shell.
    pub(in crate::lbm) fn encode_store_of_shell(&self, encoder: &mut wgpu::CommandEncoder) {
        let parts = self.imb.as_ref().and_then(|c| c.store_by_region.as_ref());
        if let Some([shell, _]) = parts {
            self.encode_store(encoder, shell, self.time % 2);
        }
    }

    /// At the end of a redo's step split by region, after every region: the store of the other
    /// covered cells.
    pub(in crate::lbm) fn submit_store_of_interior(&mut self) {
        let Some([_, interior]) = self.imb.as_mut().and_then(|c| c.store_by_region.take()) else {
            return;
        };
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        self.encode_store(&mut encoder, &interior, self.time % 2);
        self.gpu.queue.submit([encoder.finish()]);
    }
}
