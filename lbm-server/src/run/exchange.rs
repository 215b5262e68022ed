//! The exchange of a coupled step over the link: the DEM's states received and read in SI, the
//! fluid's replies sent back in the DEM's units.

use super::session::Session;
use protocol::transport::Received;
use protocol::{ParticleReply, ParticleState, StepFlags, StepHeader, Units};

impl Session {
    /// Waits for the DEM's states of `step`.
    pub(super) fn receive_states(&self, step: u64) -> Result<Received<ParticleState>, String> {
        self.link.receive_states(step).map_err(|e| self.describe(e))
    }

    /// Sends the fluid's `replies` (SI) to the DEM in its `units`; a reply that carries FINAL or
    /// STOP tells the DEM to end.
    pub(super) fn reply(
        &mut self,
        header: StepHeader,
        units: Units,
        replies: &[ParticleReply],
    ) -> Result<(), String> {
        let sent = if units == Units::SI {
            self.link.send_forces(header, |i| replies[i])
        } else {
            self.link
                .send_forces(header, |i| units.reply_from_si(&replies[i]))
        };
        sent.map_err(|e| self.describe(e))?;
        self.told_to_end = header.has(StepFlags::FINAL) || header.has(StepFlags::STOP);
        Ok(())
    }
}

/// The DEM's states of a step in SI, for the fluid and particles.csv. A DEM that speaks SI: its
/// states are read where it wrote them (the shared memory, no copy) and copied only for
/// particles.csv, after the reply (the DEM loans the next sample once it has the forces); other
/// units are converted here, and the replies back where they are sent.
pub(super) struct SiStates {
    /// The DEM's units.
    pub(super) units: Units,
    /// The states in SI: converted (units not SI), or copied for particles.csv (SI).
    pub(super) states: Vec<ParticleState>,
}

impl SiStates {
    pub(super) fn new(units: Units) -> Self {
        Self {
            units,
            states: Vec::new(),
        }
    }

    /// The states of `received` in SI.
    pub(super) fn read<'a>(&'a mut self, received: &'a Received<ParticleState>) -> &'a [ParticleState] {
        if self.units == Units::SI {
            return received.particles();
        }
        let units = self.units;
        self.states.clear();
        self.states
            .extend(received.particles().iter().map(|s| units.state_to_si(s)));
        &self.states
    }

    /// Where the DEM speaks SI and the step is written: a copy of its states for particles.csv,
    /// taken before the sample goes back.
    pub(super) fn keep_for_output(&mut self, received: &Received<ParticleState>, output: bool) {
        if self.units == Units::SI && output {
            self.states.clear();
            self.states.extend_from_slice(received.particles());
        }
    }
}
