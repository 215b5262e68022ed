//! The lockstep loop of a coupled run: the DEM's states of step n in, the fluid's loads of step n
//! out. Each step is a list of named passes (`Session::coupled_step`), each timed in the run's
//! counters (`counters.rs`): receive the states (waiting for the DEM), read them in SI
//! (exchange), answer them (fluid: the states checked, the fluid's step, its health check,
//! `answer.rs`), see how the step ends, send the reply (exchange), write the particles (output),
//! and end the run where the step ends it.

use super::session::Session;
use super::Ending;
use crate::output::Progress;
use protocol::transport::Received;
use protocol::{ParticleReply, ParticleState, StepFlags, StepHeader, Units};
use std::sync::atomic::Ordering;

impl Session {
    /// The lockstep loop: states(n) in, forces(n) out, until the last step or a step that ends
    /// the run.
    pub(super) fn step_loop(&mut self) -> Result<Ending, String> {
        let mut si = SiStates::new(self.hello.expect("connected").units);
        let mut replies = Vec::new();
        let mut progress = Progress::new(self.p.steps);
        self.counters.start();
        for step in 0..self.p.steps {
            if let Some(ending) = self.coupled_step(step, &mut si, &mut replies, &mut progress)? {
                return Ok(ending);
            }
        }
        progress.finish();
        Ok(Ending::Completed)
    }

    /// One coupled step, pass by pass: how the run ends where this step ends it.
    fn coupled_step(
        &mut self,
        step: u64,
        si: &mut SiStates,
        replies: &mut Vec<ParticleReply>,
        progress: &mut Progress,
    ) -> Result<Option<Ending>, String> {
        let last = step + 1 == self.p.steps;
        let received = self.receive_states(step)?;
        self.counters.lap_waiting_for_dem();
        let states = si.read(&received);
        self.counters.lap_exchange();
        let failure = self.answer(states, step, last, replies);
        self.counters.lap_fluid();
        let count = states.len();
        let header = received.header();
        let end = self.step_end(step, last, header, failure);
        si.keep_for_output(&received, end.output);
        drop(received);
        let reply = StepHeader::new(step, header.time, count, end.flags(last));
        self.reply(reply, si.units, replies)?;
        self.counters.completed(step, count);
        self.counters.lap_exchange();
        if end.output {
            self.write_particles(step, header.time * si.units.time_s, &si.states, replies)?;
        }
        progress.update(step + 1);
        self.counters.lap_output();
        self.end_at(end, last, progress)
    }

    /// Waits for the DEM's states of `step`.
    fn receive_states(&self, step: u64) -> Result<Received<ParticleState>, String> {
        self.link.receive_states(step).map_err(|e| self.describe(e))
    }

    /// How a step ends: in failure (the fluid's answer), stopped (the DEM's STOP, Ctrl-C or the
    /// failure), and whether it gets its particles written (every `output.interval` steps, the last
    /// and a stopped one; not one that ends in failure: its loads are the zeros of the STOP reply,
    /// and the error names what went wrong).
    fn step_end(&self, step: u64, last: bool, header: StepHeader, failure: Option<String>) -> StepEnd {
        let stop =
            header.has(StepFlags::STOP) || self.interrupted.load(Ordering::SeqCst) || failure.is_some();
        let output = (step % self.p.scene.output.interval == 0 || last || stop) && failure.is_none();
        StepEnd {
            failure,
            stop,
            output,
        }
    }

    /// Sends the fluid's `replies` (SI) to the DEM in its `units`; a reply that carries FINAL or
    /// STOP tells the DEM to end.
    fn reply(&mut self, header: StepHeader, units: Units, replies: &[ParticleReply]) -> Result<(), String> {
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

    /// The particles of `step` (SI) into particles.csv (and the .vtp series).
    fn write_particles(
        &mut self,
        step: u64,
        time: f64,
        states: &[ParticleState],
        replies: &[ParticleReply],
    ) -> Result<(), String> {
        self.particles.write_step(step, time, states, replies)
    }

    /// The run's end where this step ends it: its failure, or, stopped, how it ended.
    fn end_at(&mut self, end: StepEnd, last: bool, progress: &Progress) -> Result<Option<Ending>, String> {
        if let Some(why) = end.failure {
            return Err(why);
        }
        if !end.stop {
            return Ok(None);
        }
        progress.finish();
        self.end_early(last).map(Some)
    }

    /// A run stopped by Ctrl-C or the DEM's STOP: the field outputs of the step it stopped at
    /// (unless it was the last, which wrote them), and how it ended.
    fn end_early(&mut self, last: bool) -> Result<Ending, String> {
        if !last {
            self.fluid
                .write_fields_of_early_end()
                .map_err(|e| self.describe_fluid(e))?;
        }
        // Ctrl-C on a terminal reaches both processes: our own interrupt takes precedence.
        Ok(if self.interrupted.load(Ordering::SeqCst) {
            Ending::Interrupted
        } else {
            Ending::StoppedByPeer
        })
    }
}

/// How a step ends (`Session::step_end`).
struct StepEnd {
    /// Why the run fails at this step.
    failure: Option<String>,
    /// Whether its reply carries STOP.
    stop: bool,
    /// Whether its particles are written.
    output: bool,
}

impl StepEnd {
    /// The flags of the step's reply: FINAL after the `last` step, STOP where it stops.
    fn flags(&self, last: bool) -> u64 {
        let end = if last { StepFlags::FINAL } else { 0 };
        end | if self.stop { StepFlags::STOP } else { 0 }
    }
}

/// The DEM's states of a step in SI, for the fluid and particles.csv. A DEM that speaks SI: its
/// states are read where it wrote them (the shared memory, no copy) and copied only for
/// particles.csv, after the reply (the DEM loans the next sample once it has the forces); other
/// units are converted here, and the replies back where they are sent.
struct SiStates {
    /// The DEM's units.
    units: Units,
    /// The states in SI: converted (units not SI), or copied for particles.csv (SI).
    states: Vec<ParticleState>,
}

impl SiStates {
    fn new(units: Units) -> Self {
        Self {
            units,
            states: Vec::new(),
        }
    }

    /// The states of `received` in SI.
    fn read<'a>(&'a mut self, received: &'a Received<ParticleState>) -> &'a [ParticleState] {
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
    fn keep_for_output(&mut self, received: &Received<ParticleState>, output: bool) {
        if self.units == Units::SI && output {
            self.states.clear();
            self.states.extend_from_slice(received.particles());
        }
    }
}
