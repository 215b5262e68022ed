//! What a rank other than 0 sends rank 0 of a coupled step ([`share_of`], read by [`Share`]):
//! 1. the loads of the particles whose box lies in its own cells alone, which it reduced itself
//!    (`reduce`, `sum_loads`: the single process's order over the same pairs), 6 f32 each, in
//!    the particles' order;
//! 2. of the particles whose box crosses a cut, the pairs of the box's cells it holds: a bit per
//!    cell (covered: the pair's w is not 0), then each covered cell's momentum (3 f32): an
//!    uncovered cell's pair is the zero pair rank 0 holds there already, and `reduce` reads w
//!    only as covered or not.

use super::box_ranks::{BoxRanks, StepBoxes};
use super::records::{GpuLoad, LOAD_BYTES};

/// Bytes of a covered cell's momentum as sent.
const MOMENTUM_BYTES: usize = 12;

/// The share of `rank` (not 0): from its `loads` (every particle's, or none where it holds no
/// box alone) and its `pairs` (to the last box across a cut, or none where no box crosses one), as
/// little-endian bytes.
pub(super) fn share_of(boxes: &StepBoxes, rank: usize, loads: &[GpuLoad], pairs: &[[f32; 4]]) -> Vec<u8> {
    let mut share = Vec::new();
    for (j, ranks) in boxes.ranks().enumerate() {
        if ranks == BoxRanks::One(rank) {
            share.extend(loads[j].iter().flat_map(|v| v.to_le_bytes()));
        }
    }
    let cells = cells_across_cuts(boxes, rank);
    let mut bits = vec![0u8; cells.len().div_ceil(8)];
    let mut momenta = Vec::new();
    for (i, &c) in cells.iter().enumerate() {
        let pair = pairs[c as usize];
        if pair[3] != 0.0 {
            bits[i / 8] |= 1 << (i % 8);
            momenta.extend(pair[..3].iter().flat_map(|v| v.to_le_bytes()));
        }
    }
    share.extend(bits);
    share.extend(momenta);
    share
}

/// A rank's share as rank 0 reads it.
pub(super) struct Share<'a> {
    pub(super) bytes: &'a [u8],
    pub(super) rank: usize,
}

impl Share<'_> {
    /// The loads it sent placed in `loads` (every particle's).
    pub(super) fn place_loads(&self, boxes: &StepBoxes, loads: &mut [GpuLoad]) {
        let mut at = 0;
        for (j, ranks) in boxes.ranks().enumerate() {
            if ranks == BoxRanks::One(self.rank) {
                loads[j] = std::array::from_fn(|k| f32_at(self.bytes, at + 4 * k));
                at += LOAD_BYTES as usize;
            }
        }
    }

    /// The covered cells' pairs it sent placed in `pairs` (rank 0's, to the last box across a
    /// cut).
    pub(super) fn place_pairs(&self, boxes: &StepBoxes, pairs: &mut [[f32; 4]]) {
        let alone = boxes.ranks().filter(|&r| r == BoxRanks::One(self.rank)).count();
        let from = alone * LOAD_BYTES as usize;
        let cells = cells_across_cuts(boxes, self.rank);
        let mut at = from + cells.len().div_ceil(8);
        for (i, &c) in cells.iter().enumerate() {
            if self.bytes[from + i / 8] & (1 << (i % 8)) != 0 {
                let v = |k: usize| f32_at(self.bytes, at + 4 * k);
                pairs[c as usize] = [v(0), v(1), v(2), 1.0];
                at += MOMENTUM_BYTES;
            }
        }
        assert_eq!(at, self.bytes.len(), "rank {}'s share read whole", self.rank);
    }
}

/// The pairs (indices into the step's) of the cells that `rank` holds of the boxes across a cut,
/// box by box in the particles' order.
fn cells_across_cuts(boxes: &StepBoxes, rank: usize) -> Vec<u64> {
    let coords = boxes.block.coords_of(rank);
    let mut cells = Vec::new();
    for b in boxes.several() {
        b.pairs_in(&boxes.block, coords, &mut cells);
    }
    cells
}

/// The little-endian f32 at byte `at`.
fn f32_at(bytes: &[u8], at: usize) -> f32 {
    f32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"))
}
