//! A coupled run's checkpoints (docs/checkpoint.md, PROTOCOL.md 6.4): the reply of step n carries
//! CHECKPOINT where one is due after it; the DEM writes its state for step n + 1 into the staging
//! folder, ends it with the marker file `dem.complete`, and sends states(n + 1); the fluid's own
//! state, taken after step n, is held until then and handed to the writer. At the run's end (its
//! last step, Ctrl-C, the DEM's STOP) no states follow: the fluid waits for the marker.

use super::ending::StepEnd;
use super::session::Session;
use super::EXIT_BAD_INPUT;
use crate::checkpoint::Loaded;
use crate::checkpoint::OutputPositions;
use protocol::handshake::Status;
use protocol::{Capabilities, Hello, Welcome};
use scene::checkpoint::{DEM_COMPLETE, DIR, STAGING};
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
    /// Hello) gets none, with a warning (a resumed run refuses it in its Welcome:
    /// [`resume_refusal`]).
    pub(super) fn dem_checkpoints(&self, hello: &Hello) -> bool {
        let can = can_checkpoint(hello);
        let software = protocol::handshake::field_text(&hello.software);
        if self.checkpoints.enabled() && !can {
            protocol::say!(
                "lbm-server: warning: the DEM ({software}) cannot checkpoint (no CHECKPOINT \
                 capability in its Hello): this run writes no checkpoints"
            );
        }
        can && self.checkpoints.enabled()
    }

    /// A resumed run goes on with this DEM: the outputs are cut back to where its checkpoint
    /// found them (until now OUT is as the earlier run left it).
    pub(super) fn cut_back_outputs(&self) -> Result<(), String> {
        match &self.p.resumed {
            Some(loaded) => scene::checkpoint::cut_back(&self.p.out, &loaded.header.outputs),
            None => Ok(()),
        }
    }

    /// A resumed run refused the DEM in its Welcome (`resume_refusal`): the DEM and the other
    /// ranks ended, `why` said, nothing in OUT written (not even summary.json); exit 2.
    pub(super) fn refuse_resume(mut self, why: &str) -> u8 {
        self.end_dem(true);
        self.fluid.end_ranks(EXIT_BAD_INPUT, 0.0);
        protocol::say!("lbm-server: error: {why}");
        protocol::say!(
            "lbm-server: nothing in {} was changed; its checkpoint needs a DEM that can \
             checkpoint (dem-client, or a DEM that declares CHECKPOINT: PROTOCOL.md 6.4)",
            self.p.out.display()
        );
        EXIT_BAD_INPUT
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

    /// A run that failed while a checkpoint was held for the DEM's part (the DEM died or fell
    /// silent after the reply that asked for it): where the DEM completed its part first, both
    /// halves are of one step and the checkpoint goes to the writer (the state is still good);
    /// else the one before stays.
    pub(super) fn keep_held_checkpoint(&mut self) {
        let marker = self.p.out.join(STAGING).join(DEM_COMPLETE);
        if self.checkpoints.holding() && marker.is_file() {
            self.checkpoints.release();
        }
    }

    /// What a run that did not complete leaves to resume from (once the checkpoint being written
    /// is done): the last complete checkpoint, or none.
    pub(super) fn say_resumable(&self) {
        if !self.checkpoints.enabled() {
            return;
        }
        let out = self.p.out.display();
        match self.checkpoints.last_complete() {
            Some(step) => protocol::say!(
                "lbm-server: the last complete checkpoint, at step {step}, is in {out}/{DIR}: \
                 `lbm-server run --resume {out}` goes on from it"
            ),
            None => protocol::say!(
                "lbm-server: no checkpoint was completed: the run cannot be resumed (a new run \
                 starts from step 0)"
            ),
        }
    }
}

/// Whether the DEM of `hello` writes and reads checkpoints (the CHECKPOINT capability).
fn can_checkpoint(hello: &Hello) -> bool {
    hello.version >= 2 && hello.capabilities & Capabilities::CHECKPOINT != 0
}

/// The Welcome of a run resumed from `resumed` to a DEM that cannot checkpoint: a refusal
/// (`CANNOT_RESUME`, its reason short enough for the field), and why in full; None where the run
/// may go on with it.
pub(super) fn resume_refusal(resumed: Option<&Loaded>, hello: &Hello) -> Option<(Welcome, String)> {
    let loaded = resumed.filter(|_| !can_checkpoint(hello))?;
    let software = protocol::handshake::field_text(&hello.software);
    let why = format!(
        "cannot resume from {}: the DEM ({software}, protocol version {}) does not declare the \
         CHECKPOINT capability in its Hello, so it cannot go on from a checkpoint",
        loaded.dir.display(),
        hello.version
    );
    let ours = format!("lbm-server {}", env!("CARGO_PKG_VERSION"));
    let reason = "the run resumes from a checkpoint; this DEM does not declare CHECKPOINT (6.4)";
    Some((Welcome::refused(&ours, Status::CannotResume, reason), why))
}
