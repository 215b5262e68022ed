//! The coupled step timed pass by pass (`lbm-server bench --passes`): each pass submitted and
//! waited for on its own, the device's timestamps between passes, and the host's own passes.

use super::loads::convert_loads;
use super::records::{GpuLoad, Load, SolidParticle};
use crate::lbm::gpu::GpuLattice;

/// The device's timestamps between the passes of a coupled step ([`GpuLattice::pass_clock`]).
pub struct PassClock {
    set: wgpu::QuerySet,
    resolved: wgpu::Buffer,
}

/// Timestamps a coupled step can write (it writes at most 8).
const PASS_STAMPS: u32 = 16;

impl GpuLattice {
    /// A coupled step with each pass submitted and waited for on its own: what `clock` advanced
    /// by over each pass (the submit round trip included), in the order of the step
    /// (`lbm-server bench --passes`). "upload" is the host's pass that writes the particles for
    /// the GPU, "readback" the wait for the loads and the pass that converts them.
    pub fn step_coupled_timed<const N: usize>(
        &mut self,
        particles: &[SolidParticle],
        clock: &dyn Fn() -> [f64; N],
    ) -> Result<Vec<(&'static str, [f64; N])>, String> {
        let gpu = self.gpu.clone();
        let mut times = Vec::new();
        let mut mark = clock();
        let elapsed = |mark: &mut [f64; N]| {
            let now = clock();
            let spent = std::array::from_fn(|i| now[i] - mark[i]);
            *mark = now;
            spent
        };
        let mut split = |pass: &'static str, encoder: wgpu::CommandEncoder| {
            gpu.queue.submit([encoder.finish()]);
            gpu.wait();
            times.push((pass, elapsed(&mut mark)));
            gpu.device.create_command_encoder(&Default::default())
        };
        let mut loads = Vec::new();
        self.coupled_step(particles, &mut split, &mut |l| {
            convert_loads(l, &mut loads, &|_, l| l)
        })?;
        times.push(("readback", elapsed(&mut mark)));
        Ok(times)
    }

    /// Timestamps for [`GpuLattice::step_coupled_clocked`], where the device writes them inside
    /// command encoders (None elsewhere).
    pub fn pass_clock(&self) -> Option<PassClock> {
        let need = wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS;
        if !self.gpu.device.features().contains(need) {
            return None;
        }
        let d = &self.gpu.device;
        Some(PassClock {
            set: d.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass clock"),
                ty: wgpu::QueryType::Timestamp,
                count: PASS_STAMPS,
            }),
            resolved: d.create_buffer(&wgpu::BufferDescriptor {
                label: Some("pass clock"),
                size: PASS_STAMPS as u64 * 8,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
        })
    }

    /// A coupled step as a run makes it (not split into submissions), with a timestamp after
    /// each pass: the milliseconds of each pass by the device's clock, in the order of the step
    /// (the host's "upload" only marks the start; with the redo "fluid" includes the loads' copy).
    pub fn step_coupled_clocked(
        &mut self,
        particles: &[SolidParticle],
        clock: &PassClock,
    ) -> Result<Vec<(&'static str, f64)>, String> {
        let mut names = Vec::new();
        let mut stamp = |name: &'static str, mut encoder: wgpu::CommandEncoder| {
            encoder.write_timestamp(&clock.set, names.len() as u32);
            names.push(name);
            encoder
        };
        let mut loads = Vec::new();
        self.coupled_step(particles, &mut stamp, &mut |l| {
            convert_loads(l, &mut loads, &|_, l| l)
        })?;
        let count = names.len() as u32;
        let gpu = self.gpu.clone();
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        encoder.resolve_query_set(&clock.set, 0..count, &clock.resolved, 0);
        gpu.queue.submit([encoder.finish()]);
        let ticks: Vec<u64> =
            bytemuck::cast_slice(&gpu.read_range(&clock.resolved, 0, count as u64 * 8)).to_vec();
        let ms_per_tick = gpu.queue.get_timestamp_period() as f64 * 1e-6;
        Ok((1..names.len())
            .map(|k| (names[k], ticks[k].wrapping_sub(ticks[k - 1]) as f64 * ms_per_tick))
            .collect())
    }

    /// The host's own passes of a coupled step over `particles`, timed without the device:
    /// milliseconds (median of `repeats`) to size, check and write the records into staging
    /// memory, and to convert as many loads (`lbm-server bench --passes`: on a GPU machine they
    /// run on its CPU, in series with every step).
    pub fn host_pass_times(
        &mut self,
        particles: &[SolidParticle],
        repeats: usize,
    ) -> Result<[f64; 2], String> {
        let zeros = vec![GpuLoad::default(); particles.len()];
        let mut loads: Vec<Load> = Vec::new();
        let mut times = Vec::new();
        for _ in 0..repeats.max(1) {
            let start = std::time::Instant::now();
            self.stage_particles(particles)?;
            let upload = start.elapsed().as_secs_f64();
            let start = std::time::Instant::now();
            convert_loads(&zeros, &mut loads, &|_, l| l)?;
            times.push([upload, start.elapsed().as_secs_f64()]);
            // The staged records go to the device (the same as the next step's).
            self.gpu.queue.submit([]);
            self.gpu.wait();
        }
        Ok(std::array::from_fn(|k| {
            let mut column: Vec<f64> = times.iter().map(|t| t[k]).collect();
            column.sort_by(f64::total_cmp);
            column[column.len() / 2] * 1e3
        }))
    }
}
