//! Where each particle's bounding box lies among the blocks of a lattice decomposed over ranks
//! ([`StepBoxes`]): within one rank's own cells (that rank reduces the particle's load itself, in
//! the single process's order), or across a cut (the pairs of its cells gathered at rank 0).

use super::block::ImbBlock;
use super::cover::box_edge;
use super::records::SolidParticles;
use super::staging::Periods;

/// The ranks that hold the cells of a particle's box (those inside the lattice).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BoxRanks {
    /// One rank holds every one (rank 0 where none lies inside the lattice).
    One(usize),
    /// Several ranks hold some: the box crosses a cut.
    Several,
}

/// A particle's bounding box as `cover` (imb.wgsl) and `reduce` (imb_loads.wgsl) walk it: its first cell (whole
/// lattice coordinates), its edge, its first pair, and the ranks that hold its cells.
#[derive(Debug, Clone, Copy)]
pub(super) struct ParticleBox {
    origin: [i64; 3],
    edge: u32,
    first: u64,
    pub(super) ranks: BoxRanks,
}

/// The boxes of a step's particles among the blocks (particle order), and the block they were
/// found from.
pub struct StepBoxes {
    pub(super) boxes: Vec<ParticleBox>,
    pub(super) block: ImbBlock,
}

impl StepBoxes {
    /// The boxes of `particles` (the coordinates of the whole lattice of `block`), with their
    /// centres wrapped as the step stages them (`upload_particles`).
    pub fn of<P: SolidParticles + ?Sized>(particles: &P, block: ImbBlock) -> StepBoxes {
        let periods = Periods::of((block.whole, block.periodic));
        let mut first = 0u64;
        let boxes = (0..particles.count())
            .map(|j| {
                let p = periods.wrap(&particles.particle(j));
                let edge = box_edge(p.radius);
                // imb.wgsl's `box_origin`: floor(x - r) in f32, of the f32 centre and radius.
                let origin = p.position.map(|x| (x as f32 - p.radius as f32).floor() as i64);
                let mut b = ParticleBox {
                    origin,
                    edge,
                    first,
                    ranks: BoxRanks::Several,
                };
                b.ranks = b.ranks_of(&block);
                first += (edge as u64).pow(3);
                b
            })
            .collect();
        StepBoxes { boxes, block }
    }

    /// Each particle's ranks (particle order).
    pub fn ranks(&self) -> impl Iterator<Item = BoxRanks> + '_ {
        self.boxes.iter().map(|b| b.ranks)
    }

    /// Whether some particle's box crosses a cut.
    pub(super) fn any_several(&self) -> bool {
        self.ranks().any(|r| r == BoxRanks::Several)
    }

    /// The boxes that cross a cut.
    pub(super) fn several(&self) -> impl Iterator<Item = &ParticleBox> + '_ {
        self.boxes.iter().filter(|b| b.ranks == BoxRanks::Several)
    }

    /// The pairs up to the last of a box that crosses a cut (0 where none does).
    pub(super) fn pairs_to_last_several(&self) -> u64 {
        self.several()
            .last()
            .map_or(0, |b| b.first + (b.edge as u64).pow(3))
    }

    /// The rank of this block.
    pub(super) fn rank(&self) -> usize {
        self.block.rank_at(self.block.coords())
    }
}

impl ParticleBox {
    /// The ranks that hold the box's cells: one where along every axis its cells inside the
    /// lattice lie in one block (the blocks are a grid), else several.
    fn ranks_of(&self, block: &ImbBlock) -> BoxRanks {
        let mut coords = [0; 3];
        for (a, c) in coords.iter_mut().enumerate() {
            let mut along = self.offsets(a).filter_map(|(_, q)| block.block_along(a, q));
            let Some(first) = along.next() else {
                return BoxRanks::One(0);
            };
            if along.any(|b| b != first) {
                return BoxRanks::Several;
            }
            *c = first;
        }
        BoxRanks::One(block.rank_at(coords))
    }

    /// The box's offsets along axis `a` and their whole-lattice coordinates.
    fn offsets(&self, a: usize) -> impl Iterator<Item = (u64, i64)> {
        let origin = self.origin[a];
        (0..self.edge as u64).map(move |u| (u, origin + u as i64))
    }

    /// The pairs (indices into the step's pairs) of the box's cells that the block at `coords`
    /// holds, in the box's order (x fastest), added to `into`.
    pub(super) fn pairs_in(&self, block: &ImbBlock, coords: [usize; 3], into: &mut Vec<u64>) {
        let along = |a: usize| -> Vec<u64> {
            self.offsets(a)
                .filter(|&(_, q)| block.block_along(a, q) == Some(coords[a]))
                .map(|(u, _)| u)
                .collect()
        };
        let (xs, ys, zs) = (along(0), along(1), along(2));
        let m = self.edge as u64;
        for z in &zs {
            for y in &ys {
                into.extend(xs.iter().map(|x| self.first + x + m * (y + m * z)));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lbm::imb::SolidParticle;

    /// Rank 0's block of a lattice of 8 x 6 x 8 cells, periodic along x, cut into [2, 1, 2].
    fn block() -> ImbBlock {
        ImbBlock {
            whole: [8, 6, 8],
            periodic: [true, false, false],
            own_lo: [0, 0, 0],
            own_hi: [4, 6, 4],
            base: [-1, 0, 0],
            interior_lo: [2, 0, 0],
            interior_hi: [4, 6, 3],
        }
    }

    fn boxes_of(spheres: &[([f64; 3], f64)]) -> StepBoxes {
        let particles: Vec<SolidParticle> = spheres
            .iter()
            .map(|&(position, radius)| SolidParticle {
                position,
                radius,
                ..Default::default()
            })
            .collect();
        StepBoxes::of(&particles[..], block())
    }

    #[test]
    fn a_box_lies_in_one_block_where_its_cells_in_the_lattice_do() {
        let boxes = boxes_of(&[
            // Cells 4..8 along x and z: rank 3's block.
            ([6.0, 3.0, 6.0], 1.2),
            // Beyond the closed y and z faces, within rank 1's block inside.
            ([6.0, 0.1, 0.1], 1.2),
            // Across the x cut; across the periodic x faces (cells 6, 7, 0, 1).
            ([4.0, 3.0, 2.0], 1.2),
            ([0.0, 3.0, 2.0], 1.2),
            // A centre beyond the periodic face, wrapped: cells 4 to 7 along x, rank 1's.
            ([-2.0, 3.0, 2.0], 1.2),
            // Wholly outside the closed z faces: no rank holds a cell.
            ([2.0, 3.0, -3.0], 1.2),
        ]);
        use BoxRanks::{One, Several};
        let ranks: Vec<BoxRanks> = boxes.ranks().collect();
        assert_eq!(ranks, [One(3), One(1), Several, Several, One(1), One(0)]);
        assert_eq!(boxes.rank(), 0);
        assert_eq!(boxes.pairs_to_last_several(), 4 * 64);
    }

    /// The cells each rank holds of a box across the cuts: every cell of the box inside the
    /// lattice once, none outside.
    #[test]
    fn the_ranks_hold_each_cell_of_a_box_across_the_cuts_once() {
        let boxes = boxes_of(&[([1.0, 0.5, 3.5], 2.2)]);
        let b = &boxes.boxes[0];
        assert_eq!(b.ranks, BoxRanks::Several);
        let m = b.edge as u64;
        let mut held = vec![0; m.pow(3) as usize];
        for rank in 0..4 {
            let mut cells = Vec::new();
            b.pairs_in(&boxes.block, boxes.block.coords_of(rank), &mut cells);
            for t in cells {
                held[t as usize] += 1;
            }
        }
        for (t, &h) in held.iter().enumerate() {
            let t = t as u64;
            let q = [t % m, (t / m) % m, t / (m * m)].map(|u| u as i64);
            let inside = (0..3).all(|a| boxes.block.block_along(a, b.origin[a] + q[a]).is_some());
            assert_eq!(h, usize::from(inside), "box cell {q:?}");
        }
    }
}
