//! Broad phase: a sorted-cell (linked-cell) grid builds a Verlet list of every pair closer than
//! r_i + r_j + skin; it is rebuilt only once some particle has moved more than skin / 2 since the
//! last build. O(N) per build, never O(N^2).

use super::V3;
use rayon::prelude::*;

/// A uniform grid over the particles' bounding box, particles sorted by cell.
struct Grid {
    lo: V3,
    cell: f64,
    dims: [usize; 3],
    /// Start of each cell in `order` (len cells + 1).
    start: Vec<u32>,
    /// Particle indices sorted by cell.
    order: Vec<u32>,
}

impl Grid {
    fn build(x: &[V3], cell: f64) -> Grid {
        let mut lo = V3::repeat(f64::INFINITY);
        let mut hi = V3::repeat(f64::NEG_INFINITY);
        for p in x {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        // Never more cells than ~8 per particle: a runaway particle widens the cells instead.
        let mut cell = cell;
        let max_cells = (8 * x.len()).max(64) as f64;
        let dims = loop {
            let d = (hi - lo) / cell;
            if !d.iter().all(|v| v.is_finite()) {
                break [1, 1, 1];
            }
            let dims = [d.x, d.y, d.z].map(|v| v.floor() as usize + 1);
            if dims.iter().map(|&v| v as f64).product::<f64>() <= max_cells {
                break dims;
            }
            cell *= 1.5;
        };
        let mut grid = Grid {
            lo,
            cell,
            dims,
            start: Vec::new(),
            order: Vec::new(),
        };
        let keys: Vec<u32> = x.iter().map(|p| grid.key(grid.coords(p))).collect();
        let n_cells = dims[0] * dims[1] * dims[2];
        let mut start = vec![0u32; n_cells + 1];
        for &k in &keys {
            start[k as usize + 1] += 1;
        }
        for c in 0..n_cells {
            start[c + 1] += start[c];
        }
        let mut fill = start.clone();
        let mut order = vec![0u32; x.len()];
        for (i, &k) in keys.iter().enumerate() {
            order[fill[k as usize] as usize] = i as u32;
            fill[k as usize] += 1;
        }
        grid.start = start;
        grid.order = order;
        grid
    }

    fn coords(&self, p: &V3) -> [usize; 3] {
        let c = (p - self.lo) / self.cell;
        let f = |v: f64, d: usize| (v.max(0.0) as usize).min(d - 1);
        [f(c.x, self.dims[0]), f(c.y, self.dims[1]), f(c.z, self.dims[2])]
    }

    fn key(&self, c: [usize; 3]) -> u32 {
        ((c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0]) as u32
    }

    /// Indices of the particles in the 27 cells around `c`, cell by cell in key order. The cells
    /// of a row along x are consecutive keys, so their particles are one run of `order`: nine
    /// runs, not 27 cells, each looked up by two reads of `start`.
    fn around(&self, c: [usize; 3], mut visit: impl FnMut(u32)) {
        let range = |a: usize| c[a].saturating_sub(1)..=(c[a] + 1).min(self.dims[a] - 1);
        let (x0, x1) = (c[0].saturating_sub(1), (c[0] + 1).min(self.dims[0] - 1));
        for z in range(2) {
            for y in range(1) {
                let (first, last) = (self.key([x0, y, z]) as usize, self.key([x1, y, z]) as usize);
                for &j in &self.order[self.start[first] as usize..self.start[last + 1] as usize] {
                    visit(j);
                }
            }
        }
    }
}

/// Pairs (i, j), i < j, with |x_i - x_j| < r_i + r_j + skin, sorted by i then j.
pub fn verlet_pairs(x: &[V3], r: &[f64], skin: f64) -> Vec<(u32, u32)> {
    if x.len() < 2 {
        return Vec::new();
    }
    let r_max = r.iter().copied().fold(0.0, f64::max);
    let grid = Grid::build(x, 2.0 * r_max + skin);
    (0..x.len())
        .into_par_iter()
        .flat_map_iter(|i| {
            let mut near = Vec::new();
            grid.around(grid.coords(&x[i]), |j| {
                let j = j as usize;
                if j > i {
                    let cut = r[i] + r[j] + skin;
                    if (x[i] - x[j]).norm_squared() < cut * cut {
                        near.push(j as u32);
                    }
                }
            });
            near.sort_unstable();
            near.into_iter().map(move |j| (i as u32, j))
        })
        .collect()
}

/// A box periodic along some axes: its lower corner and, per axis, its length (0: not periodic).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Periodic {
    pub lo: V3,
    pub len: [f64; 3],
}

impl Periodic {
    pub fn any(&self) -> bool {
        self.len.iter().any(|&l| l > 0.0)
    }

    /// `x` moved by whole periods into [lo, lo + len) along the periodic axes.
    pub fn wrap(&self, x: V3) -> V3 {
        V3::from_fn(|a, _| {
            let l = self.len[a];
            if l > 0.0 {
                self.lo[a] + (x[a] - self.lo[a]).rem_euclid(l)
            } else {
                x[a]
            }
        })
    }
}

/// Pairs (i, j, shift), i < j, whose nearest images are closer than r_i + r_j + skin in a box
/// periodic along some axes: |x_i - (x_j + shift)| < cut, shift a whole number of periods per
/// axis, sorted by i then j. The centres must lie in the box, and each periodic length must exceed
/// twice the largest cut (one image per pair). Images of the spheres near the periodic faces, one
/// period away, join the cell search as ghosts.
pub fn periodic_pairs(x: &[V3], r: &[f64], skin: f64, box_: &Periodic) -> Vec<(u32, u32, V3)> {
    let r_max = r.iter().copied().fold(0.0, f64::max);
    let reach = 2.0 * r_max + skin;
    // (original, shift) of each point: the spheres, then their images.
    let mut points: Vec<(usize, V3)> = (0..x.len()).map(|i| (i, V3::zeros())).collect();
    for a in 0..3 {
        let l = box_.len[a];
        if l <= 0.0 {
            continue;
        }
        for k in 0..points.len() {
            let (i, shift) = points[k];
            let at = x[i][a] + shift[a] - box_.lo[a];
            for (near, sign) in [(at < reach, 1.0), (at > l - reach, -1.0)] {
                if near {
                    let mut s = shift;
                    s[a] += sign * l;
                    points.push((i, s));
                }
            }
        }
    }
    let xs: Vec<V3> = points.iter().map(|&(i, s)| x[i] + s).collect();
    let rs: Vec<f64> = points.iter().map(|&(i, _)| r[i]).collect();
    let mut out: Vec<(u32, u32, V3)> = verlet_pairs(&xs, &rs, skin)
        .into_iter()
        .filter_map(|(p, q)| {
            let ((i, si), (j, sj)) = (points[p as usize], points[q as usize]);
            if i == j {
                // A sphere and its own image (more than a period apart: never, with the length
                // required).
                return None;
            }
            // x_i + si - (x_j + sj) = x_i - (x_j + (sj - si)).
            let shift = sj - si;
            Some(if i < j {
                (i as u32, j as u32, shift)
            } else {
                (j as u32, i as u32, -shift)
            })
        })
        .collect();
    // A pair is found once per pair of its copies that are close (e.g. both spheres and both
    // their images near a face): the same shift each time, at the nearest image.
    out.sort_by_key(|p| (p.0, p.1));
    out.dedup();
    out
}

/// Reference O(N^2) search, for tests only.
#[cfg(test)]
pub fn brute_force_pairs(x: &[V3], r: &[f64], skin: f64) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    for i in 0..x.len() {
        for j in i + 1..x.len() {
            let cut = r[i] + r[j] + skin;
            if (x[i] - x[j]).norm_squared() < cut * cut {
                out.push((i as u32, j as u32));
            }
        }
    }
    out
}

/// Reference O(N^2) search at the nearest image, for tests only.
#[cfg(test)]
pub fn brute_force_periodic_pairs(x: &[V3], r: &[f64], skin: f64, box_: &Periodic) -> Vec<(u32, u32, V3)> {
    let mut out = Vec::new();
    for i in 0..x.len() {
        for j in i + 1..x.len() {
            let d = x[i] - x[j];
            let shift = V3::from_fn(|a, _| {
                let l = box_.len[a];
                if l > 0.0 {
                    l * (d[a] / l).round()
                } else {
                    0.0
                }
            });
            let cut = r[i] + r[j] + skin;
            if (d - shift).norm_squared() < cut * cut {
                out.push((i as u32, j as u32, shift));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn periodic_search_equals_brute_force_at_the_nearest_image() {
        for (n, seed, size, len) in [
            (2, 1, 0.04, [0.04, 0.0, 0.0]),
            (500, 2, 0.1, [0.1, 0.1, 0.0]),
            (2000, 3, 0.2, [0.2, 0.2, 0.1]),
            (300, 5, 0.08, [0.08, 0.0, 0.04]),
        ] {
            let (x, r) = random_set(n, seed, size);
            let box_ = Periodic { lo: V3::zeros(), len };
            for skin in [0.0, 0.001] {
                let fast = periodic_pairs(&x, &r, skin, &box_);
                let slow = brute_force_periodic_pairs(&x, &r, skin, &box_);
                assert_eq!(fast.len(), slow.len(), "n {n} skin {skin}");
                for (f, s) in fast.iter().zip(&slow) {
                    assert_eq!((f.0, f.1), (s.0, s.1), "n {n} skin {skin}");
                    assert!((f.2 - s.2).norm() < 1e-12, "n {n} skin {skin}: {f:?} {s:?}");
                }
                let across = fast.iter().filter(|p| p.2 != V3::zeros()).count();
                assert!(n < 100 || across > 0, "n {n}: some pairs across the faces");
            }
        }
    }

    fn random_set(n: usize, seed: u64, box_size: f64) -> (Vec<V3>, Vec<f64>) {
        let mut s = seed;
        let mut unit = move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let x = (0..n)
            .map(|_| V3::new(unit() * box_size, unit() * box_size, unit() * box_size * 0.5))
            .collect();
        let r = (0..n).map(|_| 0.002 + 0.006 * unit()).collect();
        (x, r)
    }

    #[test]
    fn cell_search_equals_brute_force_on_random_polydisperse_sets() {
        for (n, seed, size) in [(2, 1, 0.01), (500, 2, 0.1), (2000, 3, 0.2), (3000, 4, 5.0)] {
            let (x, r) = random_set(n, seed, size);
            for skin in [0.0, 0.001, 0.004] {
                assert_eq!(
                    verlet_pairs(&x, &r, skin),
                    brute_force_pairs(&x, &r, skin),
                    "n {n} skin {skin}"
                );
            }
        }
    }

    #[test]
    fn a_runaway_particle_does_not_blow_up_the_grid() {
        let (mut x, r) = random_set(1000, 7, 0.1);
        x[0] = V3::new(1e6, -1e6, 3e5);
        assert_eq!(verlet_pairs(&x, &r, 0.001), brute_force_pairs(&x, &r, 0.001));
    }
}
