//! The fluid's answer to the DEM's states of a step: the states checked (every number finite,
//! every radius positive, every particle inside the domain), the fluid's step with them, and, at
//! the run's last step, its last health check; or, where the run ends at this step, zero loads
//! for the reply that carries STOP and the error that says why.

use super::session::Session;
use protocol::{ParticleReply, ParticleState};

impl Session {
    /// The fluid's replies to the states of `step` in `replies`, or why the run ends at this step
    /// (then `replies` holds zero loads, for the reply that carries STOP): states the fluid rejects,
    /// with the fluid's own blow-up first where it has one (a blown-up fluid sends forces that throw
    /// the particles out or make them NaN), or the fluid's failure (a health check).
    pub(super) fn answer(
        &mut self,
        states: &[ParticleState],
        step: u64,
        last: bool,
        replies: &mut Vec<ParticleReply>,
    ) -> Option<String> {
        let fluid = &mut self.fluid;
        replies.clear();
        let ended = match check_states(states, step, &self.p.scene.domain) {
            Some(why) => Some(match fluid.unstable_now() {
                Some(cause) => format!("{cause}; then {why}"),
                None => why,
            }),
            None => fluid
                .step(states, replies)
                .and_then(|()| if last { fluid.check_last_step() } else { Ok(()) })
                .err(),
        };
        if ended.is_some() {
            replies.clear();
            replies.extend(states.iter().map(|s| ParticleReply {
                id: s.id,
                force: [0.0; 3],
                torque: [0.0; 3],
            }));
        }
        ended.map(|e| self.describe_fluid(e))
    }
}

/// Health check of the DEM's states: every number finite, every radius positive, every particle
/// inside the domain.
fn check_states(states: &[ParticleState], step: u64, domain: &scene::Domain) -> Option<String> {
    states.iter().find_map(|s| {
        let finite = s
            .position
            .iter()
            .chain(&s.velocity)
            .chain(&s.angular_velocity)
            .all(|v| v.is_finite());
        if !finite || s.radius.is_nan() || s.radius <= 0.0 {
            return Some(format!(
                "the DEM client sent an invalid state at step {step}: particle id {} with position {:?}, \
                 velocity {:?}, radius {}",
                s.id, s.position, s.velocity, s.radius
            ));
        }
        let outside = (0..3).any(|a| s.position[a] < domain.min[a] || s.position[a] > domain.max[a]);
        outside.then(|| {
            format!(
                "particle id {} left the domain at step {step}: position {:?} m, velocity {:?} m/s \
                 (domain {:?} .. {:?} m); the fluid covers only the domain: an instability upstream, or \
                 a face without a wall",
                s.id, s.position, s.velocity, domain.min, domain.max
            )
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_particle_outside_the_domain_or_not_finite_stops_the_run_with_its_id() {
        let domain = scene::Domain {
            min: [0.0; 3],
            max: [0.1, 0.1, 0.2],
            periodic: Vec::new(),
        };
        let state = |id: u64, z: f64| ParticleState {
            id,
            position: [0.05, 0.05, z],
            velocity: [0.0, 0.0, -22.0],
            radius: 0.002,
            ..Default::default()
        };
        assert_eq!(check_states(&[state(0, 0.1), state(1, 0.2)], 3, &domain), None);
        let out = check_states(&[state(0, 0.1), state(7, -0.01)], 3, &domain).expect("refused");
        assert!(out.contains("particle id 7 left the domain at step 3"), "{out}");
        let nan = check_states(&[state(2, f64::NAN)], 4, &domain).expect("refused");
        assert!(nan.contains("invalid state at step 4: particle id 2"), "{nan}");
    }
}
