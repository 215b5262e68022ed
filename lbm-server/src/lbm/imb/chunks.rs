//! The host's passes over a step's particles in chunks, run in parallel: the chunks sized from
//! the radii (their pairs and largest box), and a pass over each.

use super::cover::box_edge;
use super::records::SolidParticles;

/// Particles per chunk of the host's passes over a step's particles: the chunks run in parallel
/// (rayon); a step with fewer particles stays on the calling thread.
pub(in crate::lbm) const CHUNK: usize = 2048;

/// A chunk of [`CHUNK`] particles: the pair index of its first particle, its pairs (the cells of
/// its particles' bounding boxes) and its largest box edge.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct ChunkSize {
    pub(super) first: u32,
    pub(super) pairs: u64,
    pub(super) largest_edge: u32,
}

/// The chunks of a step's particles, sized from the radii (in parallel), with their first pairs.
pub(super) fn chunk_sizes<P: SolidParticles + ?Sized>(particles: &P) -> Vec<ChunkSize> {
    let n = particles.count();
    let mut chunks = vec![ChunkSize::default(); n.div_ceil(CHUNK)];
    for_each_chunk(chunks.iter_mut().collect(), |c, chunk: &mut ChunkSize| {
        for j in c * CHUNK..(c * CHUNK + CHUNK).min(n) {
            let edge = box_edge(particles.radius(j));
            chunk.pairs += (edge as u64).pow(3);
            chunk.largest_edge = chunk.largest_edge.max(edge);
        }
    });
    let mut first = 0u64;
    for chunk in &mut chunks {
        // Past u32 only when the pairs exceed any binding (`reserve` refuses them).
        chunk.first = first.min(u32::MAX as u64) as u32;
        first += chunk.pairs;
    }
    chunks
}

/// `fill(c, chunk c)` for each chunk: in parallel when there is more than one, else on this
/// thread.
pub(super) fn for_each_chunk<S: Send>(chunks: Vec<S>, fill: impl Fn(usize, S) + Sync) {
    use rayon::prelude::*;
    if chunks.len() <= 1 {
        chunks.into_iter().enumerate().for_each(|(c, s)| fill(c, s));
    } else {
        chunks.into_par_iter().enumerate().for_each(|(c, s)| fill(c, s));
    }
}
