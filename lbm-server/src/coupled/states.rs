//! The DEM's states as the lattice's particles: SI converted to lattice units where the coupled
//! step reads them, each sphere drawn larger by the radius correction.

use super::radius_correction::drawn_larger_by;
use crate::lbm::imb::{SolidParticle, SolidParticles};
use protocol::ParticleState;
use scene::lattice::LatticeUnits;

/// The DEM's states (SI) as the lattice reads them: each converted to lattice units where the
/// coupled step reads it.
pub(super) struct LatticeStates<'a> {
    pub(super) states: &'a [ParticleState],
    pub(super) origin: [f64; 3],
    pub(super) units: &'a LatticeUnits,
    /// Each radius of r cells is drawn r + this / max(r, 2) (`coupling.radius_correction`).
    pub(super) deficit_product: f64,
}

impl LatticeStates<'_> {
    /// The radius particle j is drawn with (cells): below 2 cells, where nothing was measured,
    /// the deficit of 2 cells.
    fn drawn_radius(&self, j: usize) -> f64 {
        let r = self.units.cells(self.states[j].radius);
        r + drawn_larger_by(self.deficit_product, r)
    }
}

impl SolidParticles for LatticeStates<'_> {
    fn count(&self) -> usize {
        self.states.len()
    }

    fn particle(&self, j: usize) -> SolidParticle {
        let (s, u) = (&self.states[j], self.units);
        SolidParticle {
            position: u.lattice_position(s.position, self.origin),
            radius: self.drawn_radius(j),
            velocity: u.velocity(s.velocity),
            angular_velocity: u.angular_velocity(s.angular_velocity),
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
        let units = LatticeUnits {
            dx: 0.001,
            dt: 1e-3,
            ..scene::Scene::default_scene().lattice_units.expect("a lattice")
        };
        let lattice = LatticeStates {
            states: &states,
            origin: [0.0; 3],
            units: &units,
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
