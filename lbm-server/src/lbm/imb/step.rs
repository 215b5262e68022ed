//! The coupled step ([`GpuLattice::step_coupled`]): the particles cover the cells, the fluid
//! collides with the solid term and streams, and each particle's force and torque come back. Its
//! passes in order are listed at `coupled_step`.

use super::loads::convert_loads;
use super::passes::{CoveredPasses, StepPasses};
use super::records::{GpuLoad, Load, SolidParticle, SolidParticles, LOAD_BYTES, PAIR_BYTES, REDUCE_SLICES};
use crate::lbm::gpu::GpuLattice;

/// Receives the encoder after each pass of a coupled step (named) and returns the one to go on
/// with: the identity, a submit and wait for timing each pass, or a timestamp.
pub(super) type Split<'a> = &'a mut dyn FnMut(&'static str, wgpu::CommandEncoder) -> wgpu::CommandEncoder;

impl GpuLattice {
    /// One coupled step: the particles cover the cells, the fluid streams and collides with the
    /// solid term, and the force and torque on each particle over the step come back.
    pub fn step_coupled(&mut self, particles: &[SolidParticle]) -> Result<Vec<Load>, String> {
        let mut loads = Vec::new();
        self.step_coupled_with(particles, &mut loads, |_, load| load)?;
        Ok(loads)
    }

    /// A coupled step that reads the particles where they are and writes `load(j, load of j)` for
    /// each particle j to `out` (replaced): the caller's unit conversions ride on the step's own
    /// passes over the particles, which run in parallel chunks.
    pub fn step_coupled_with<P: SolidParticles + ?Sized, T: Send>(
        &mut self,
        particles: &P,
        out: &mut Vec<T>,
        load: impl Fn(usize, Load) -> T + Sync,
    ) -> Result<(), String> {
        self.coupled_step(particles, &mut |_, encoder| encoder, &mut |loads| {
            convert_loads(loads, out, &load)
        })
    }

    /// The coupled step, pass by pass; `split` receives the encoder after each device pass (named)
    /// and returns the one to go on with, `read` receives the loads:
    /// 1. `stage`: the faces' ramp, and the host's pass over the particles: sized, checked and
    ///    written for the device, with the step's counts;
    /// 2. `encode_cover`: each particle's solid fraction over its box (what eq. 7's B weighs),
    ///    its cells' slots, and the cover mask or the list of covered cells;
    /// 3. `encode_collision`: the collision with the solid term (eq. 7-9), in the fluid kernels
    ///    (fused) or over the covered cells before them (the redo and skip);
    /// 4. `encode_reduce`: each particle's force and torque (eq. 10-11), the covers cleared;
    /// 5. `submit_with_loads`: the loads copied for the host, and the passes so far submitted;
    /// 6. `submit_fluid_after_loads`: with the redo and skip, the fluid kernels and the redo's store
    ///    over the covered cells (skip: the cover mask cleared), which run while the host reads the
    ///    loads;
    /// 7. `read_loads`: the loads, once on the host, handed to `read`.
    pub(super) fn coupled_step<P: SolidParticles + ?Sized>(
        &mut self,
        particles: &P,
        split: Split,
        read: &mut dyn FnMut(&[GpuLoad]) -> Result<(), String>,
    ) -> Result<(), String> {
        let (n, passes) = self.stage(particles)?;
        let encoder = split(
            "upload",
            self.gpu.device.create_command_encoder(&Default::default()),
        );
        let encoder = self.encode_cover(encoder, &passes.cover, n, split);
        let encoder = self.encode_collision(encoder, &passes, split);
        let encoder = self.encode_reduce(encoder, &passes, n, split);
        let (bytes, with_loads) = self.submit_with_loads(encoder, n);
        self.submit_fluid_after_loads(&passes, split);
        self.read_loads(bytes, with_loads, read)
    }

    /// Before the device's passes: the faces' share of velocity (during the ramp), the particles
    /// staged, and this step's pipelines and counts (particles, pairs, room in the list of
    /// covered cells) for the kernels; the count of particles and the pipelines.
    pub(super) fn stage<P: SolidParticles + ?Sized>(
        &mut self,
        particles: &P,
    ) -> Result<(u32, StepPasses), String> {
        self.ramp_faces();
        let pairs = self.stage_particles(particles)?;
        let passes = self.step_passes()?;
        let n = particles.count() as u32;
        let coupling = self.imb.as_ref().expect("coupling");
        let info = [n, pairs as u32, 0, coupling.saved_capacity];
        self.gpu
            .queue
            .write_buffer(&coupling.info, 0, bytemuck::cast_slice(&info));
        Ok((n, passes))
    }

    /// The solid fractions: `cover` over the `n` particles' boxes. The slots and the cover mask
    /// are all 0 here (`reduce` clears them); with the redo and skip the covered cells are
    /// listed by `cover` (status[4], status[8]) and dispatched indirectly (status[5..8],
    /// status[9..12]).
    pub(super) fn encode_cover(
        &self,
        mut encoder: wgpu::CommandEncoder,
        cover: &wgpu::ComputePipeline,
        n: u32,
        split: Split,
    ) -> wgpu::CommandEncoder {
        encoder.clear_buffer(&self.status, 16, Some(32));
        let coupling = self.imb.as_ref().expect("coupling");
        let pairs = coupling.staged.1 * PAIR_BYTES;
        if pairs > 0 {
            encoder.clear_buffer(&coupling.pairs, 0, Some(pairs));
        }
        self.dispatch_groups(&mut encoder, cover, self.time % 2, n);
        split("cover", encoder)
    }

    /// The collision with the solid term (eq. 7-9): fused, the fluid kernels give the covered
    /// cells theirs (shaders/lbm.wgsl); with the redo and skip, the covered cells collide first.
    pub(super) fn encode_collision(
        &mut self,
        mut encoder: wgpu::CommandEncoder,
        passes: &StepPasses,
        split: Split,
    ) -> wgpu::CommandEncoder {
        match &passes.covered {
            None => {
                self.encode_step(&mut encoder);
                split("fluid", encoder)
            }
            Some(covered) => self.encode_covered_collision(encoder, covered, split),
        }
    }

    /// The redo and skip: the covered cells collide with the solid term first, from their
    /// pre-collision populations, and keep the result (shaders/imb_covered.wgsl).
    pub(super) fn encode_covered_collision(
        &self,
        mut encoder: wgpu::CommandEncoder,
        covered: &CoveredPasses,
        split: Split,
    ) -> wgpu::CommandEncoder {
        let parity = self.time % 2;
        self.dispatch_groups(&mut encoder, &covered.groups, parity, 1);
        let indirect = &self.imb.as_ref().expect("coupling").indirect;
        encoder.copy_buffer_to_buffer(&self.status, 20, indirect, 0, 28);
        encoder = split("covered_groups", encoder);
        for (offset, pipeline) in [0, 16].into_iter().zip(&covered.collide) {
            self.dispatch_indirect(&mut encoder, pipeline, parity, offset);
        }
        split("collide_covered", encoder)
    }

    /// Force and torque per particle (eq. 10-11): each particle's slices of its box summed, then
    /// the slices into the particle's load; the covers cleared for the next step.
    pub(super) fn encode_reduce(
        &self,
        mut encoder: wgpu::CommandEncoder,
        passes: &StepPasses,
        n: u32,
        split: Split,
    ) -> wgpu::CommandEncoder {
        let parity = self.time % 2;
        self.dispatch_groups(
            &mut encoder,
            &passes.reduce,
            parity,
            (n * REDUCE_SLICES).div_ceil(64),
        );
        self.dispatch_groups(&mut encoder, &passes.sum_loads, parity, n.div_ceil(64));
        split("reduce", encoder)
    }

    /// With the redo and skip (else nothing) the fluid kernels, which update every cell as without
    /// particles (skip: all but the listed ones), and the redo's store over the covered cells (skip:
    /// the cover mask cleared) go in a submission of their own: it runs while the host reads the
    /// loads back and the DEM takes its step (docs/imb.md, "The redo").
    pub(super) fn submit_fluid_after_loads(&mut self, passes: &StepPasses, split: Split) {
        let Some(covered) = &passes.covered else {
            return;
        };
        let parity = self.time % 2;
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        self.encode_step(&mut encoder);
        encoder = split("fluid", encoder);
        match &covered.store {
            Some(store) => {
                for (offset, pipeline) in [0, 16].into_iter().zip(store) {
                    self.dispatch_indirect(&mut encoder, pipeline, parity, offset);
                }
                encoder = split("store_covered", encoder);
            }
            None => {
                self.clear_cover_mask(&mut encoder);
                encoder = split("uncover", encoder);
            }
        }
        self.gpu.queue.submit([encoder.finish()]);
    }

    /// Skip, after the fluid kernels: every bit of the cover mask back to zero (a bit set is a
    /// covered cell's of this step: a buffer clear of one bit per cell, where a pass over the
    /// covered cells took an atomic per cell).
    pub(super) fn clear_cover_mask(&self, encoder: &mut wgpu::CommandEncoder) {
        let cells = self.setup.cells() as u64;
        let covered = &self.imb.as_ref().expect("coupling").covered;
        encoder.clear_buffer(covered, 0, Some(cells.div_ceil(32) * 4));
    }

    /// The `n` particles' loads copied where the host reads them, at the end of the passes so
    /// far, which go to the device: the loads' bytes and that submission.
    pub(super) fn submit_with_loads(
        &self,
        mut encoder: wgpu::CommandEncoder,
        n: u32,
    ) -> (u64, wgpu::SubmissionIndex) {
        let bytes = n as u64 * LOAD_BYTES;
        let coupling = self.imb.as_ref().expect("coupling");
        if bytes > 0 {
            encoder.copy_buffer_to_buffer(&coupling.loads, 0, &coupling.readback, 0, bytes);
        }
        (bytes, self.gpu.queue.submit([encoder.finish()]))
    }

    /// Dispatches as many workgroups as `covered_groups` wrote to status[5..8] (offset 0) or
    /// status[9..12] (offset 16).
    fn dispatch_indirect(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        pipeline: &wgpu::ComputePipeline,
        parity: u64,
        offset: u64,
    ) {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &self.way().bind_groups[parity as usize], &[]);
        pass.dispatch_workgroups_indirect(&self.imb.as_ref().expect("coupling").indirect, offset);
    }
}
