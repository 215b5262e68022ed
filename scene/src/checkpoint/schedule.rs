//! When a run writes a checkpoint: every `output.checkpoint_interval` steps (or
//! `--checkpoint-interval`), every `output.checkpoint_wall_interval` minutes of wall time, and,
//! where either is set, at the run's end and on Ctrl-C.

use crate::Scene;
use std::time::{Duration, Instant};

/// The checkpoints of a run.
pub struct Schedule {
    /// Steps between two (0: none by steps).
    every: u64,
    /// Wall time between two (None: none by the clock).
    wall: Option<Duration>,
    /// When the last was written (or the run started).
    last: Instant,
}

impl Schedule {
    /// The scene's checkpoints, its step interval replaced by `steps` where given.
    pub fn new(scene: &Scene, steps: Option<u64>) -> Self {
        let minutes = scene.output.checkpoint_wall_interval;
        Self {
            every: steps.unwrap_or(scene.output.checkpoint_interval),
            wall: minutes.map(|m| Duration::from_secs_f64(m * 60.0)),
            last: Instant::now(),
        }
    }

    /// Whether the run writes checkpoints at all (then also at its end and on Ctrl-C).
    pub fn enabled(&self) -> bool {
        self.every > 0 || self.wall.is_some()
    }

    /// Whether one is due once `step` steps are completed.
    pub fn due(&self, step: u64) -> bool {
        let by_steps = self.every > 0 && step.is_multiple_of(self.every);
        by_steps || self.wall.is_some_and(|w| self.last.elapsed() >= w)
    }

    /// Whether one is due by the wall clock (`output.checkpoint_wall_interval`).
    pub fn by_wall_clock(&self) -> bool {
        self.wall.is_some()
    }

    /// The step interval (0: none), for the fluid's chunks of steps.
    pub fn every(&self) -> u64 {
        self.every
    }

    /// One was written now: the wall clock's interval starts again.
    pub fn written(&mut self) {
        self.last = Instant::now();
    }
}
