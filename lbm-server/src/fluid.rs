//! A fluid-only scene (a `[lattice]` and no particles): the GPU lattice alone, with health checks,
//! VTK snapshots, probe lines and a summary.

use crate::checkpoint::{Checkpoints, OutputPositions};
use crate::fields::{probe_cells, FieldOutput};
use crate::lbm::geometry::Setup;
use crate::lbm::gpu::{Gpu, GpuLattice};
use crate::output::LatticeSummary;
use crate::parallel::{
    all, checkpoint_due, rank0s, resume_blocks, write_last_good_of_ranks, write_snapshot_of_ranks,
    BlockLattice, Communicator, Decomposition, FieldPieces, ParallelSummary, RankUnhealthy,
};
use crate::terminal::Progress;
use crate::trials::{kernels_of, Trial};
use scene::lattice::LatticeUnits;
use scene::Scene;
use serde::Serialize;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

mod setup;
pub use setup::{health_of, setup_of, stability_warning};

#[derive(Debug, Serialize)]
struct FluidSummary {
    software: String,
    written_unix_s: u64,
    scene: String,
    scene_file: String,
    adapter: String,
    lattice: LatticeSummary,
    parallel: ParallelSummary,
    steps_requested: u64,
    steps_completed: u64,
    wall_time_s: f64,
    mlups: f64,
    /// The fluid kernels ("quads" or "cells"; with `lattice.kernel = "auto"`, those the start-up
    /// trial kept) and what the trial measured (empty where it did not run).
    kernel: &'static str,
    trial: Vec<String>,
    exit_reason: String,
    exit_code: u8,
}

/// What stopped a run early.
enum Stop {
    Interrupted,
    Failed(String),
}

/// Runs a fluid-only scene on the ranks of `comm`, cut into `blocks` (from its checkpoint where
/// `checkpoints` resumes one); returns the exit code (the same on every rank). Rank 0 writes the
/// outputs and says how the run went.
pub fn run(
    scene: &Scene,
    scene_file: &str,
    steps: u64,
    out: &Path,
    interrupted: Arc<AtomicBool>,
    comm: &dyn Communicator,
    blocks: [usize; 3],
    mut checkpoints: Checkpoints,
) -> u8 {
    let units = scene.lattice_units.as_ref().expect("fluid scenes have a lattice");
    let root = comm.rank() == 0;
    let Some((gpu, mut lattice, trial)) = open(scene, steps, (comm, blocks), &checkpoints) else {
        return 1;
    };
    let started = Instant::now();
    let from = lattice.time();
    let at = checkpoints.resumed.as_ref().map(|l| l.header.outputs.clone());
    let run = FluidRun::new(
        scene,
        units,
        out,
        (comm, &lattice.decomposition),
        trial.clone(),
        at.as_ref(),
        &mut checkpoints,
    );
    let (result, trial) = match run {
        Ok(mut run) => (run.steps(&mut lattice, steps, &interrupted), run.trial),
        Err(e) => (Err(e), trial),
    };
    let result = checkpoints_written(result, &mut checkpoints);
    let wall = started.elapsed().as_secs_f64();
    let (reason, code) = match &result {
        Ok(()) => ("completed".to_string(), 0),
        Err(Stop::Interrupted) => ("interrupted".to_string(), 130),
        Err(Stop::Failed(e)) => (format!("error: {e}"), 1),
    };
    let parallel = ParallelSummary::gather(comm, &lattice, &gpu.adapter.name, wall);
    let code = if root {
        let ended = Ended {
            from,
            result,
            reason,
            code,
            wall,
            steps,
            completed: lattice.time(),
            trial,
        };
        report(scene, scene_file, out, &gpu.adapter.name, parallel, ended)
    } else {
        code
    };
    // Every rank ends once rank 0 has said how the run went and written its summary: a launcher
    // ends the other ranks as soon as one exits with a code other than 0.
    comm.min(0);
    code
}

/// The run's kernels (a trial on one rank; on several every rank steps in lockstep: no trial, the
/// first kernels) and its lattice on this rank's device, in the state of the checkpoint it resumes
/// from where it does; None where any rank failed to start it (each says why).
fn open(
    scene: &Scene,
    steps: u64,
    (comm, blocks): (&dyn Communicator, [usize; 3]),
    checkpoints: &Checkpoints,
) -> Option<(Arc<Gpu>, BlockLattice, Trial)> {
    let units = scene.lattice_units.as_ref().expect("fluid scenes have a lattice");
    let mut trial = Trial::new(kernels_of(units.kernel), Vec::new(), steps);
    let started = start_lattice(scene, units, (comm, blocks), &mut trial);
    let say = |e: &str| {
        let rank = match comm.size() {
            1 => String::new(),
            _ => format!("rank {}: ", comm.rank()),
        };
        protocol::say!("lbm-server: error: {rank}{e}");
    };
    if !all(comm, started.is_ok()) {
        started.err().inspect(|e| say(e));
        return None;
    }
    let (gpu, mut lattice) = started.expect("started on every rank");
    trial.agree_open(comm);
    // Every rank, once all have made their block (rank 0 sends each its part).
    if let Err(e) = resume_blocks(&mut lattice, comm, checkpoints.resumed.as_ref()) {
        say(&e);
        return None;
    }
    Some((gpu, lattice, trial))
}

/// The steps' `result`, once the checkpoint being written is done (its failure the run's, where
/// the steps went well).
fn checkpoints_written(result: Result<(), Stop>, checkpoints: &mut Checkpoints) -> Result<(), Stop> {
    match result {
        Ok(()) => checkpoints.wait().map_err(Stop::Failed),
        Err(Stop::Interrupted) => {
            let _ = checkpoints.wait();
            Err(Stop::Interrupted)
        }
        failed => failed,
    }
}

/// How a fluid run ended (`from`: the step it started from).
struct Ended {
    from: u64,
    result: Result<(), Stop>,
    reason: String,
    code: u8,
    wall: f64,
    steps: u64,
    completed: u64,
    /// The start-up trial of the kernels: what it measured and kept.
    trial: Trial,
}

/// Rank 0 says how the run ended and writes summary.json; returns the exit code.
fn report(
    scene: &Scene,
    scene_file: &str,
    out: &Path,
    adapter: &str,
    parallel: ParallelSummary,
    e: Ended,
) -> u8 {
    let units = scene.lattice_units.as_ref().expect("fluid scenes have a lattice");
    match &e.result {
        Err(Stop::Failed(msg)) => protocol::say!("lbm-server: error: {msg}"),
        Err(Stop::Interrupted) => {
            protocol::say!(
                "lbm-server: interrupted after {} of {} steps",
                e.completed,
                e.steps
            )
        }
        Ok(()) => {}
    }
    let cells = units.n.iter().product::<usize>() as f64;
    let wall = e.wall;
    let summary = FluidSummary {
        software: crate::output::software(),
        written_unix_s: crate::output::unix_seconds(),
        scene: scene.name.clone(),
        scene_file: scene_file.to_string(),
        adapter: adapter.to_string(),
        lattice: LatticeSummary::of(units),
        parallel,
        steps_requested: e.steps,
        steps_completed: e.completed,
        wall_time_s: wall,
        mlups: cells * (e.completed - e.from) as f64 / wall.max(1e-9) / 1e6,
        kernel: e.trial.kept().kernel.name(),
        trial: e.trial.lines.clone(),
        exit_reason: e.reason,
        exit_code: e.code,
    };
    if let Err(err) = write_summary(&summary, out) {
        protocol::say!("lbm-server: error: summary.json: {err}");
        return 1;
    }
    if e.code == 0 {
        protocol::say!(
            "lbm-server: {} steps in {wall:.2} s ({:.2} MLUPS); output in {}",
            e.completed - e.from,
            summary.mlups,
            out.display()
        );
    }
    e.code
}

/// This rank's device and block of the scene's lattice on it, the run's first line said (by rank
/// 0) once it is ready to step (and a warning where its tau is near 1/2, or its storage was
/// measured to fail).
fn start_lattice(
    scene: &Scene,
    units: &LatticeUnits,
    (comm, blocks): (&dyn Communicator, [usize; 3]),
    trial: &mut Trial,
) -> Result<(Arc<Gpu>, BlockLattice), String> {
    let gpu = Arc::new(Gpu::for_local_rank(comm.local_rank())?);
    // On a CPU driver the kernels are not timed (coupled/ways.rs, `trial`).
    if gpu.on_cpu() {
        trial.pin_first();
    }
    let d = Decomposition::new(units.n, scene.periodic_axes(), blocks, comm.rank());
    let setup = Setup {
        kernel: trial.kept().kernel,
        ..setup_of(units)
    };
    let mut lattice = BlockLattice::new(gpu.clone(), setup, health_of(units), d)?;
    lattice.set_overlap_asked(scene.parallel.overlap);
    crate::run::started();
    if comm.rank() != 0 {
        return Ok((gpu, lattice));
    }
    let on = if comm.size() > 1 {
        format!(
            "{} ranks in {}x{}x{} blocks, rank 0 on {}",
            comm.size(),
            blocks[0],
            blocks[1],
            blocks[2],
            gpu.adapter.name
        )
    } else {
        gpu.adapter.name.clone()
    };
    protocol::say!(
        "lbm-server: scene '{}': {}x{}x{} cells, dx {:e} m, dt {:e} s, tau {:.4}, Mach {:.3}, {} on {on}, {}{}",
        scene.name,
        units.n[0],
        units.n[1],
        units.n[2],
        units.dx,
        units.dt,
        units.tau,
        units.mach,
        units.operator,
        lattice.lattice.kernel().describe(),
        match trial.open() {
            true => format!("; {}", trial.describe()),
            false => String::new(),
        }
    );
    let storage = crate::storage_accuracy::storage_warning(units);
    for warning in stability_warning(units, false).into_iter().chain(storage) {
        warning.say();
    }
    Ok((gpu, lattice))
}

/// summary.json in `out` (the run's other outputs are written before it).
fn write_summary(summary: &FluidSummary, out: &Path) -> std::io::Result<()> {
    let text = serde_json::to_string_pretty(summary).unwrap_or_default();
    std::fs::write(out.join("summary.json"), text + "\n")
}

/// The outputs of one fluid run: rank 0's probe lines, snapshots (on several ranks, each rank's
/// piece of them) and summary.
struct FluidRun<'a> {
    scene: &'a Scene,
    units: &'a LatticeUnits,
    comm: &'a dyn Communicator,
    /// Rank 0's outputs.
    fields: Option<FieldOutput>,
    /// On several ranks, every rank's pieces of the snapshots.
    pieces: Option<FieldPieces>,
    /// The probe lines' cells (indices of the whole lattice), on every rank.
    line_cells: Vec<usize>,
    checkpoints: &'a mut Checkpoints,
    /// The step of the last check that passed (its fields kept on the device).
    last_good: Option<u64>,
    /// The start-up trial of the kernels (trials.rs) and its clock.
    trial: Trial,
    made: Instant,
}

impl<'a> FluidRun<'a> {
    /// The outputs into `out` of the block `d` on the ranks of `comm`, resumed `at` a
    /// checkpoint's positions where given.
    fn new(
        scene: &'a Scene,
        units: &'a LatticeUnits,
        out: &'a Path,
        (comm, d): (&'a dyn Communicator, &Decomposition),
        trial: Trial,
        at: Option<&OutputPositions>,
        checkpoints: &'a mut Checkpoints,
    ) -> Result<Self, Stop> {
        let fields = if comm.rank() == 0 {
            FieldOutput::new(scene, units, out, at).map(Some)
        } else {
            Ok(None)
        };
        if !all(comm, fields.is_ok()) {
            return Err(Stop::Failed(
                fields.err().unwrap_or_else(|| "rank 0's outputs".into()),
            ));
        }
        let pieces =
            (comm.size() > 1).then(|| FieldPieces::new(scene, units, out.to_path_buf(), d, comm.rank()));
        Ok(Self {
            scene,
            units,
            comm,
            fields: fields.expect("checked"),
            pieces,
            line_cells: probe_cells(scene, units),
            checkpoints,
            last_good: None,
            trial,
            made: Instant::now(),
        })
    }

    /// While the trial is under way: the kernels of the step `lattice` takes next (the trial's;
    /// a run without particles has one way of the covered cells). Every rank's trial goes by
    /// rank 0's clock and the choices all ranks build, so that all step alike.
    fn take_kernel(&mut self, lattice: &mut GpuLattice) {
        let now = rank0s(self.comm, self.made.elapsed().as_secs_f64());
        self.trial
            .give_agreed_choice(lattice, lattice.time, now, self.comm);
    }

    fn steps(
        &mut self,
        lattice: &mut BlockLattice,
        steps: u64,
        interrupted: &AtomicBool,
    ) -> Result<(), Stop> {
        let check = self.units.check_interval;
        let every = [
            check,
            self.scene.output.interval,
            self.scene.output.fields_interval,
            self.checkpoints.schedule.every(),
        ];
        // Rank 0's progress alone.
        let mut progress = (self.comm.rank() == 0).then(|| Progress::new(steps));
        progress.iter_mut().for_each(|p| p.update(lattice.time()));
        while lattice.time() < steps {
            let now = lattice.time();
            // The trial times one step at a time (each followed by the health check's readback).
            let trial = self.trial.under_way();
            if trial {
                self.take_kernel(&mut lattice.lattice);
            }
            let next = every
                .iter()
                .filter(|e| **e > 0)
                .map(|e| (now / e + 1) * e)
                .chain([steps])
                .chain(trial.then_some(now + 1))
                .min()
                .expect("steps");
            lattice.step(next - now, self.comm);
            // Interrupted (Ctrl-C), the run ends here: this step gets a last step's outputs. The
            // ranks agree, so that all stop at the same step.
            let going = !interrupted.load(Ordering::SeqCst);
            let stopping = !all(self.comm, going);
            self.outputs(lattice, next, next == steps || stopping)?;
            progress.iter_mut().for_each(|p| p.update(next));
            if stopping {
                progress.iter().for_each(Progress::abandon);
                self.flush().map_err(Stop::Failed)?;
                return Err(Stop::Interrupted);
            }
        }
        progress.iter().for_each(Progress::finish);
        self.flush().map_err(Stop::Failed)
    }

    /// The outputs after step `step` (the `last` of the run: all of them): the probe lines and
    /// the snapshot where due, with the health check (or the check alone), and a checkpoint where
    /// due; its outputs' positions are those before a last step's outputs that are not due
    /// (a run resumed from it then writes what an uninterrupted one does).
    fn outputs(&mut self, lattice: &mut BlockLattice, step: u64, last: bool) -> Result<(), Stop> {
        let due = |every: u64| every > 0 && step.is_multiple_of(every);
        let (lines, snapshot) = (
            due(self.scene.output.interval),
            due(self.scene.output.fields_interval),
        );
        let schedule = &self.checkpoints.schedule;
        let checkpoint = self.checkpoints.enabled() && (last || checkpoint_due(self.comm, schedule, step));
        // The whole field crosses the bus only when something is written from it; a check
        // alone reads the status and, if it fails, one cell.
        if lines || snapshot || last {
            let (own, bad) = lattice.own_fields(self.comm);
            if let Some(bad) = bad {
                return Err(self.blow_up(lattice, step, bad));
            }
            self.write(lattice, step, &own, lines, snapshot)?;
            if checkpoint {
                self.checkpoint(lattice)?;
            }
            self.write(lattice, step, &own, last && !lines, last && !snapshot)?;
        } else if let Some(bad) = lattice.health(self.comm) {
            return Err(self.blow_up(lattice, step, bad));
        } else if checkpoint {
            self.checkpoint(lattice)?;
        }
        lattice.keep_fields();
        self.last_good = Some(step);
        Ok(())
    }

    /// The probe lines and the snapshot of `step`, those asked for, from this block's `own`
    /// fields: rank 0 writes the lines (their cells gathered), every rank its piece of the
    /// snapshot (on one rank, the whole .vti); every rank stops where one could not write.
    fn write(
        &mut self,
        lattice: &BlockLattice,
        step: u64,
        own: &[[f32; 4]],
        lines: bool,
        snapshot: bool,
    ) -> Result<(), Stop> {
        let mut written = Ok(());
        if lines && !self.line_cells.is_empty() {
            let values = lattice.gather_cells(self.comm, own, &self.line_cells);
            if let Some(out) = &mut self.fields {
                written = out.write_line_values(step, &values);
            }
        }
        if snapshot {
            written = written.and(self.write_snapshot(step, own));
        }
        if !all(self.comm, written.is_ok()) {
            return Err(Stop::Failed(
                written.err().unwrap_or_else(|| "another rank's outputs".into()),
            ));
        }
        Ok(())
    }

    /// The snapshot of `step` (`write_snapshot_of_ranks`), listed in fields.pvd.
    fn write_snapshot(&mut self, step: u64, own: &[[f32; 4]]) -> Result<(), String> {
        let outputs = (self.fields.as_mut(), self.pieces.as_ref());
        write_snapshot_of_ranks(self.comm, outputs, step, own)
    }

    fn flush(&mut self) -> Result<(), String> {
        self.fields.as_mut().map_or(Ok(()), FieldOutput::flush)
    }

    /// A checkpoint of the lattice as it is now (every rank's block), and of where the outputs
    /// stand: rank 0 stages and writes it, once the one before is written (the ranks agree that
    /// it could).
    fn checkpoint(&mut self, lattice: &BlockLattice) -> Result<(), Stop> {
        let mut at = OutputPositions::default();
        let mut staged = Ok(());
        if let Some(fields) = &mut self.fields {
            staged = fields.positions(&mut at);
            staged = staged.and_then(|()| self.checkpoints.stage().map(drop));
        }
        if !all(self.comm, staged.is_ok()) {
            return Err(Stop::Failed(
                staged
                    .err()
                    .unwrap_or_else(|| "rank 0 could not write the checkpoint".into()),
            ));
        }
        let time = lattice.time() as f64 * self.units.dt;
        self.checkpoints.hold((lattice, self.comm), time, 0, at, None);
        self.checkpoints.release();
        Ok(())
    }

    /// Describes the cell furthest out of bounds (`bad`, the first found, where none is further),
    /// with the rank that holds it, and writes the last good snapshot (rank 0).
    fn blow_up(&mut self, lattice: &BlockLattice, step: u64, bad: RankUnhealthy) -> Stop {
        let check = self.units.check_interval;
        let bad = lattice.furthest_unhealthy(self.comm).unwrap_or(bad);
        let kept = lattice.kept_own_fields();
        let origin = self.scene.domain.min;
        let rank = if self.comm.size() > 1 {
            format!("rank {}, ", bad.rank)
        } else {
            String::new()
        };
        let mut msg = format!(
            "the fluid became unstable between steps {} and {step}: furthest out of bounds, {rank}{}",
            step.saturating_sub(check),
            bad.cell
                .describe(&health_of(self.units), |c| self.units.cell_centre(c, origin))
        );
        if let Some((good, own)) = self.last_good.take().zip(kept) {
            msg += &self.write_last_good(good, &own);
        }
        if let Some(out) = &mut self.fields {
            let _ = out.flush();
        }
        Stop::Failed(msg)
    }

    /// The snapshot of the last check that passed (`write_last_good_of_ranks`); a line for the
    /// error.
    fn write_last_good(&mut self, good: u64, own: &[[f32; 4]]) -> String {
        let outputs = (self.fields.as_ref(), self.pieces.as_ref());
        write_last_good_of_ranks(self.comm, outputs, good, own)
    }
}
