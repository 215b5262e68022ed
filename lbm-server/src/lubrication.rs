//! Lubrication correction for gaps the lattice cannot resolve (below one cell): the normal
//! squeeze-film force of two spheres, or of a sphere and a wall, that the lattice misses,
//!
//! F = -6 pi mu R*^2 (1/h - 1/h_c) v_n n,   R* = r1 r2 / (r1 + r2) (sphere-wall: R* = r),
//!
//! for h_min <= h < h_c, with v_n the approach speed along the line of centres n, h_c the cut-off
//! (one cell: the lattice resolves larger gaps itself) and h_min a roughness floor (1% of R*) that
//! keeps the force finite at contact. SI units throughout.

use protocol::{ParticleReply, ParticleState};
use std::collections::HashMap;

/// Where the correction applies.
#[derive(Debug, Clone)]
pub struct Lubrication {
    /// Dynamic viscosity [Pa s].
    pub viscosity: f64,
    /// Cut-off gap h_c [m]: one lattice cell.
    pub cutoff: f64,
    /// Planes that are walls: (axis, coordinate [m], inward normal sign).
    pub walls: Vec<(usize, f64, f64)>,
}

/// Roughness floor, as a fraction of the reduced radius.
const MIN_GAP_FRACTION: f64 = 0.01;

impl Lubrication {
    /// Adds the correction to `replies` (same order as `states`).
    pub fn apply(&self, states: &[ParticleState], replies: &mut [ParticleReply]) {
        for (s, r) in states.iter().zip(replies.iter_mut()) {
            for &(axis, at, inward) in &self.walls {
                let gap = inward * (s.position[axis] - at) - s.radius;
                let approach = -inward * s.velocity[axis];
                let f = self.squeeze(s.radius, gap, approach);
                r.force[axis] += inward * f;
            }
        }
        for (i, j) in self.close_pairs(states) {
            let (a, b) = (&states[i], &states[j]);
            let d: [f64; 3] = std::array::from_fn(|k| b.position[k] - a.position[k]);
            let dist = d.iter().map(|v| v * v).sum::<f64>().sqrt();
            if dist == 0.0 {
                continue;
            }
            let n = d.map(|v| v / dist);
            let approach: f64 = (0..3).map(|k| (a.velocity[k] - b.velocity[k]) * n[k]).sum();
            let reduced = a.radius * b.radius / (a.radius + b.radius);
            let f = self.squeeze(reduced, dist - a.radius - b.radius, approach);
            for (k, nk) in n.iter().enumerate() {
                replies[i].force[k] -= f * nk;
                replies[j].force[k] += f * nk;
            }
        }
    }

    /// Repulsive squeeze force magnitude for reduced radius R, gap h and approach speed (negative
    /// when separating: the force then pulls the surfaces together).
    fn squeeze(&self, reduced: f64, gap: f64, approach: f64) -> f64 {
        if gap >= self.cutoff {
            return 0.0;
        }
        let h = gap.max(MIN_GAP_FRACTION * reduced);
        6.0 * std::f64::consts::PI
            * self.viscosity
            * reduced
            * reduced
            * (1.0 / h - 1.0 / self.cutoff)
            * approach
    }

    /// Pairs closer than the cut-off, from a hashed cell grid (O(N)).
    fn close_pairs(&self, states: &[ParticleState]) -> Vec<(usize, usize)> {
        let r_max = states.iter().map(|s| s.radius).fold(0.0, f64::max);
        let cell = 2.0 * r_max + self.cutoff;
        if states.len() < 2 || cell <= 0.0 {
            return Vec::new();
        }
        let key = |p: &[f64; 3]| p.map(|x| (x / cell).floor() as i64);
        let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
        for (i, s) in states.iter().enumerate() {
            grid.entry(key(&s.position)).or_default().push(i);
        }
        let mut pairs = Vec::new();
        for (i, s) in states.iter().enumerate() {
            let k = key(&s.position);
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        let Some(list) = grid.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) else {
                            continue;
                        };
                        for &j in list.iter().filter(|&&j| j > i) {
                            let t = &states[j];
                            let d2: f64 = (0..3).map(|a| (t.position[a] - s.position[a]).powi(2)).sum();
                            if d2.sqrt() - s.radius - t.radius < self.cutoff {
                                pairs.push((i, j));
                            }
                        }
                    }
                }
            }
        }
        pairs.sort_unstable();
        pairs
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sphere(id: u64, x: f64, v: f64) -> ParticleState {
        ParticleState {
            id,
            position: [x, 0.5, 0.5],
            velocity: [v, 0.0, 0.0],
            radius: 0.01,
            ..Default::default()
        }
    }

    #[test]
    fn approaching_spheres_are_pushed_apart_as_one_over_the_gap() {
        let lub = Lubrication {
            viscosity: 0.1,
            cutoff: 0.002,
            walls: Vec::new(),
        };
        let force_at = |gap: f64| {
            let states = [sphere(0, 0.3, 0.01), sphere(1, 0.3 + 0.02 + gap, -0.01)];
            let mut replies = [ParticleReply::default(); 2];
            lub.apply(&states, &mut replies);
            assert_eq!(replies[0].force[0], -replies[1].force[0], "equal and opposite");
            replies[1].force[0]
        };
        let (f1, f2) = (force_at(0.0005), force_at(0.00025));
        // R* = 0.005, v_n = 0.02: F = 6 pi mu R*^2 (1/h - 1/h_c) v_n
        let exact =
            |h: f64| 6.0 * std::f64::consts::PI * 0.1 * 0.005f64.powi(2) * (1.0 / h - 1.0 / 0.002) * 0.02;
        assert!((f1 - exact(0.0005)).abs() < 1e-12 && f1 > 0.0);
        assert!((f2 - exact(0.00025)).abs() < 1e-12 && f2 > f1);
        assert_eq!(
            force_at(0.003),
            0.0,
            "beyond the cut-off the lattice resolves the gap"
        );
    }

    #[test]
    fn a_sphere_approaching_a_wall_is_slowed_and_the_force_is_finite_at_contact() {
        let lub = Lubrication {
            viscosity: 0.1,
            cutoff: 0.002,
            walls: vec![(0, 0.0, 1.0)],
        };
        let states = [sphere(0, 0.0105, -0.01)];
        let mut replies = [ParticleReply::default()];
        lub.apply(&states, &mut replies);
        assert!(replies[0].force[0] > 0.0, "pushed away from the wall x = 0");
        let touching = [sphere(0, 0.01, -0.01)];
        let mut at_contact = [ParticleReply::default()];
        lub.apply(&touching, &mut at_contact);
        assert!(at_contact[0].force[0].is_finite() && at_contact[0].force[0] > replies[0].force[0]);
    }
}
