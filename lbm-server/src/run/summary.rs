//! OUT/summary.json of a coupled run: what ran, how far, how fast, where the wall time went, and
//! how it ended.

use super::counters::TimeSplit;
use super::session::Session;
use crate::output::LatticeSummary;
use crate::parallel::ParallelSummary;
use protocol::Physics;
use serde::Serialize;
use std::path::Path;

/// The DEM side, as it introduced itself.
#[derive(Debug, Clone, Serialize)]
pub(super) struct PeerInfo {
    pub software: String,
    pub pid: u64,
    pub protocol_version: u32,
    pub physics: Vec<&'static str>,
}

/// OUT/summary.json.
#[derive(Debug, Clone, Serialize)]
pub(super) struct Summary {
    /// The fluid program and its version.
    pub software: String,
    /// When the summary was written, seconds since 1970-01-01 UTC.
    pub written_unix_s: u64,
    pub scene: String,
    pub scene_file: String,
    pub run: String,
    pub steps_requested: u64,
    pub steps_completed: u64,
    pub last_completed_step: Option<u64>,
    pub particles_initial: u64,
    pub wall_time_s: f64,
    /// Where the wall time went.
    pub time_s: TimeSplit,
    /// Lattice cell updates per second of the fluid's own step, in millions (cells x steps / the
    /// `fluid` part of `time_s`): the coupled fluid's speed inside the whole program.
    pub fluid_mlups: f64,
    pub steps_per_second: f64,
    pub particle_steps_per_second: f64,
    pub fluid_physics: Vec<&'static str>,
    /// Where the covered cells took their solid term ("redo", "skip" or "fused"; with
    /// `coupling.covered_cells = "auto"`, the way the start-up trial kept).
    pub covered_cells: &'static str,
    /// The fluid kernels ("quads" or "cells"; with `lattice.kernel = "auto"`, those the start-up
    /// trial kept).
    pub kernel: &'static str,
    /// What the start-up trial measured and kept, a line per stage (empty where it did not run).
    pub trial: Vec<String>,
    /// The fluid's discretisation.
    pub lattice: LatticeSummary,
    pub peer: Option<PeerInfo>,
    /// The ranks the lattice was cut over (one on a single process), their blocks and devices.
    pub parallel: ParallelSummary,
    /// "completed" (exit 0), "interrupted" (Ctrl-C or SIGTERM, exit 130), "stopped by the DEM
    /// client" (its STOP before the last step, exit 130), or "error: ..." (exit 1)
    pub exit_reason: String,
    pub exit_code: u8,
}

impl Summary {
    pub(super) fn write(&self, path: &Path) -> std::io::Result<()> {
        let text = serde_json::to_string_pretty(self).map_err(std::io::Error::other)?;
        std::fs::write(path, text + "\n")
    }
}

impl Session {
    /// The summary of the run so far, ended for `exit_reason` with `exit_code`.
    pub(super) fn summary(&self, exit_reason: String, exit_code: u8, parallel: ParallelSummary) -> Summary {
        let c = &self.counters;
        let wall = c.wall();
        let steps_completed = c.steps_completed();
        let time_s = c.time_split(wall);
        let cells: usize = self.fluid.units().n.iter().product();
        Summary {
            software: crate::output::software(),
            written_unix_s: crate::output::unix_seconds(),
            scene: self.p.scene.name.clone(),
            scene_file: self.p.scene_file.clone(),
            run: self.link.run().to_string(),
            steps_requested: self.p.steps,
            steps_completed,
            last_completed_step: c.last_completed,
            particles_initial: self.hello.map_or(0, |h| h.initial_count),
            wall_time_s: wall,
            time_s,
            fluid_mlups: cells as f64 * steps_completed as f64 / time_s.fluid.max(1e-9) / 1e6,
            steps_per_second: steps_completed as f64 / wall.max(1e-9),
            particle_steps_per_second: c.particle_steps as f64 / wall.max(1e-9),
            fluid_physics: Physics::names(self.fluid.physics()),
            covered_cells: self.fluid.covered_cells().name(),
            kernel: self.fluid.kernel().name(),
            trial: self.fluid.trial_lines().to_vec(),
            lattice: LatticeSummary::of(self.fluid.units()),
            peer: self.peer.clone(),
            parallel,
            exit_reason,
            exit_code,
        }
    }
}
