//! STAND-IN fluid (removed when the lattice-Boltzmann and IMB issues land): a quiescent fluid that
//! exerts Stokes drag, F = -6 pi mu r v, and buoyancy, F = -rho_f V g, on each sphere. No torque.

use protocol::{ParticleReply, ParticleState};

/// The fluid properties the stand-in needs, in SI units.
#[derive(Debug, Clone, Copy)]
pub struct StokesFluid {
    pub density: f64,
    pub dynamic_viscosity: f64,
    pub gravity: [f64; 3],
}

impl StokesFluid {
    /// Drag and buoyancy on one sphere (SI in, SI out).
    pub fn load(&self, s: &ParticleState) -> ParticleReply {
        let drag = -6.0 * std::f64::consts::PI * self.dynamic_viscosity * s.radius;
        let volume = 4.0 / 3.0 * std::f64::consts::PI * s.radius.powi(3);
        let force = std::array::from_fn(|a| drag * s.velocity[a] - self.density * volume * self.gravity[a]);
        ParticleReply {
            id: s.id,
            force,
            torque: [0.0; 3],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn drag_opposes_motion_and_buoyancy_opposes_gravity() {
        let fluid = StokesFluid {
            density: 1000.0,
            dynamic_viscosity: 1e-3,
            gravity: [0.0, 0.0, -9.81],
        };
        let s = ParticleState {
            id: 3,
            velocity: [0.01, 0.0, 0.0],
            radius: 1e-3,
            ..Default::default()
        };
        let r = fluid.load(&s);
        assert_eq!(r.id, 3);
        let drag = 6.0 * std::f64::consts::PI * 1e-3 * 1e-3 * 0.01;
        assert!((r.force[0] + drag).abs() < 1e-18);
        let buoyancy = 1000.0 * 4.0 / 3.0 * std::f64::consts::PI * 1e-9 * 9.81;
        assert!((r.force[2] - buoyancy).abs() < 1e-15);
    }
}
