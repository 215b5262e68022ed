//! What a coupled run counts: the steps it completed, the particle steps, and where its wall time
//! went (summary.json's `time_s`), each part of the lockstep loop timed as a lap of one clock.

use serde::Serialize;
use std::time::Instant;

/// The counters of a coupled run.
pub(super) struct Counters {
    /// The last step whose reply was sent.
    pub(super) last_completed: Option<u64>,
    /// Particles x steps completed.
    pub(super) particle_steps: u64,
    /// The wall time's start: the session's, then the lockstep loop's.
    started: Instant,
    /// The end of the last lap.
    lap: Instant,
    /// The laps so far, by part (`other` is the rest of the wall time, made by `time_split`).
    time: TimeSplit,
}

impl Counters {
    pub(super) fn new() -> Self {
        let now = Instant::now();
        Self {
            last_completed: None,
            particle_steps: 0,
            started: now,
            lap: now,
            time: TimeSplit::default(),
        }
    }

    /// The lockstep loop starts: the wall time and the first lap from now.
    pub(super) fn start(&mut self) {
        self.started = Instant::now();
        self.lap = Instant::now();
    }

    /// Step `step` completed, with `count` particles.
    pub(super) fn completed(&mut self, step: u64, count: usize) {
        self.last_completed = Some(step);
        self.particle_steps += count as u64;
    }

    /// The steps completed.
    pub(super) fn steps_completed(&self) -> u64 {
        self.last_completed.map_or(0, |s| s + 1)
    }

    /// The last completed step, as error messages name it.
    pub(super) fn last_completed_text(&self) -> String {
        self.last_completed.map_or("none".to_string(), |s| s.to_string())
    }

    /// The time since the last lap went to waiting for the DEM.
    pub(super) fn lap_waiting_for_dem(&mut self) {
        self.time.waiting_for_dem += self.lap();
    }

    /// The time since the last lap went to the fluid's step.
    pub(super) fn lap_fluid(&mut self) {
        self.time.fluid += self.lap();
    }

    /// The time since the last lap went to the exchange of states and replies.
    pub(super) fn lap_exchange(&mut self) {
        self.time.exchange += self.lap();
    }

    /// The time since the last lap went to the output.
    pub(super) fn lap_output(&mut self) {
        self.time.output += self.lap();
    }

    /// Seconds since the last lap, which ends now.
    fn lap(&mut self) -> f64 {
        let now = Instant::now();
        let lap = now.duration_since(self.lap).as_secs_f64();
        self.lap = now;
        lap
    }

    /// The wall time so far [s].
    pub(super) fn wall(&self) -> f64 {
        self.started.elapsed().as_secs_f64()
    }

    /// Where `wall` seconds went: the laps, and the rest as `other`.
    pub(super) fn time_split(&self, wall: f64) -> TimeSplit {
        let t = self.time;
        let other = wall - (t.waiting_for_dem + t.fluid + t.exchange + t.output);
        TimeSplit {
            other: other.max(0.0),
            ..t
        }
    }
}

/// Where a coupled run's wall time went, in seconds (summary.json `time_s`). The lockstep runs the
/// two processes in turn, so these add up to the wall time less the start and the end (`other`).
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct TimeSplit {
    /// Waiting for the DEM's states of each step: the DEM's own step (its sub-steps, contacts and
    /// output) and the states crossing over.
    pub waiting_for_dem: f64,
    /// The fluid's step with the particles: the host's passes over them, the GPU's kernels, the
    /// loads read back, the health checks.
    pub fluid: f64,
    /// The states read and converted (their check is the fluid's part), and the replies converted
    /// and sent.
    pub exchange: f64,
    /// particles.csv (and the .vtp series), and the progress line.
    pub output: f64,
    /// The rest of the wall time: the loop's start and end, the DEM process's exit.
    pub other: f64,
}

impl TimeSplit {
    /// The split line of a run's last message: each part's share of `wall` seconds.
    pub fn describe(&self, wall: f64) -> String {
        let share = |t: f64| 100.0 * t / wall.max(1e-9);
        format!(
            "fluid {:.0}%, waiting for the DEM {:.0}%, exchange {:.0}%, output {:.0}%, other {:.0}%",
            share(self.fluid),
            share(self.waiting_for_dem),
            share(self.exchange),
            share(self.output),
            share(self.other)
        )
    }
}
