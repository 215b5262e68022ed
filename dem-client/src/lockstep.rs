//! The DEM side of the lockstep loop (`dem-client connect`): states(n) out, forces(n) in, the
//! particles advanced over the fluid step; from the Welcome's `first_step` (a resumed run's),
//! and, where a reply carries CHECKPOINT, the particles' state for step n + 1 written into the
//! checkpoint folder, its marker last, before states(n + 1) are sent (PROTOCOL.md 6.4).

use crate::connect::{CoupledParticles, Faults, Substeps};
use protocol::{DemLink, LinkError, ParticleReply, ParticleState, StepFlags, StepHeader, Welcome};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

/// The run's loop and what it needs besides the particles.
pub(crate) struct Lockstep<'a> {
    pub link: &'a DemLink,
    pub welcome: &'a Welcome,
    pub substeps: Substeps,
    pub interrupted: &'a AtomicBool,
    pub faults: Faults,
    /// Where the fluid asks for the DEM's part of its checkpoints (None: it cannot ask).
    pub checkpoint_dir: Option<&'a Path>,
}

impl Lockstep<'_> {
    /// Runs the loop; returns the number of the steps completed (`last`: the last of them).
    pub fn run(&self, particles: &mut CoupledParticles, last: &mut Option<u64>) -> Result<u64, LinkError> {
        let (link, welcome, faults) = (self.link, self.welcome, self.faults);
        let mut states: Vec<ParticleState> = Vec::new();
        let mut replies: Vec<ParticleReply> = Vec::new();
        for step in welcome.first_step..welcome.steps {
            if faults.churn && step > 0 {
                particles.churn(step);
            }
            faults.stall(step);
            let stop = self.interrupted.load(Ordering::SeqCst);
            let flags = if stop { StepFlags::STOP } else { 0 };
            let sent_step = if faults.skip_step == Some(step) {
                step + 1
            } else {
                step
            };
            particles.states_into(&mut states);
            let header = StepHeader::new(sent_step, step as f64 * welcome.dt, states.len(), flags);
            link.send_states(header, |i| states[i])?;
            let received = link.receive_forces(step)?;
            replies.clear();
            replies.extend_from_slice(received.particles());
            check_ids(&states, &replies)?;
            let checkpoint = received.header().has(StepFlags::CHECKPOINT);
            let done = received.header().has(StepFlags::FINAL | StepFlags::STOP) || stop;
            drop(received);
            *last = Some(step);
            if done && !checkpoint {
                return Ok(step + 1);
            }
            particles.advance(&replies, self.substeps, welcome.dt);
            if checkpoint {
                self.write_checkpoint(step + 1, particles)?;
            }
            if done {
                return Ok(step + 1);
            }
        }
        Ok(welcome.steps)
    }

    /// The particles' state for `step` into the checkpoint folder, then its marker.
    fn write_checkpoint(&self, step: u64, particles: &CoupledParticles) -> Result<(), LinkError> {
        let dir = self.checkpoint_dir.ok_or_else(|| {
            LinkError::Ipc("the fluid asked for a checkpoint, but no checkpoint folder was given".into())
        })?;
        crate::checkpoint::write_coupled(dir, step, particles).map_err(LinkError::Ipc)
    }
}

/// The fluid must answer every particle, in order.
fn check_ids(states: &[ParticleState], replies: &[ParticleReply]) -> Result<(), LinkError> {
    let wrong = states.iter().zip(replies).position(|(s, r)| s.id != r.id);
    if replies.len() != states.len() || wrong.is_some() {
        return Err(LinkError::Ipc(format!(
            "the fluid's reply does not match the states sent (count {} vs {}, first wrong index {:?})",
            replies.len(),
            states.len(),
            wrong
        )));
    }
    Ok(())
}
