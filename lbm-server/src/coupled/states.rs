//! The DEM's states as the lattice's particles: SI converted to lattice units where the coupled
//! step reads them, each sphere drawn larger by the radius correction.

use super::radius_correction::drawn_larger_by;
use crate::lbm::imb::{SolidParticle, SolidParticles};
use protocol::ParticleState;

/// The DEM's states (SI) as the lattice reads them: each converted to lattice units where the
/// coupled step reads it.
pub(super) struct LatticeStates<'a> {
    pub(super) states: &'a [ParticleState],
    pub(super) origin: [f64; 3],
    pub(super) dx: f64,
    pub(super) dt: f64,
    /// Each radius of r cells is drawn r + this / max(r, 2) (`coupling.radius_correction`).
    pub(super) deficit_product: f64,
}

impl LatticeStates<'_> {
    /// The radius particle j is drawn with (cells): below 2 cells, where nothing was measured,
    /// the deficit of 2 cells.
    fn drawn_radius(&self, j: usize) -> f64 {
        let r = self.states[j].radius / self.dx;
        r + drawn_larger_by(self.deficit_product, r)
    }
}

impl SolidParticles for LatticeStates<'_> {
    fn count(&self) -> usize {
        self.states.len()
    }

    fn particle(&self, j: usize) -> SolidParticle {
        let (s, dx) = (&self.states[j], self.dx);
        SolidParticle {
            position: std::array::from_fn(|a| (s.position[a] - self.origin[a]) / dx),
            radius: self.drawn_radius(j),
            velocity: s.velocity.map(|v| v * self.dt / dx),
            angular_velocity: s.angular_velocity.map(|w| w * self.dt),
        }
    }

    fn radius(&self, j: usize) -> f64 {
        self.drawn_radius(j)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sphere_is_drawn_larger_by_the_deficit_product_over_its_radius() {
        let states = [0.003, 0.006].map(|radius| ParticleState {
            radius,
            ..Default::default()
        });
        let lattice = LatticeStates {
            states: &states,
            origin: [0.0; 3],
            dx: 0.001,
            dt: 1e-3,
            deficit_product: 0.75,
        };
        assert_eq!(lattice.particle(0).radius, 3.25, "3 cells + 0.75 / 3");
        assert_eq!(lattice.radius(1), 6.125, "the deficit falls as 1 / radius");
        let small = [ParticleState {
            radius: 0.001,
            ..Default::default()
        }];
        let lattice = LatticeStates {
            states: &small,
            ..lattice
        };
        assert_eq!(lattice.radius(0), 1.375, "below 2 cells, the deficit of 2");
    }
}
