//! STAND-IN particle motion (removed when the DEM issue lands): symplectic Euler under gravity and
//! the fluid force, elastic reflection at the domain faces, no contacts.

use protocol::{ParticleReply, ParticleState};

/// The particles the DEM side owns, in SI units.
pub struct Particles {
    pub states: Vec<ParticleState>,
    /// Mass of each particle [kg].
    pub mass: Vec<f64>,
    /// Density of the solid [kg/m^3].
    pub density: f64,
    next_id: u64,
}

impl Particles {
    pub fn from_scene(scene: &scene::Scene) -> Self {
        let density = scene.particles.density;
        let states: Vec<ParticleState> = scene
            .initial_particles()
            .iter()
            .map(|p| ParticleState {
                id: p.id,
                position: p.position,
                velocity: p.velocity,
                angular_velocity: p.angular_velocity,
                radius: p.radius,
            })
            .collect();
        let mass = states.iter().map(|s| sphere_mass(density, s.radius)).collect();
        let next_id = states.iter().map(|s| s.id + 1).max().unwrap_or(0);
        Self {
            states,
            mass,
            density,
            next_id,
        }
    }

    /// Advances every particle by `dt` under `gravity` and the fluid's replies (same order).
    pub fn advance(
        &mut self,
        replies: &[ParticleReply],
        gravity: [f64; 3],
        dt: f64,
        domain: ([f64; 3], [f64; 3]),
    ) {
        for ((s, m), r) in self.states.iter_mut().zip(&self.mass).zip(replies) {
            for (a, g) in gravity.iter().enumerate() {
                s.velocity[a] += dt * (r.force[a] / m + g);
                s.position[a] += dt * s.velocity[a];
            }
            reflect(s, domain);
        }
    }

    /// Test aid: removes the last particle or inserts a copy of the first with a fresh id, so the
    /// particle count changes between steps.
    pub fn churn(&mut self, step: u64) {
        if step % 2 == 1 && self.states.len() > 1 {
            self.states.pop();
            self.mass.pop();
        } else {
            let mut s = self.states[0];
            s.id = self.next_id;
            self.next_id += 1;
            self.mass.push(sphere_mass(self.density, s.radius));
            self.states.push(s);
        }
    }
}

pub fn sphere_mass(density: f64, radius: f64) -> f64 {
    density * 4.0 / 3.0 * std::f64::consts::PI * radius.powi(3)
}

/// Elastic reflection at the domain faces.
fn reflect(s: &mut ParticleState, (lo, hi): ([f64; 3], [f64; 3])) {
    for a in 0..3 {
        if s.position[a] - s.radius < lo[a] {
            s.position[a] = 2.0 * (lo[a] + s.radius) - s.position[a];
            s.velocity[a] = s.velocity[a].abs();
        } else if s.position[a] + s.radius > hi[a] {
            s.position[a] = 2.0 * (hi[a] - s.radius) - s.position[a];
            s.velocity[a] = -s.velocity[a].abs();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn free_fall_matches_symplectic_euler_and_reflects() {
        let mut p = Particles {
            states: vec![ParticleState {
                id: 0,
                position: [0.5, 0.5, 0.5],
                radius: 0.1,
                ..Default::default()
            }],
            mass: vec![1.0],
            density: 1.0,
            next_id: 1,
        };
        let none = [ParticleReply::default()];
        let domain = ([0.0; 3], [1.0; 3]);
        p.advance(&none, [0.0, 0.0, -10.0], 0.1, domain);
        assert!((p.states[0].velocity[2] + 1.0).abs() < 1e-12);
        assert!((p.states[0].position[2] - 0.4).abs() < 1e-12);
        for _ in 0..10 {
            p.advance(&none, [0.0, 0.0, -10.0], 0.1, domain);
        }
        assert!(
            p.states[0].position[2] >= 0.1,
            "stays inside: {:?}",
            p.states[0].position
        );
    }
}
