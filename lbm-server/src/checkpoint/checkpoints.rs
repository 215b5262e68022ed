//! A run's checkpoints ([`Checkpoints`]): when they are due, the header each gets, the lattice's
//! state taken off the device and handed to the writer, and the checkpoint a resumed run started
//! from.

use super::read::Loaded;
use super::write::{Snapshot, Writer};
use crate::parallel::{BlockLattice, Communicator};
use scene::checkpoint::{Header, OutputPositions, Schedule, FORMAT, VERSION};
use std::path::{Path, PathBuf};

/// The checkpoints of one run.
pub struct Checkpoints {
    pub schedule: Schedule,
    writer: Writer,
    scene_hash: String,
    /// `--checkpoint-interval`, given to this run or to the one it resumed.
    given: Option<u64>,
    /// The checkpoint this run resumed from.
    pub resumed: Option<Loaded>,
    /// A checkpoint taken and waiting for the DEM's part (`hold`).
    held: Option<Snapshot>,
}

impl Checkpoints {
    /// The checkpoints of a run of `scene` (its file's text `scene_text`) into `out`, every
    /// `steps` where given (`--checkpoint-interval`; resumed from `resumed` without it, the
    /// interval the first run was given), resumed from `resumed`.
    pub fn new(
        out: &Path,
        scene: &scene::Scene,
        scene_text: &str,
        steps: Option<u64>,
        resumed: Option<Loaded>,
    ) -> Self {
        let given = steps.or(resumed.as_ref().and_then(|l| l.header.checkpoint_interval));
        Self {
            schedule: Schedule::new(scene, given),
            given,
            writer: Writer::new(out),
            scene_hash: scene::checkpoint::scene_hash(scene_text),
            resumed,
            held: None,
        }
    }

    /// `--checkpoint-interval`, given to this run or to the one it resumed.
    pub fn given(&self) -> Option<u64> {
        self.given
    }

    /// Whether the run writes checkpoints.
    pub fn enabled(&self) -> bool {
        self.schedule.enabled()
    }

    /// An empty staging folder for the next checkpoint (once the one being written is done).
    pub fn stage(&mut self) -> Result<PathBuf, String> {
        self.writer.stage()
    }

    /// Whether a checkpoint is held for the DEM's part.
    pub fn holding(&self) -> bool {
        self.held.is_some()
    }

    /// Hands the checkpoint held to the writer (the DEM's part, where it has one, is complete).
    pub fn release(&mut self) {
        if let Some(snapshot) = self.held.take() {
            self.writer.commit(snapshot);
        }
    }

    /// The lattice's state, copied off every rank's device and put together at rank 0
    /// (`BlockLattice::whole_state`), and its header (`particles` at simulated time `time_s`, the
    /// outputs standing `at`), held at rank 0 until the DEM's part is complete (`release` hands
    /// them to the writer, which writes them into the staging folder on a thread). Every rank
    /// takes part.
    pub fn hold(
        &mut self,
        (lattice, comm): (&BlockLattice, &dyn Communicator),
        time_s: f64,
        particles: u64,
        at: OutputPositions,
        covered_cells: Option<String>,
    ) {
        let started = std::time::Instant::now();
        let whole = lattice.whole_state(comm);
        let readback_s = started.elapsed().as_secs_f64();
        self.schedule.written();
        let Some(state) = whole else {
            return;
        };
        let header = Header {
            format: FORMAT.into(),
            version: VERSION,
            scene_hash: self.scene_hash.clone(),
            lattice: lattice.decomposition.n,
            storage: lattice.lattice.storage().name().into(),
            step: state.time,
            time_s,
            particles,
            aa_phase: state.time % 2,
            face_scale: state.face_scale,
            covered_cells,
            checkpoint_interval: self.given,
            outputs: at,
            files: Vec::new(),
        };
        self.held = Some(Snapshot {
            header,
            state,
            readback_s,
        });
    }

    /// Waits for the checkpoint being written.
    pub fn wait(&mut self) -> Result<(), String> {
        self.writer.wait()
    }

    /// The step of the last complete checkpoint in the output folder, once the one being written
    /// is done (`wait`): this run's last, else the one it resumed from.
    pub fn last_complete(&self) -> Option<u64> {
        let resumed = self.resumed.as_ref().map(|l| l.header.step);
        self.writer.last.or(resumed)
    }
}
