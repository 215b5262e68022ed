//! How the lattice is cut into blocks, one per rank: the blocks along each axis, chosen for the
//! fewest halo cells or given by the scene (`[parallel] blocks`), and one rank's block with its
//! ghost layers as a lattice of its own.

use crate::lbm::geometry::{Face, Setup};

/// The thinnest block along an axis that is cut: one layer of cells against each neighbour's
/// ghost layer, so that the two faces' exchanges touch different cells.
pub const MIN_BLOCK_CELLS: usize = 2;

/// One rank's block of the lattice.
#[derive(Debug, Clone)]
pub struct Decomposition {
    /// The whole lattice's cells along each axis.
    pub n: [usize; 3],
    /// Blocks along each axis (their product: the ranks).
    pub blocks: [usize; 3],
    /// The block's position among the blocks (x fastest: rank = x + bx (y + by z)).
    pub coords: [usize; 3],
    /// The block's first cell in the whole lattice, and its cells along each axis.
    pub origin: [usize; 3],
    pub size: [usize; 3],
    /// Whether each face (x_min, x_max, y_min, ...) has a ghost layer: a neighbouring rank across
    /// it (along a cut axis, wrapping where the axis is periodic).
    pub ghost: [bool; 6],
    periodic: [bool; 3],
}

impl Decomposition {
    /// Block `rank` of a lattice of `n` cells cut into `blocks` (checked by [`check_blocks`]).
    pub fn new(n: [usize; 3], periodic: [bool; 3], blocks: [usize; 3], rank: usize) -> Decomposition {
        let coords = [
            rank % blocks[0],
            (rank / blocks[0]) % blocks[1],
            rank / (blocks[0] * blocks[1]),
        ];
        let size: [usize; 3] = std::array::from_fn(|a| n[a] / blocks[a]);
        let ghost = std::array::from_fn(|f| {
            let (a, hi) = (f / 2, f % 2 == 1);
            let edge = if hi {
                coords[a] + 1 == blocks[a]
            } else {
                coords[a] == 0
            };
            blocks[a] > 1 && (periodic[a] || !edge)
        });
        Decomposition {
            n,
            blocks,
            coords,
            origin: std::array::from_fn(|a| coords[a] * size[a]),
            size,
            ghost,
            periodic,
        }
    }

    /// The rank whose block holds cell `x` of the whole lattice.
    pub fn owner(&self, x: [usize; 3]) -> usize {
        let c: [usize; 3] = std::array::from_fn(|a| x[a] / self.size[a]);
        c[0] + self.blocks[0] * (c[1] + self.blocks[1] * c[2])
    }

    /// The axes along which the whole lattice is periodic.
    pub fn periodic(&self) -> [bool; 3] {
        self.periodic
    }

    /// The ranks.
    pub fn ranks(&self) -> usize {
        self.blocks.iter().product()
    }

    /// The rank across face `face` (x_min, x_max, y_min, ...), where it has a ghost layer.
    pub fn neighbour(&self, face: usize) -> Option<usize> {
        if !self.ghost[face] {
            return None;
        }
        let a = face / 2;
        let mut c = self.coords;
        c[a] = if face % 2 == 1 {
            (c[a] + 1) % self.blocks[a]
        } else {
            (c[a] + self.blocks[a] - 1) % self.blocks[a]
        };
        Some(c[0] + self.blocks[0] * (c[1] + self.blocks[1] * c[2]))
    }

    /// The block's lattice: its cells and ghost layers.
    pub fn local_n(&self) -> [usize; 3] {
        std::array::from_fn(|a| self.size[a] + self.lo(a) + usize::from(self.ghost[2 * a + 1]))
    }

    /// 1 where the block has a ghost layer below along axis `a`.
    pub fn lo(&self, a: usize) -> usize {
        usize::from(self.ghost[2 * a])
    }

    /// The whole lattice's coordinates of the block's cell `x` (ghost layers included: wrapped
    /// across periodic faces).
    pub fn global(&self, x: [usize; 3]) -> [usize; 3] {
        std::array::from_fn(|a| (self.origin[a] + x[a] + self.n[a] - self.lo(a)) % self.n[a])
    }

    /// The block's own cells (ghost layers left out): (index in the block's lattice, index in
    /// the whole lattice), x fastest.
    pub fn own_cells(&self) -> Vec<(usize, usize)> {
        let ln = self.local_n();
        let mut cells = Vec::with_capacity(self.size.iter().product());
        for z in 0..self.size[2] {
            for y in 0..self.size[1] {
                for x in 0..self.size[0] {
                    let l = [x + self.lo(0), y + self.lo(1), z + self.lo(2)];
                    let g = self.global(l);
                    cells.push((
                        l[0] + ln[0] * (l[1] + ln[1] * l[2]),
                        g[0] + self.n[0] * (g[1] + self.n[1] * g[2]),
                    ));
                }
            }
        }
        cells
    }

    /// The position among the block's own cells (x fastest, as [`Decomposition::own_cells`] lists
    /// them) of cell `x` of the whole lattice, where the block holds it.
    pub fn own_index(&self, x: [usize; 3]) -> Option<usize> {
        if !(0..3).all(|a| x[a] / self.size[a] == self.coords[a]) {
            return None;
        }
        let l: [usize; 3] = std::array::from_fn(|a| x[a] - self.origin[a]);
        Some(l[0] + self.size[0] * (l[1] + self.size[1] * l[2]))
    }

    /// The block's lattice, from the whole lattice's `setup`: its solid cells, the whole
    /// lattice's faces where the block meets them, a wall closing each ghost layer.
    pub fn local_setup(&self, setup: &Setup) -> Setup {
        let ln = self.local_n();
        let mut local = setup.clone();
        local.n = ln;
        local.ghost_faces = self.ghost;
        for (f, face) in local.faces.iter_mut().enumerate() {
            if self.blocks[f / 2] > 1 {
                *face = if self.ghost[f] { Face::Wall } else { setup.faces[f] };
            }
        }
        local.solid = (0..ln.iter().product())
            .map(|k| setup.solid[setup.index(self.global(local.coords(k)))])
            .collect();
        local
    }
}

/// The blocks for `ranks` ranks on a lattice of `n` cells: of the ways to cut each axis into
/// equal blocks at least [`MIN_BLOCK_CELLS`] thick, the one with the fewest halo cells (cells
/// next to a cut, periodic wraps counted); of equals, the one cut most along z, then y (whole
/// rows along x stay together).
pub fn choose_blocks(n: [usize; 3], periodic: [bool; 3], ranks: usize) -> Result<[usize; 3], String> {
    let cuts = |a: usize, b: usize| {
        if b == 1 {
            0
        } else if periodic[a] {
            b
        } else {
            b - 1
        }
    };
    let halo = |b: [usize; 3]| -> usize {
        (0..3)
            .map(|a| 2 * cuts(a, b[a]) * n[(a + 1) % 3] * n[(a + 2) % 3])
            .sum()
    };
    let fits = |a: usize, b: usize| n[a].is_multiple_of(b) && (b == 1 || n[a] / b >= MIN_BLOCK_CELLS);
    let mut best: Option<([usize; 3], usize)> = None;
    for bz in (1..=ranks)
        .rev()
        .filter(|b| ranks.is_multiple_of(*b) && fits(2, *b))
    {
        for by in (1..=ranks / bz)
            .rev()
            .filter(|b| (ranks / bz).is_multiple_of(*b) && fits(1, *b))
        {
            let bx = ranks / bz / by;
            if !fits(0, bx) {
                continue;
            }
            let b = [bx, by, bz];
            if best.is_none_or(|(_, h)| halo(b) < h) {
                best = Some((b, halo(b)));
            }
        }
    }
    best.map(|(b, _)| b).ok_or_else(|| {
        format!(
            "{ranks} ranks: no way to cut the lattice of {}x{}x{} cells into {ranks} equal blocks at \
             least {MIN_BLOCK_CELLS} cells thick along each cut axis; run on fewer ranks, or give \
             [parallel] blocks",
            n[0], n[1], n[2]
        )
    })
}

/// Checks `blocks` (the scene's `[parallel] blocks`) against the lattice and the ranks: each axis
/// cut into equal blocks at least [`MIN_BLOCK_CELLS`] thick, one block per rank.
pub fn check_blocks(n: [usize; 3], blocks: [usize; 3], ranks: usize) -> Result<(), String> {
    let shown = format!("[{}, {}, {}]", blocks[0], blocks[1], blocks[2]);
    let product: usize = blocks.iter().product();
    if product != ranks {
        return Err(format!(
            "parallel.blocks = {shown}: {product} blocks, but the run has {ranks} rank(s) (mpirun -np); \
             one block per rank"
        ));
    }
    for a in 0..3 {
        let (b, cells) = (blocks[a], n[a]);
        if b == 0 || !cells.is_multiple_of(b) {
            return Err(format!(
                "parallel.blocks = {shown}: {b} blocks do not divide the lattice's {cells} cells along {}",
                ["x", "y", "z"][a]
            ));
        }
        if b > 1 && cells / b < MIN_BLOCK_CELLS {
            return Err(format!(
                "parallel.blocks = {shown}: blocks of {} cell(s) along {}, thinner than the halo needs \
                 (at least {MIN_BLOCK_CELLS})",
                cells / b,
                ["x", "y", "z"][a]
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_blocks_with_fewest_halo_cells_are_chosen() {
        assert_eq!(choose_blocks([8, 8, 8], [true; 3], 1), Ok([1, 1, 1]));
        assert_eq!(choose_blocks([8, 8, 8], [true; 3], 2), Ok([1, 1, 2]));
        assert_eq!(choose_blocks([8, 8, 32], [false; 3], 4), Ok([1, 1, 4]));
        assert_eq!(choose_blocks([32, 8, 8], [false; 3], 4), Ok([4, 1, 1]));
        assert_eq!(choose_blocks([16, 16, 16], [false; 3], 8), Ok([2, 2, 2]));
        assert!(choose_blocks([3, 3, 3], [true; 3], 2).is_err());
    }

    #[test]
    fn bad_blocks_are_refused_naming_the_value() {
        assert!(check_blocks([8, 8, 8], [2, 1, 1], 2).is_ok());
        let e = check_blocks([8, 8, 8], [3, 1, 1], 3).unwrap_err();
        assert!(e.contains("[3, 1, 1]") && e.contains("do not divide"), "{e}");
        let e = check_blocks([8, 8, 8], [2, 2, 1], 2).unwrap_err();
        assert!(e.contains("4 blocks") && e.contains("2 rank"), "{e}");
        let e = check_blocks([8, 8, 8], [8, 1, 1], 8).unwrap_err();
        assert!(e.contains("thinner than the halo"), "{e}");
    }

    #[test]
    fn a_block_knows_its_neighbours_and_ghost_layers() {
        let d = Decomposition::new([8, 6, 4], [false, true, false], [2, 3, 1], 3);
        assert_eq!(d.coords, [1, 1, 0]);
        assert_eq!(d.ghost, [true, false, true, true, false, false]);
        assert_eq!(d.local_n(), [5, 4, 4]);
        assert_eq!(d.neighbour(0), Some(2));
        assert_eq!(d.neighbour(2), Some(1));
        assert_eq!(d.neighbour(3), Some(5));
        let first = Decomposition::new([8, 6, 4], [false, true, false], [2, 3, 1], 0);
        assert_eq!(first.neighbour(2), Some(4), "periodic along y: wraps");
        assert_eq!(first.global([0, 0, 0]), [0, 5, 0]);
        assert_eq!(d.own_cells().len(), 4 * 2 * 4);
        for (i, &(_, g)) in d.own_cells().iter().enumerate() {
            let x = [g % 8, (g / 8) % 6, g / 48];
            assert_eq!(d.own_index(x), Some(i));
        }
        assert_eq!(d.own_index([0, 0, 0]), None);
    }
}
