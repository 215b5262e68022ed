//! Initial-overlap check over a hashed cell grid: O(N), never O(N^2).

use crate::InitialParticle;
use std::collections::{BTreeSet, HashMap};

/// The periodic axes of a domain: their lower face and length (length 0 along the others).
#[derive(Debug, Clone, Copy, Default)]
pub struct Periods {
    pub lo: [f64; 3],
    pub len: [f64; 3],
}

impl Periods {
    /// The distance between the nearest images of a and b.
    fn distance(&self, a: &[f64; 3], b: &[f64; 3]) -> f64 {
        (0..3)
            .map(|k| {
                let (d, l) = (a[k] - b[k], self.len[k]);
                if l > 0.0 {
                    d - l * (d / l).round()
                } else {
                    d
                }
            })
            .map(|s| s * s)
            .sum::<f64>()
            .sqrt()
    }
}

/// Pairs (id a, id b, overlap depth [m]) whose overlap exceeds `fraction` of the smaller radius,
/// at their nearest images along the periodic axes of `periods` (two spheres at opposite faces
/// overlap across them).
pub fn overlapping_pairs(
    particles: &[InitialParticle],
    fraction: f64,
    periods: &Periods,
) -> Vec<(u64, u64, f64)> {
    let r_max = particles.iter().map(|p| p.radius).fold(0.0, f64::max);
    if particles.len() < 2 || r_max <= 0.0 {
        return Vec::new();
    }
    let grid = Grid::new(2.0 * r_max, periods);
    let mut cells: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    for (i, p) in particles.iter().enumerate() {
        cells.entry(grid.key(&p.position)).or_default().push(i);
    }
    let mut pairs = Vec::new();
    for (i, p) in particles.iter().enumerate() {
        for key in grid.neighbours(grid.key(&p.position)) {
            let Some(cell) = cells.get(&key) else {
                continue;
            };
            for &j in cell.iter().filter(|&&j| j > i) {
                let q = &particles[j];
                let depth = p.radius + q.radius - periods.distance(&p.position, &q.position);
                if depth > fraction * p.radius.min(q.radius) {
                    pairs.push((p.id, q.id, depth));
                }
            }
        }
    }
    pairs.sort_by_key(|p| (p.0, p.1));
    pairs
}

/// Cells at least `size` wide; along a periodic axis a whole number of them spans the period,
/// and the neighbours wrap.
struct Grid {
    size: [f64; 3],
    lo: [f64; 3],
    /// Cells along each periodic axis (0 along the others).
    count: [i64; 3],
}

impl Grid {
    fn new(size: f64, periods: &Periods) -> Grid {
        let count = periods.len.map(|l| {
            if l > 0.0 {
                ((l / size).floor() as i64).max(1)
            } else {
                0
            }
        });
        Grid {
            size: std::array::from_fn(|a| {
                if count[a] > 0 {
                    periods.len[a] / count[a] as f64
                } else {
                    size
                }
            }),
            lo: periods.lo,
            count,
        }
    }

    fn key(&self, x: &[f64; 3]) -> [i64; 3] {
        std::array::from_fn(|a| {
            let k = ((x[a] - self.lo[a]) / self.size[a]).floor() as i64;
            if self.count[a] > 0 {
                k.rem_euclid(self.count[a])
            } else {
                k
            }
        })
    }

    /// The cell and its 26 neighbours, wrapped along the periodic axes, each once.
    fn neighbours(&self, k: [i64; 3]) -> BTreeSet<[i64; 3]> {
        let mut out = BTreeSet::new();
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let n = [k[0] + dx, k[1] + dy, k[2] + dz];
                    out.insert(std::array::from_fn(|a| {
                        if self.count[a] > 0 {
                            n[a].rem_euclid(self.count[a])
                        } else {
                            n[a]
                        }
                    }));
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sphere(id: u64, position: [f64; 3], radius: f64) -> InitialParticle {
        InitialParticle {
            id,
            position,
            velocity: [0.0; 3],
            angular_velocity: [0.0; 3],
            radius,
        }
    }

    /// Every pair against a brute-force search at the nearest images, in boxes periodic along
    /// none, some and all axes, some of them only one or two cells long.
    #[test]
    fn the_grid_finds_every_overlap_a_brute_force_search_finds() {
        let mut seed = 7u64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for len in [[0.0; 3], [1.0, 0.0, 0.0], [1.0, 0.09, 0.0], [0.05, 0.12, 1.0]] {
            let lo = [-0.3, 0.2, 0.0];
            let periods = Periods { lo, len };
            let extent = len.map(|l| if l > 0.0 { l } else { 1.0 });
            let particles: Vec<InitialParticle> = (0..400)
                .map(|i| {
                    let x = std::array::from_fn(|a| lo[a] + next() * extent[a]);
                    sphere(i, x, 0.01 + 0.015 * next())
                })
                .collect();
            let mut want = Vec::new();
            for (i, p) in particles.iter().enumerate() {
                for q in &particles[i + 1..] {
                    let depth = p.radius + q.radius - periods.distance(&p.position, &q.position);
                    if depth > 0.1 * p.radius.min(q.radius) {
                        want.push((p.id, q.id, depth));
                    }
                }
            }
            want.sort_by_key(|p| (p.0, p.1));
            let got = overlapping_pairs(&particles, 0.1, &periods);
            assert!(!want.is_empty(), "{len:?}: some overlaps");
            assert_eq!(got, want, "periods {len:?}");
        }
    }

    #[test]
    fn spheres_at_opposite_periodic_faces_overlap_across_them() {
        let a = sphere(0, [0.001, 0.5, 0.5], 0.01);
        let b = sphere(1, [0.995, 0.5, 0.5], 0.01);
        let periodic = Periods {
            lo: [0.0; 3],
            len: [1.0, 0.0, 0.0],
        };
        let pairs = overlapping_pairs(&[a, b], 0.05, &periodic);
        assert_eq!(pairs.len(), 1);
        assert!((pairs[0].2 - 0.014).abs() < 1e-12, "{pairs:?}");
        assert!(overlapping_pairs(&[a, b], 0.05, &Periods::default()).is_empty());
    }
}
