//! The coupling of one block of a lattice decomposed over ranks ([`ImbBlock`], `crate::parallel`):
//! the particles stay in the whole lattice's coordinates, and the block covers its own cells
//! alone (a sphere that spans a block face is covered on both sides, each side by its rank).

use crate::lbm::gpu::GpuLattice;

/// Where a lattice's block lies in the whole lattice.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ImbBlock {
    /// The whole lattice's cells along each axis, and its periodic axes.
    pub whole: [usize; 3],
    pub periodic: [bool; 3],
    /// The block's own cells, from `own_lo` to `own_hi` (excluded), in whole-lattice coordinates.
    pub own_lo: [usize; 3],
    pub own_hi: [usize; 3],
    /// The whole-lattice coordinates of the block lattice's cell (0, 0, 0): `own_lo`, one less
    /// along an axis with a ghost layer below (-1 where that layer wraps).
    pub base: [i64; 3],
    /// The block lattice's cells outside its shell, from `interior_lo` to `interior_hi`
    /// (excluded), in the block lattice's coordinates (`parallel::Halo::interior`): the redo's
    /// store of the shell's covered cells in a step split by region.
    pub interior_lo: [usize; 3],
    pub interior_hi: [usize; 3],
}

impl ImbBlock {
    /// The shaders' override constants of the block (imb.wgsl's BLOCK, WHOLE_*, OWN_*, BASE_*,
    /// INTERIOR_*); without one, BLOCK false and the lattice is the whole.
    pub fn constants(block: Option<ImbBlock>) -> Vec<(&'static str, f64)> {
        let Some(b) = block else {
            return vec![("BLOCK", 0.0)];
        };
        let cells = |v: [usize; 3]| v.map(|v| v as f64);
        let vectors = [
            (["WHOLE_X", "WHOLE_Y", "WHOLE_Z"], cells(b.whole)),
            (["OWN_LO_X", "OWN_LO_Y", "OWN_LO_Z"], cells(b.own_lo)),
            (["OWN_HI_X", "OWN_HI_Y", "OWN_HI_Z"], cells(b.own_hi)),
            (["BASE_X", "BASE_Y", "BASE_Z"], b.base.map(|v| v as f64)),
            (
                ["INTERIOR_LO_X", "INTERIOR_LO_Y", "INTERIOR_LO_Z"],
                cells(b.interior_lo),
            ),
            (
                ["INTERIOR_HI_X", "INTERIOR_HI_Y", "INTERIOR_HI_Z"],
                cells(b.interior_hi),
            ),
        ];
        let periodic = (0..3).map(|a| u32::from(b.periodic[a]) << a).sum::<u32>();
        let mut c = vec![("BLOCK", 1.0), ("WHOLE_PERIODIC", f64::from(periodic))];
        for (names, v) in vectors {
            c.extend(names.into_iter().zip(v));
        }
        c
    }

    /// The cells of a block along axis `a` (every block of the lattice has as many).
    fn size(&self, a: usize) -> usize {
        self.own_hi[a] - self.own_lo[a]
    }

    /// This block's position among the blocks along each axis.
    pub(super) fn coords(&self) -> [usize; 3] {
        std::array::from_fn(|a| self.own_lo[a] / self.size(a))
    }

    /// The blocks along each axis.
    fn blocks(&self) -> [usize; 3] {
        std::array::from_fn(|a| self.whole[a] / self.size(a))
    }

    /// The rank of the block at `coords` among the blocks (x fastest, as
    /// `parallel::Decomposition` numbers them).
    pub(super) fn rank_at(&self, coords: [usize; 3]) -> usize {
        let blocks = self.blocks();
        coords[0] + blocks[0] * (coords[1] + blocks[1] * coords[2])
    }

    /// The position among the blocks of rank `rank`'s block.
    pub(super) fn coords_of(&self, rank: usize) -> [usize; 3] {
        let blocks = self.blocks();
        [
            rank % blocks[0],
            (rank / blocks[0]) % blocks[1],
            rank / (blocks[0] * blocks[1]),
        ]
    }

    /// The position along axis `a` of the block that holds whole-lattice coordinate `q` (as
    /// imb.wgsl's `lattice_cell` finds the cell: wrapped along a periodic axis); none outside the
    /// lattice along a closed axis.
    pub(super) fn block_along(&self, a: usize, q: i64) -> Option<usize> {
        let n = self.whole[a] as i64;
        let g = match self.periodic[a] {
            true => q.rem_euclid(n),
            false if (0..n).contains(&q) => q,
            false => return None,
        };
        Some(g as usize / self.size(a))
    }
}

impl GpuLattice {
    /// The lattice the particles' coordinates refer to: its cells along each axis and its
    /// periodic axes (the whole lattice's where this lattice is a block of it).
    pub(super) fn particles_lattice(&self) -> ([usize; 3], [bool; 3]) {
        match self.options.and_then(|o| o.block) {
            Some(b) => (b.whole, b.periodic),
            None => (self.setup.n, std::array::from_fn(|a| self.setup.periodic(a))),
        }
    }
}
