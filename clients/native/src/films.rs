//! The squeeze films of PROTOCOL.md 4.5 between spheres and against axis-aligned walls, at each
//! of the external DEM's steps (clients/python/substep_loads.py's `SqueezeFilms`, compiled): the
//! law is `protocol::squeeze_film::film_damping`, along the line of centres (the wall's normal).

use crate::vec3::{dot, norm, scale, sub, V3};
use protocol::squeeze_film::{film_damping, MIN_GAP_FRACTION};

/// A wall of the scene: its axis, its coordinate and its inward normal's sign.
#[derive(Debug, Clone, Copy)]
pub struct Wall {
    pub axis: usize,
    pub at: f64,
    pub sign: f64,
}

/// The squeeze films and the pairs that may feel one within the fluid step.
pub struct SqueezeFilms {
    pub viscosity: f64,
    /// The cut-off gap h_c [m]: one lattice cell.
    pub cutoff: f64,
    pub walls: Vec<Wall>,
    /// The period of each axis (0: not periodic).
    pub periods: V3,
    /// The candidate pairs, by particle id.
    pairs: Vec<(usize, usize)>,
    /// The same pairs by atom row (those with both atoms present), kept until the rows change,
    /// with each pair's effective radius r_i r_j / (r_i + r_j).
    rows: Vec<(u32, u32, f64)>,
}

impl SqueezeFilms {
    pub fn new(viscosity: f64, cutoff: f64, walls: Vec<Wall>, periods: V3) -> SqueezeFilms {
        SqueezeFilms {
            viscosity,
            cutoff,
            walls,
            periods,
            pairs: Vec::new(),
            rows: Vec::new(),
        }
    }

    /// The pairs (by id) that can come within the cut-off while each sphere moves up to `travel`.
    pub fn candidates(&mut self, ids: &[usize], x: &[V3], radius: &[f64], travel: f64) {
        let pairs = near_pairs(x, radius, self.cutoff + 2.0 * travel, self.periods);
        self.pairs = pairs.iter().map(|&(i, j)| (ids[i], ids[j])).collect();
        self.rows = pairs
            .into_iter()
            .map(|(i, j)| (i as u32, j as u32, effective_radius(radius[i], radius[j])))
            .collect();
    }

    /// Re-resolves the pairs' rows after the atoms changed rows (`row_of_id` maps a particle id
    /// to its row, `usize::MAX` where absent; a pair with an absent atom is left out).
    pub fn remap(&mut self, row_of_id: &[usize], radius: &[f64]) {
        self.rows.clear();
        for &(a, b) in &self.pairs {
            let (i, j) = (row_of_id[a], row_of_id[b]);
            if i != usize::MAX && j != usize::MAX {
                self.rows
                    .push((i as u32, j as u32, effective_radius(radius[i], radius[j])));
            }
        }
    }

    /// Adds the film force on each sphere (rows as `x`, the rows of the last `candidates` or
    /// `remap`) for the present gaps and velocities to `f`: the pairs a chunk at a time,
    /// gathered into lanes (`Lanes`) whose forces the vector units compute side by side, then
    /// added in the pairs' order.
    pub fn add_forces(&self, x: &[V3], v: &[V3], radius: &[f64], f: &mut [V3]) {
        let mut lanes = Lanes::default();
        let mut out = [[0.0; CHUNK]; 3];
        for chunk in self.rows.chunks(CHUNK) {
            lanes.gather(chunk, x, v, radius, self.periods);
            self.lane_forces(&lanes, &mut out);
            for (k, &(i, j, _)) in chunk.iter().enumerate() {
                let pair = [out[0][k], out[1][k], out[2][k]];
                crate::vec3::add_to(&mut f[i as usize], pair);
                f[j as usize] = sub(f[j as usize], pair);
            }
        }
        for (i, fi) in f.iter_mut().enumerate() {
            for w in &self.walls {
                let gap = w.sign * (x[i][w.axis] - w.at) - radius[i];
                // sign * c * (approach speed -sign v) = -c v along the wall's axis
                fi[w.axis] -= film_damping(self.viscosity, radius[i], gap, self.cutoff) * v[i][w.axis];
            }
        }
    }

    /// The film force on sphere i of each lane's pair (every lane of the chunk: those past its
    /// pairs hold an earlier chunk's, unused): `pair_force` without branches, which the compiler
    /// turns into vector instructions, the same operations in the same order lane by lane.
    #[allow(clippy::needless_range_loop)] // one index across the lanes' arrays
    fn lane_forces(&self, l: &Lanes, out: &mut [[f64; CHUNK]; 3]) {
        let inv_cutoff = 1.0 / self.cutoff;
        for k in 0..CHUNK {
            let d = [l.d[0][k], l.d[1][k], l.d[2][k]];
            let dist = norm(d);
            let normal = scale(d, 1.0 / if dist > 0.0 { dist } else { 1.0 });
            let approach = -dot([l.dv[0][k], l.dv[1][k], l.dv[2][k]], normal);
            let (r_eff, gap) = (l.r_eff[k], dist - l.ri[k] - l.rj[k]);
            let h = gap.max(MIN_GAP_FRACTION * r_eff);
            let c = 6.0 * std::f64::consts::PI * self.viscosity * r_eff * r_eff * (1.0 / h - inv_cutoff);
            let c = if gap <= 0.0 || gap >= self.cutoff { 0.0 } else { c };
            for a in 0..3 {
                out[a][k] = normal[a] * (c * approach);
            }
        }
    }
}

/// The effective radius of a pair of spheres, r_i r_j / (r_i + r_j).
fn effective_radius(ri: f64, rj: f64) -> f64 {
    ri * rj / (ri + rj)
}

/// The pairs evaluated side by side.
const CHUNK: usize = 64;

/// One chunk of pairs in lanes: x_i - x_j (nearest image), v_i - v_j, r_eff, r_i, r_j.
struct Lanes {
    d: [[f64; CHUNK]; 3],
    dv: [[f64; CHUNK]; 3],
    r_eff: [f64; CHUNK],
    ri: [f64; CHUNK],
    rj: [f64; CHUNK],
}

impl Default for Lanes {
    fn default() -> Lanes {
        Lanes {
            d: [[0.0; CHUNK]; 3],
            dv: [[0.0; CHUNK]; 3],
            r_eff: [0.0; CHUNK],
            ri: [0.0; CHUNK],
            rj: [0.0; CHUNK],
        }
    }
}

impl Lanes {
    /// The lanes of `pairs` (rows of `x`, `v`, `radius`; at most CHUNK).
    fn gather(&mut self, pairs: &[(u32, u32, f64)], x: &[V3], v: &[V3], radius: &[f64], periods: V3) {
        let periodic = periods.iter().any(|&p| p > 0.0);
        for (k, &(i, j, r_eff)) in pairs.iter().enumerate() {
            let (i, j) = (i as usize, j as usize);
            let d = sub(x[i], x[j]);
            let d = if periodic { separation(d, periods) } else { d };
            let dv = sub(v[i], v[j]);
            for a in 0..3 {
                self.d[a][k] = d[a];
                self.dv[a][k] = dv[a];
            }
            (self.r_eff[k], self.ri[k], self.rj[k]) = (r_eff, radius[i], radius[j]);
        }
    }
}

/// x_i - x_j at the nearest image along the axes with a period > 0.
pub fn separation(mut d: V3, periods: V3) -> V3 {
    for a in 0..3 {
        if periods[a] > 0.0 {
            d[a] -= periods[a] * (d[a] / periods[a]).round_ties_even();
        }
    }
    d
}

/// The pairs (i < j, rows of `x`) whose surfaces are closer than `reach` (nearest image along the
/// periodic axes), found on a grid of cells one largest diameter plus `reach` wide.
pub fn near_pairs(x: &[V3], radius: &[f64], reach: f64, periods: V3) -> Vec<(usize, usize)> {
    let n = x.len();
    if n < 2 {
        return Vec::new();
    }
    let grid = Grid::new(x, radius, reach, periods);
    let (start, members) = grid.bins(x);
    let mut pairs = Vec::new();
    let mut near = Vec::with_capacity(27);
    for i in 0..n {
        grid.neighbours(grid.cell(x[i]), &mut near);
        for &key in &near {
            for &j in &members[start[key]..start[key + 1]] {
                if j <= i {
                    continue;
                }
                let d = separation(sub(x[i], x[j]), periods);
                // the square root only where the squared distance is not clearly beyond
                let far = radius[i] + radius[j] + reach;
                if dot(d, d) < far * far * (1.0 + 1e-9) && norm(d) - radius[i] - radius[j] < reach {
                    pairs.push((i, j));
                }
            }
        }
    }
    pairs.sort_unstable();
    pairs
}

/// Cells at least one largest diameter plus the reach wide over the spheres' extent (the period
/// along a periodic axis).
struct Grid {
    lo: V3,
    width: V3,
    dims: [usize; 3],
    periodic: [bool; 3],
}

impl Grid {
    fn new(x: &[V3], radius: &[f64], reach: f64, periods: V3) -> Grid {
        let size = 2.0 * radius.iter().cloned().fold(0.0, f64::max) + reach;
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for p in x {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        let (mut width, mut dims, mut periodic) = ([0.0; 3], [1usize; 3], [false; 3]);
        for a in 0..3 {
            periodic[a] = periods[a] > 0.0;
            let span = if periodic[a] {
                periods[a]
            } else {
                hi[a] - lo[a] + size
            };
            dims[a] = ((span / size).floor() as usize).max(1);
            width[a] = span / dims[a] as f64;
        }
        Grid {
            lo,
            width,
            dims,
            periodic,
        }
    }

    fn cell(&self, p: V3) -> [usize; 3] {
        let mut c = [0; 3];
        for a in 0..3 {
            let k = ((p[a] - self.lo[a]) / self.width[a]).floor() as i64;
            let d = self.dims[a] as i64;
            c[a] = if self.periodic[a] {
                k.rem_euclid(d)
            } else {
                k.clamp(0, d - 1)
            } as usize;
        }
        c
    }

    fn key(&self, c: [usize; 3]) -> usize {
        (c[0] * self.dims[1] + c[1]) * self.dims[2] + c[2]
    }

    /// The rows of `x` by cell: cell k holds members[start[k]..start[k + 1]].
    fn bins(&self, x: &[V3]) -> (Vec<usize>, Vec<usize>) {
        let cells = self.dims.iter().product::<usize>();
        let keys: Vec<usize> = x.iter().map(|&p| self.key(self.cell(p))).collect();
        let mut start = vec![0usize; cells + 1];
        for &k in &keys {
            start[k + 1] += 1;
        }
        for k in 0..cells {
            start[k + 1] += start[k];
        }
        let mut fill = start.clone();
        let mut members = vec![0; x.len()];
        for (i, &k) in keys.iter().enumerate() {
            members[fill[k]] = i;
            fill[k] += 1;
        }
        (start, members)
    }

    /// The keys of the cells next to `c` and `c` itself, each once (a wrapped offset can meet
    /// the same cell twice).
    fn neighbours(&self, c: [usize; 3], out: &mut Vec<usize>) {
        out.clear();
        for o in 0..27 {
            let offset = [o / 9, (o / 3) % 3, o % 3];
            let mut n = [0usize; 3];
            let mut inside = true;
            for a in 0..3 {
                let k = c[a] as i64 + offset[a] as i64 - 1;
                let d = self.dims[a] as i64;
                if self.periodic[a] {
                    n[a] = k.rem_euclid(d) as usize;
                } else if (0..d).contains(&k) {
                    n[a] = k as usize;
                } else {
                    inside = false;
                }
            }
            if inside {
                let key = self.key(n);
                if !out.contains(&key) {
                    out.push(key);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every pair by brute force.
    fn brute(x: &[V3], radius: &[f64], reach: f64, periods: V3) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        for i in 0..x.len() {
            for j in i + 1..x.len() {
                if norm(separation(sub(x[i], x[j]), periods)) - radius[i] - radius[j] < reach {
                    out.push((i, j));
                }
            }
        }
        out
    }

    fn cloud(n: usize, seed: u64) -> Vec<V3> {
        let mut s = seed;
        let mut next = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n)
            .map(|_| [next() * 0.01, next() * 0.01, next() * 0.004])
            .collect()
    }

    #[test]
    fn the_grid_finds_every_near_pair() {
        let x = cloud(400, 7);
        let radius = vec![0.0004; x.len()];
        for periods in [[0.0; 3], [0.01, 0.0, 0.0], [0.01, 0.01, 0.004]] {
            assert_eq!(
                near_pairs(&x, &radius, 0.0003, periods),
                brute(&x, &radius, 0.0003, periods)
            );
        }
    }

    /// The film force on sphere i of a pair by `film_damping`: `d` = x_i - x_j, `dv` = v_i - v_j.
    fn pair_force(films: &SqueezeFilms, d: V3, dv: V3, ri: f64, rj: f64) -> V3 {
        let dist = norm(d);
        let normal = scale(d, 1.0 / if dist > 0.0 { dist } else { 1.0 });
        let damping = film_damping(
            films.viscosity,
            effective_radius(ri, rj),
            dist - ri - rj,
            films.cutoff,
        );
        scale(normal, damping * -dot(dv, normal))
    }

    #[test]
    fn the_lanes_give_film_damping_to_the_bit() {
        let films = SqueezeFilms::new(0.07, 0.000156, Vec::new(), [0.0; 3]);
        let (x, v) = (cloud(2 * CHUNK, 3), cloud(2 * CHUNK, 5));
        let radius: Vec<f64> = (0..x.len()).map(|i| 0.0004 + 1e-5 * (i % 7) as f64).collect();
        let rows: Vec<(u32, u32, f64)> = (0..CHUNK)
            .map(|k| {
                (
                    k as u32,
                    (k + CHUNK) as u32,
                    effective_radius(radius[k], radius[k + CHUNK]),
                )
            })
            .collect();
        let mut x = x;
        for k in 0..CHUNK {
            // gaps from -0.1 to 1.5 cut-offs, through the minimum gap
            let gap = films.cutoff * (-0.1 + 1.6 * k as f64 / CHUNK as f64);
            let dir = sub(x[k + CHUNK], x[k]);
            let reach = radius[k] + radius[k + CHUNK] + gap;
            x[k + CHUNK] = crate::vec3::add(x[k], scale(dir, reach / norm(dir)));
        }
        let (mut lanes, mut out) = (Lanes::default(), [[0.0; CHUNK]; 3]);
        lanes.gather(&rows, &x, &v, &radius, films.periods);
        films.lane_forces(&lanes, &mut out);
        for (k, &(i, j, _)) in rows.iter().enumerate() {
            let (i, j) = (i as usize, j as usize);
            let want = pair_force(&films, sub(x[i], x[j]), sub(v[i], v[j]), radius[i], radius[j]);
            assert_eq!([out[0][k], out[1][k], out[2][k]], want, "pair {k}");
        }
        assert!(out[0].iter().filter(|&&f| f != 0.0).count() > CHUNK / 2);
    }

    #[test]
    fn a_film_pushes_an_approaching_pair_apart_and_damps_a_wall_approach() {
        let mut films = SqueezeFilms::new(
            0.1,
            0.001,
            vec![Wall {
                axis: 2,
                at: 0.0,
                sign: 1.0,
            }],
            [0.0; 3],
        );
        let x = [[0.0, 0.0, 0.0021], [0.0021, 0.0, 0.0021]];
        let (v, radius) = ([[0.01, 0.0, 0.0], [0.0, 0.0, -0.01]], [0.001, 0.001]);
        films.candidates(&[0, 1], &x, &radius, 0.0);
        let mut f = [[0.0; 3]; 2];
        films.add_forces(&x, &v, &radius, &mut f);
        let c = film_damping(0.1, 0.0005, 0.0021 - 0.001 - 0.001, 0.001);
        assert_eq!(f[0][0], -c * 0.01, "the pair's film on sphere 0");
        assert_eq!(f[1][0], c * 0.01);
        let wall = film_damping(0.1, 0.001, 0.0011, 0.001);
        assert_eq!(wall, 0.0, "1.1 mm from the floor: beyond the cut-off");
        assert_eq!(f[1][2], 0.0);
    }
}
