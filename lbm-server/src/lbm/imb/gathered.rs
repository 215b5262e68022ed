//! The coupled step of one block of a lattice decomposed over ranks (`crate::parallel`): the
//! step's passes as on one process, the loads left unread ([`GpuLattice::step_coupled_unread`]);
//! the block's pairs read back ([`GpuLattice::step_pairs`]); and at rank 0 the loads reduced from
//! every rank's pairs gathered ([`GpuLattice::reduce_gathered`]).
//!
//! Each cell of a particle's box belongs to one block, and the other blocks hold a zero pair
//! there (w = 0: not covered), so the gathered pairs are the single process's, pair for pair.
//! `reduce` and `sum_loads` then sum them in the single process's order: the loads are its own,
//! bit for bit (partial loads per rank, added afterwards, would not be).

use super::loads::convert_loads;
use super::records::{Load, SolidParticles, PAIR_BYTES};
use super::step::Split;
use crate::lbm::gpu::GpuLattice;

impl GpuLattice {
    /// The coupled step's passes with the particles (whole-lattice coordinates), all submitted:
    /// the block's covers, its covered cells' collision, the reduce (the covers cleared) and the
    /// fluid kernels; the loads are not read (rank 0 makes them from every rank's pairs).
    pub fn step_coupled_unread<P: SolidParticles + ?Sized>(&mut self, particles: &P) -> Result<(), String> {
        let split: Split = &mut |_, encoder| encoder;
        let (n, passes) = self.stage(particles)?;
        let encoder = self.gpu.device.create_command_encoder(&Default::default());
        let encoder = self.encode_cover(encoder, &passes.cover, n, split);
        let encoder = self.encode_collision(encoder, &passes, split);
        let encoder = self.encode_reduce(encoder, &passes, n, split);
        self.gpu.queue.submit([encoder.finish()]);
        self.submit_fluid_after_loads(&passes, split);
        Ok(())
    }

    /// The pairs of the step staged last (16 bytes per cell of each particle's box, in the
    /// particles' order), read back once the step is done.
    pub fn step_pairs(&self) -> Vec<u8> {
        let coupling = self.imb.as_ref().expect("coupling");
        let bytes = coupling.staged.1 * PAIR_BYTES;
        if bytes == 0 {
            return Vec::new();
        }
        self.gpu.read_buffer(&coupling.pairs, bytes)
    }

    /// At rank 0, after the step: `load(j, load of j)` for each particle j of the step in `out`
    /// (replaced), reduced from `pairs` (every block's, gathered by [`merge_pairs`]) by `reduce`
    /// and `sum_loads` as on one process.
    pub fn reduce_gathered<T: Send>(
        &mut self,
        pairs: &[u8],
        out: &mut Vec<T>,
        load: impl Fn(usize, Load) -> T + Sync,
    ) -> Result<(), String> {
        let coupling = self.imb.as_ref().expect("coupling");
        let n = coupling.staged.0;
        if !pairs.is_empty() {
            self.gpu.queue.write_buffer(&coupling.pairs, 0, pairs);
        }
        let passes = self.step_passes()?;
        let encoder = self.gpu.device.create_command_encoder(&Default::default());
        let encoder = self.encode_reduce(encoder, &passes, n, &mut |_, encoder| encoder);
        let (bytes, with_loads) = self.submit_with_loads(encoder, n);
        self.read_loads(bytes, with_loads, &mut |loads| convert_loads(loads, out, &load))
    }
}

/// Every block's pairs of a step (`pieces`, rank order, each [`GpuLattice::step_pairs`]) as one:
/// each pair from the block that covers its cell (w not 0), else the zero pair all hold.
pub fn merge_pairs(pieces: &[Vec<u8>]) -> Vec<u8> {
    let Some((first, others)) = pieces.split_first() else {
        return Vec::new();
    };
    let mut merged = first.clone();
    let pair = PAIR_BYTES as usize;
    for piece in others {
        assert_eq!(piece.len(), merged.len(), "every rank stages the same particles");
        for (m, p) in merged.chunks_exact_mut(pair).zip(piece.chunks_exact(pair)) {
            let w = f32::from_le_bytes(p[pair - 4..].try_into().expect("4 bytes"));
            if w != 0.0 {
                m.copy_from_slice(p);
            }
        }
    }
    merged
}
