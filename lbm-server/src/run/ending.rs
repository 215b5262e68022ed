//! How a coupled step ends the run, if it does: in failure, or stopped (the DEM's STOP, Ctrl-C),
//! and whether its particles are written.

use super::session::Session;
use super::Ending;
use crate::terminal::Progress;
use protocol::{StepFlags, StepHeader};
use std::sync::atomic::Ordering;

impl Session {
    /// How a step ends: in failure (the fluid's answer), stopped (the DEM's STOP, Ctrl-C or the
    /// failure), and whether it gets its particles written (every `output.interval` steps, the last
    /// and a stopped one; not one that ends in failure: its loads are the zeros of the STOP reply,
    /// and the error names what went wrong).
    pub(super) fn step_end(
        &self,
        step: u64,
        last: bool,
        header: StepHeader,
        failure: Option<String>,
    ) -> StepEnd {
        let stop =
            header.has(StepFlags::STOP) || self.interrupted.load(Ordering::SeqCst) || failure.is_some();
        let output = (step % self.p.scene.output.interval == 0 || last || stop) && failure.is_none();
        StepEnd {
            failure,
            stop,
            output,
        }
    }

    /// The run's end where this step ends it: its failure, or, stopped, how it ended.
    pub(super) fn end_at(
        &mut self,
        end: StepEnd,
        last: bool,
        progress: &Progress,
    ) -> Result<Option<Ending>, String> {
        if let Some(why) = end.failure {
            return Err(why);
        }
        if !end.stop {
            return Ok(None);
        }
        if last {
            progress.finish();
        } else {
            progress.abandon();
        }
        self.end_early(last).map(Some)
    }

    /// A run stopped by Ctrl-C or the DEM's STOP: the field outputs of the step it stopped at
    /// (unless it was the last, which wrote them), and how it ended (stopped at the last step, it
    /// completed).
    fn end_early(&mut self, last: bool) -> Result<Ending, String> {
        if !last {
            self.fluid
                .write_fields_of_early_end()
                .map_err(|e| self.describe_fluid(e))?;
        }
        // Ctrl-C on a terminal reaches both processes: our own interrupt takes precedence. The
        // DEM's STOP on the last step ends nothing early.
        Ok(if self.interrupted.load(Ordering::SeqCst) {
            Ending::Interrupted
        } else if last {
            Ending::Completed
        } else {
            Ending::StoppedByPeer
        })
    }
}

/// How a step ends (`Session::step_end`).
pub(super) struct StepEnd {
    /// Why the run fails at this step.
    pub(super) failure: Option<String>,
    /// Whether its reply carries STOP.
    pub(super) stop: bool,
    /// Whether its particles are written.
    pub(super) output: bool,
}

impl StepEnd {
    /// The flags of the step's reply: FINAL after the `last` step, STOP where it stops.
    pub(super) fn flags(&self, last: bool) -> u64 {
        let end = if last { StepFlags::FINAL } else { 0 };
        end | if self.stop { StepFlags::STOP } else { 0 }
    }
}
