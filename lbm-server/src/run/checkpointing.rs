//! A coupled run's checkpoints (docs/checkpoint.md, PROTOCOL.md 6.4): the reply of step n carries
//! CHECKPOINT where one is due after it; the DEM writes its state for step n + 1 into the staging
//! folder, ends it with the marker file `dem.complete`, and sends states(n + 1); the fluid's own
//! state, taken after step n, is held until then and handed to the writer. At the run's end (its
//! last step, Ctrl-C, the DEM's STOP) no states follow: the fluid waits for the marker.

use super::ending::StepEnd;
use super::session::Session;
use crate::checkpoint::OutputPositions;
use protocol::{Capabilities, Hello};
use scene::checkpoint::{DEM_COMPLETE, STAGING};
use std::path::PathBuf;
use std::time::{Duration, Instant};

impl Session {
    /// The checkpoint folders for a DEM the run starts, in its environment: where it writes its
    /// part, and the checkpoint a resumed run goes on from.
    pub(super) fn checkpoint_env(&self) -> Result<Vec<(&'static str, PathBuf)>, String> {
        let abs = |p: PathBuf| std::path::absolute(&p).map_err(|e| format!("{}: {e}", p.display()));
        let mut env = vec![(crate::launch::CHECKPOINT_DIR_ENV, abs(self.p.out.join(STAGING))?)];
        if let Some(loaded) = &self.p.resumed {
            env.push((crate::launch::RESUME_DIR_ENV, abs(loaded.dir.clone())?));
        }
        Ok(env)
    }

    /// Whether the run writes checkpoints with this DEM: one that cannot (no CHECKPOINT in its
    /// Hello) gets none, with a warning, and cannot resume a run.
    pub(super) fn dem_checkpoints(&self, hello: &Hello) -> Result<bool, String> {
        let can = hello.version >= 2 && hello.capabilities & Capabilities::CHECKPOINT != 0;
        let software = protocol::handshake::field_text(&hello.software);
        if let Some(loaded) = self.p.resumed.as_ref().filter(|_| !can) {
            return Err(format!(
                "cannot resume from {}: the DEM ({software}, protocol version {}) does not declare \
                 the CHECKPOINT capability in its Hello, so it cannot go on from a checkpoint",
                loaded.dir.display(),
                hello.version
            ));
        }
        if let Some(loaded) = &self.p.resumed {
            if !loaded.header.files.iter().any(|f| f.file == DEM_COMPLETE) {
                return Err(format!(
                    "cannot resume from {}: it holds no DEM state",
                    loaded.dir.display()
                ));
            }
        }
        if self.checkpoints.enabled() && !can {
            protocol::say!(
                "lbm-server: warning: the DEM ({software}) cannot checkpoint (no CHECKPOINT \
                 capability in its Hello): this run writes no checkpoints"
            );
        }
        Ok(can && self.checkpoints.enabled())
    }

    /// Whether the reply of `step` asks for a checkpoint: one due after it, or the run ends
    /// there (its last step, a stop); none where the step failed.
    pub(super) fn checkpoint_due(&self, step: u64, last: bool, end: &StepEnd) -> bool {
        let due = last || end.stop || self.checkpoints.schedule.due(step + 1);
        self.checkpointing && end.failure.is_none() && due
    }

    /// Before the reply that asks for it: an empty staging folder for the DEM's part.
    pub(super) fn stage_checkpoint(&mut self) -> Result<(), String> {
        self.checkpoints.stage().map(|_| ())
    }

    /// After the particles of the step are written: the fluid's state taken and held for the DEM's
    /// part, the outputs standing `at` (particles.csv's) and as the fluid's stand.
    pub(super) fn hold_checkpoint(&mut self, mut at: OutputPositions, particles: u64) -> Result<(), String> {
        self.fluid.positions(&mut at)?;
        self.fluid.checkpoint(&mut self.checkpoints, at, particles);
        Ok(())
    }

    /// The DEM's states of the next step arrived: its part is complete, the checkpoint goes to
    /// the writer.
    pub(super) fn release_checkpoint(&mut self) -> Result<(), String> {
        let marker = self.p.out.join(STAGING).join(DEM_COMPLETE);
        if !marker.is_file() {
            return Err(format!(
                "the DEM sent the states after a CHECKPOINT reply without completing its part ({} missing)",
                marker.display()
            ));
        }
        self.checkpoints.release();
        Ok(())
    }

    /// At the run's end: waits (up to `coupling.timeout`) for the DEM's part of the checkpoint
    /// held, then hands it to the writer; a DEM that does not complete it leaves the previous
    /// checkpoint in place, with a warning.
    pub(super) fn finish_checkpoint(&mut self) {
        if !self.checkpoints.holding() {
            return;
        }
        let marker = self.p.out.join(STAGING).join(DEM_COMPLETE);
        let started = Instant::now();
        let timeout = Duration::from_secs_f64(self.p.scene.coupling.timeout);
        while !marker.is_file() && started.elapsed() < timeout && !self.dem_exited() {
            std::thread::sleep(Duration::from_millis(2));
        }
        if marker.is_file() {
            self.checkpoints.release();
        } else {
            protocol::say!(
                "lbm-server: warning: the DEM did not complete its part of the last checkpoint; \
                 the one before stays in place"
            );
        }
    }
}
