//! The host's pass before the device's: the particles sized, checked against what the coupling
//! can take, and written as GPU records straight into the upload's staging memory, in parallel
//! chunks, with their centres wrapped into the lattice.

use super::chunks::{chunk_sizes, for_each_chunk, ChunkSize, CHUNK};
use super::cover::{box_edge, MAX_BOX_EDGE};
use super::records::{GpuParticle, SolidParticle, SolidParticles, MAX_PARTICLES, PARTICLE_BYTES};
use crate::lbm::gpu::{vec4, GpuLattice};

impl GpuLattice {
    /// The host's part before the device's: the particles sized, checked and written into staging
    /// memory (the buffers grown to hold them); their pairs.
    pub(super) fn stage_particles<P: SolidParticles + ?Sized>(
        &mut self,
        particles: &P,
    ) -> Result<u64, String> {
        let chunks = chunk_sizes(particles);
        self.refuse_unfit(particles, &chunks)?;
        let pairs: u64 = chunks.iter().map(|c| c.pairs).sum();
        self.reserve(particles.count() as u64, pairs)?;
        self.imb.as_mut().expect("coupling").staged = (particles.count() as u32, pairs);
        self.upload_particles(particles, &chunks)?;
        Ok(pairs)
    }

    /// Writes the particles' GPU records (centres wrapped into the lattice, pair ranges from
    /// `chunks`) straight into the upload's staging memory, chunk by chunk in parallel.
    fn upload_particles<P: SolidParticles + ?Sized>(
        &self,
        particles: &P,
        chunks: &[ChunkSize],
    ) -> Result<(), String> {
        let Some(bytes) = std::num::NonZeroU64::new(particles.count() as u64 * PARTICLE_BYTES) else {
            return Ok(());
        };
        let coupling = self.imb.as_ref().expect("coupling");
        let mut view = self
            .gpu
            .queue
            .write_buffer_with(&coupling.particles, 0, bytes)
            .ok_or("particle upload: no staging memory")?;
        // Records as bytes: the staging memory may only be written (wgpu's `WriteOnly`), and each
        // chunk's thread writes its own records.
        let (mut records, _) = view.slice(..).into_chunks::<{ PARTICLE_BYTES as usize }>();
        let staging = Staging(records.as_raw_element_ptr(), records.len());
        let periods = Periods::of(self.particles_lattice());
        for_each_chunk(chunks.iter().collect(), |c, chunk: &ChunkSize| {
            let mut first = chunk.first;
            for j in c * CHUNK..(c * CHUNK + CHUNK).min(particles.count()) {
                let p = periods.wrap(&particles.particle(j));
                let edge = box_edge(p.radius);
                staging.write(
                    j,
                    GpuParticle {
                        pos_r: vec4(p.position, p.radius),
                        vel: p.velocity.map(|v| v as f32),
                        first,
                        omega: p.angular_velocity.map(|w| w as f32),
                        edge,
                    },
                );
                first += edge * edge * edge;
            }
        });
        Ok(())
    }

    /// Refuses particles the coupling cannot take, naming the first: more than its indices hold,
    /// a radius beyond its box index, a box longer than a periodic axis. `chunks` holds the
    /// largest box edge of each chunk: the particles are looked at one by one only when one is
    /// refused.
    fn refuse_unfit<P: SolidParticles + ?Sized>(
        &self,
        particles: &P,
        chunks: &[ChunkSize],
    ) -> Result<(), String> {
        let n = particles.count();
        if n > MAX_PARTICLES {
            return Err(format!(
                "{n} particles exceed the coupling's {MAX_PARTICLES} (imb.wgsl's slot keys hold 24-bit indices)"
            ));
        }
        let largest = chunks.iter().map(|c| c.largest_edge).max().unwrap_or(0);
        let (whole, periodic) = self.particles_lattice();
        let shortest_periodic = (0..3)
            .filter(|&a| periodic[a])
            .map(|a| whole[a])
            .min()
            .unwrap_or(usize::MAX);
        if largest <= MAX_BOX_EDGE && largest as usize <= shortest_periodic {
            return Ok(());
        }
        let radius = |j: usize| particles.radius(j);
        if let Some(j) = (0..n).find(|&j| box_edge(radius(j)) > MAX_BOX_EDGE) {
            return Err(format!(
                "particle {j}: radius {} cells exceeds the coupling's {} cells",
                radius(j),
                (MAX_BOX_EDGE - 1) / 2
            ));
        }
        if let Some((j, axis)) = (0..n).find_map(|j| {
            (0..3)
                .find(|&a| periodic[a] && box_edge(radius(j)) as usize > whole[a])
                .map(|a| (j, a))
        }) {
            return Err(format!(
                "particle {j}: radius {} cells spans more than the periodic {} axis of {} cells \
                 (its box of {} cells would meet itself)",
                radius(j),
                ["x", "y", "z"][axis],
                whole[axis],
                box_edge(radius(j))
            ));
        }
        Ok(())
    }
}

/// The particle with its centre wrapped into the lattice along the periodic axes (a DEM with a
/// periodic domain may send centres beyond it): its box then lies less than one period outside.
#[cfg(test)]
pub(in crate::lbm) fn into_lattice(setup: &crate::lbm::geometry::Setup, p: &SolidParticle) -> SolidParticle {
    Periods::of((setup.n, std::array::from_fn(|a| setup.periodic(a)))).wrap(p)
}

/// The lengths of the lattice's periodic axes, 0 along the others: what wraps the centres, looked
/// up once per step rather than per particle.
#[derive(Debug, Clone, Copy)]
pub(super) struct Periods([f64; 3]);

impl Periods {
    /// The periods of a lattice of `n` cells, periodic along `periodic`.
    pub(super) fn of((n, periodic): ([usize; 3], [bool; 3])) -> Periods {
        Periods(std::array::from_fn(
            |a| if periodic[a] { n[a] as f64 } else { 0.0 },
        ))
    }

    /// `p` with its centre wrapped (`rem_euclid`, a libm `fmod`, only for a centre outside).
    pub(super) fn wrap(&self, p: &SolidParticle) -> SolidParticle {
        let position = std::array::from_fn(|a| {
            let (x, period) = (p.position[a], self.0[a]);
            if period > 0.0 && !(0.0..period).contains(&x) {
                x.rem_euclid(period)
            } else {
                x
            }
        });
        SolidParticle { position, ..*p }
    }
}

/// The particle records of an upload's staging memory (`len` of them), written record by record
/// from the threads of the chunks, never read.
struct Staging(std::ptr::NonNull<[u8; PARTICLE_BYTES as usize]>, usize);

// SAFETY: the threads write disjoint records (each its chunk's), while the view they point into
// outlives them (`upload_particles`).
unsafe impl Send for Staging {}
unsafe impl Sync for Staging {}

impl Staging {
    fn write(&self, j: usize, record: GpuParticle) {
        assert!(j < self.1, "particle record {j} beyond the upload's {}", self.1);
        // SAFETY: j is within the staging memory (asserted), which the caller's view keeps alive;
        // each record is written by one thread only; the pointee is bytes (alignment 1).
        unsafe { self.0.add(j).write(bytemuck::cast(record)) }
    }
}
