//! Lubrication correction for gaps the lattice cannot resolve (below one cell): the normal
//! squeeze-film force of two spheres, or of a sphere and a wall, that the lattice misses,
//!
//! F = -6 pi mu R*^2 (1/h - 1/h_c) v_n n,   R* = r1 r2 / (r1 + r2) (sphere-wall: R* = r),
//!
//! for approaching surfaces (v_n > 0) with gap h < h_c, v_n the approach speed along the line of
//! centres n, h = max(gap, h_min), h_c the cut-off
//! (one cell: the lattice resolves larger gaps itself) and h_min a roughness floor (1% of R*) that
//! keeps the force finite at contact. SI units throughout.
//!
//! The DEM holds the force over a whole fluid step dt, while the squeeze film's damping time
//! m* / (6 pi mu R*^2 / h) falls far below dt as h closes: held explicitly, the force would reverse
//! the approach and grow each step (a blow-up, measured on the default scene before this form). So
//! the force held is the one that gives the exact change of the approach speed over dt under the
//! film's damping, m* v_n (1 - exp(-lambda)) / dt with lambda = 6 pi mu R*^2 (1/h - 1/h_c) dt / m*
//! (m* = m1 m2 / (m1 + m2), a sphere's own mass against a wall): the explicit force while lambda
//! << 1, and never more than the force that stops the approach within the step. A pair in
//! contact, or that reaches contact within the step at its approach speed, gets no force: the
//! DEM's contact law resolves that collision in its sub-steps. Separating pairs get no force
//! either (the film cavitates in tension; see `squeeze`). This is the correction for a DEM that
//! does not integrate the films itself: a DEM that does (dem-client) declares LUBRICATION in its
//! Hello and the fluid leaves this out (`run/welcome.rs`, PROTOCOL.md 4.5).

use protocol::{ParticleReply, ParticleState};
use scene::lattice::{LatticeFace, LatticeUnits};
use scene::Scene;
use std::collections::HashMap;

/// Where the correction applies.
#[derive(Debug, Clone)]
pub struct HeldLubrication {
    /// Dynamic viscosity [Pa s].
    pub viscosity: f64,
    /// Cut-off gap h_c [m]: one lattice cell.
    pub cutoff: f64,
    /// Planes that are walls: (axis, coordinate [m], inward normal sign).
    pub walls: Vec<(usize, f64, f64)>,
    /// Per axis the domain's length where it is periodic [m] (0: not periodic): pairs across the
    /// faces of a periodic axis are found, at their nearest image.
    pub periods: [f64; 3],
    /// Particle density [kg/m^3], for the masses.
    pub density: f64,
    /// The step over which the DEM holds the force [s].
    pub dt: f64,
}

impl HeldLubrication {
    /// Lubrication with the lattice's cut-off (one cell) and the domain faces that are walls.
    pub fn for_lattice(scene: &Scene, units: &LatticeUnits) -> HeldLubrication {
        let walls = units
            .faces
            .iter()
            .enumerate()
            .filter(|(_, f)| matches!(f, LatticeFace::Wall | LatticeFace::MovingWall(_)))
            .map(|(k, _)| {
                let axis = k / 2;
                if k % 2 == 0 {
                    (axis, scene.domain.min[axis], 1.0)
                } else {
                    (axis, scene.domain.max[axis], -1.0)
                }
            })
            .collect();
        HeldLubrication {
            viscosity: scene.fluid.dynamic_viscosity,
            cutoff: units.dx,
            walls,
            periods: std::array::from_fn(|axis| {
                if units.faces[2 * axis] == LatticeFace::Periodic {
                    scene.domain.max[axis] - scene.domain.min[axis]
                } else {
                    0.0
                }
            }),
            density: scene.particles.density,
            dt: units.dt,
        }
    }

    /// Adds the correction to `replies` (same order as `states`).
    pub fn apply(&self, states: &[ParticleState], replies: &mut [ParticleReply]) {
        for (s, r) in states.iter().zip(replies.iter_mut()) {
            for &(axis, at, inward) in &self.walls {
                let gap = inward * (s.position[axis] - at) - s.radius;
                let approach = -inward * s.velocity[axis];
                let f = self.squeeze(s.radius, self.mass(s), gap, approach);
                r.force[axis] += inward * f;
            }
        }
        for (i, j) in self.close_pairs(states) {
            let (a, b) = (&states[i], &states[j]);
            let d = self.separation(a, b);
            let dist = d.iter().map(|v| v * v).sum::<f64>().sqrt();
            if dist == 0.0 {
                continue;
            }
            let n = d.map(|v| v / dist);
            let approach: f64 = (0..3).map(|k| (a.velocity[k] - b.velocity[k]) * n[k]).sum();
            let reduced = a.radius * b.radius / (a.radius + b.radius);
            let (ma, mb) = (self.mass(a), self.mass(b));
            let f = self.squeeze(reduced, ma * mb / (ma + mb), dist - a.radius - b.radius, approach);
            for (k, nk) in n.iter().enumerate() {
                replies[i].force[k] -= f * nk;
                replies[j].force[k] += f * nk;
            }
        }
    }

    /// Repulsive squeeze force magnitude for reduced radius R, reduced mass m*, gap h and approach
    /// speed, held over dt.
    fn squeeze(&self, reduced: f64, mass: f64, gap: f64, approach: f64) -> f64 {
        if gap >= self.cutoff || gap <= approach * self.dt || approach <= 0.0 {
            // Beyond the cut-off the lattice resolves the gap. In contact, or reaching contact
            // within the step, the DEM's contact law takes over: a force computed from the approach
            // at the start of the step and held while the contact bounces the pair would add to
            // the bounce. A separating pair is not held back: the film cavitates in tension, and a
            // held pull brings the pair back into contact within the step (measured on the default
            // scene: beads at rest kicked to 0.1-0.23 m/s with the pull, none without).
            return 0.0;
        }
        let damping = protocol::squeeze_film::film_damping(self.viscosity, reduced, gap, self.cutoff);
        let lambda = damping * self.dt / mass;
        -mass * approach * (-lambda).exp_m1() / self.dt
    }

    fn mass(&self, s: &ParticleState) -> f64 {
        self.density * 4.0 / 3.0 * std::f64::consts::PI * s.radius.powi(3)
    }

    /// b's centre from a's, at the nearest image along the periodic axes.
    fn separation(&self, a: &ParticleState, b: &ParticleState) -> [f64; 3] {
        std::array::from_fn(|k| {
            let d = b.position[k] - a.position[k];
            let period = self.periods[k];
            if period > 0.0 {
                d - period * (d / period).round()
            } else {
                d
            }
        })
    }

    /// Pairs closer than the cut-off, from a hashed cell grid (O(N)); along a periodic axis the
    /// grid wraps, with cells at least as long as along the others.
    fn close_pairs(&self, states: &[ParticleState]) -> Vec<(usize, usize)> {
        let r_max = states.iter().map(|s| s.radius).fold(0.0, f64::max);
        let cell = 2.0 * r_max + self.cutoff;
        if states.len() < 2 || cell <= 0.0 {
            return Vec::new();
        }
        // Cells per periodic axis (0: not periodic).
        let wraps = self.periods.map(|p| {
            if p > 0.0 {
                (p / cell).floor().max(1.0) as i64
            } else {
                0
            }
        });
        let key = |p: &[f64; 3]| -> [i64; 3] {
            std::array::from_fn(|a| match wraps[a] {
                0 => (p[a] / cell).floor() as i64,
                w => ((p[a] / self.periods[a] * w as f64).floor() as i64).rem_euclid(w),
            })
        };
        let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
        for (i, s) in states.iter().enumerate() {
            grid.entry(key(&s.position)).or_default().push(i);
        }
        let mut pairs = Vec::new();
        for (i, s) in states.iter().enumerate() {
            let k = key(&s.position);
            let mut near: Vec<[i64; 3]> = (0..27)
                .map(|t| {
                    let step = [t % 3 - 1, (t / 3) % 3 - 1, t / 9 - 1];
                    std::array::from_fn(|a| match wraps[a] {
                        0 => k[a] + step[a],
                        w => (k[a] + step[a]).rem_euclid(w),
                    })
                })
                .collect();
            // A periodic axis of one or two cells visits a cell more than once.
            near.sort_unstable();
            near.dedup();
            for list in near.iter().filter_map(|k| grid.get(k)) {
                for &j in list.iter().filter(|&&j| j > i) {
                    let t = &states[j];
                    let d2: f64 = self.separation(s, t).iter().map(|v| v * v).sum();
                    if d2.sqrt() - s.radius - t.radius < self.cutoff {
                        pairs.push((i, j));
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
        let lub = HeldLubrication {
            viscosity: 0.1,
            cutoff: 0.002,
            walls: Vec::new(),
            periods: [0.0; 3],
            density: 2500.0,
            dt: 1e-13,
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

    /// Two spheres closing across the periodic faces x = 0 and x = 0.1 m feel the film of the same
    /// pair inside the domain; without the period they are not a pair.
    #[test]
    fn spheres_across_periodic_faces_feel_the_film() {
        let lub = |periods: [f64; 3]| HeldLubrication {
            viscosity: 0.1,
            cutoff: 0.002,
            walls: Vec::new(),
            periods,
            density: 2500.0,
            dt: 1e-13,
        };
        let gap = 0.0005;
        let force = |lub: &HeldLubrication, a: f64, b: f64| {
            let states = [sphere(0, a, 0.01), sphere(1, b, -0.01)];
            let mut replies = [ParticleReply::default(); 2];
            lub.apply(&states, &mut replies);
            replies[1].force[0]
        };
        let periodic = lub([0.1, 0.0, 0.0]);
        let inside = force(&periodic, 0.05, 0.05 + 0.02 + gap);
        // a at x = 0.1 - 0.004, b 0.02 + gap further on, past x = 0.1: at 0.016 + gap.
        let across = force(&periodic, 0.096, 0.016 + gap);
        assert!(inside > 0.0);
        assert!(
            (across - inside).abs() < 1e-9 * inside,
            "{across} against {inside}"
        );
        assert_eq!(force(&lub([0.0; 3]), 0.096, 0.016 + gap), 0.0);
        // A period of one grid cell (0.03 m against cells of 0.022 m) finds the pair once.
        let tight = lub([0.03, 0.0, 0.0]);
        let states = [sphere(0, 0.001, 0.01), sphere(1, 0.001 + 0.02 + gap, -0.01)];
        assert_eq!(tight.close_pairs(&states), vec![(0, 1)]);
    }

    #[test]
    fn a_sphere_approaching_a_wall_is_slowed_until_the_contact_takes_over() {
        let lub = HeldLubrication {
            viscosity: 0.1,
            cutoff: 0.002,
            walls: vec![(0, 0.0, 1.0)],
            periods: [0.0; 3],
            density: 2500.0,
            dt: 1e-3,
        };
        let force = |x: f64, v: f64| {
            let mut replies = [ParticleReply::default()];
            lub.apply(&[sphere(0, x, v)], &mut replies);
            replies[0].force[0]
        };
        assert!(force(0.0105, -0.01) > 0.0, "pushed away from the wall x = 0");
        assert!(
            force(0.01005, -0.01) > force(0.0105, -0.01),
            "stronger as the gap closes"
        );
        assert_eq!(force(0.01005, 0.01), 0.0, "not held back when leaving");
        // 0.005 mm gap, closing at 0.01 m/s: contact within the 1 ms step; at rest on the wall.
        assert_eq!(force(0.010005, -0.01), 0.0, "the contact law takes over");
        assert_eq!(force(0.01, 0.0), 0.0);
    }

    #[test]
    fn a_force_held_over_a_long_step_slows_the_approach_and_never_reverses_it() {
        // At a gap of 0.2 mm the film's damping time m / (6 pi mu R^2 (1/h - 1/h_c)) is 1.2 ms,
        // against dt = 10 ms: an explicit force held over the step (lambda = 8) would reverse the
        // approach 7-fold and grow each step.
        let lub = HeldLubrication {
            viscosity: 1.0,
            cutoff: 0.002,
            walls: vec![(0, 0.0, 1.0)],
            periods: [0.0; 3],
            density: 2500.0,
            dt: 1e-2,
        };
        let mass = lub.mass(&sphere(0, 0.0, 0.0));
        let (mut x, mut v) = (0.0102, -0.01);
        for step in 0..200 {
            let mut reply = [ParticleReply::default()];
            lub.apply(&[sphere(0, x, v)], &mut reply);
            let v_next = v + reply[0].force[0] / mass * lub.dt;
            assert!(v_next <= 0.0 && v_next >= v, "step {step}: {v} -> {v_next}");
            v = v_next;
            x += v * lub.dt;
        }
        assert!(
            x > 0.01,
            "the film keeps the sphere off the wall: gap {}",
            x - 0.01
        );
    }
}
