//! A fluid-only scene (a `[lattice]` and no particles): the GPU lattice alone, with health checks,
//! VTK snapshots, probe lines and a summary.

use crate::checkpoint::{Checkpoints, Loaded, OutputPositions};
use crate::fields::FieldOutput;
use crate::lbm::geometry::{tau_minus, Face, Operator, Setup};
use crate::lbm::gpu::{Gpu, GpuLattice, Health, Unhealthy};
use crate::lbm::mrt::Rates;
use crate::lbm::storage::Storage;
use crate::output::{LatticeSummary, Progress};
use scene::lattice::{mach_limit, LatticeFace, LatticeUnits};
use scene::Scene;
use serde::Serialize;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

/// The lattice of a scene, for the kernels.
pub fn setup_of(units: &LatticeUnits) -> Setup {
    let face = |f: &LatticeFace| match *f {
        LatticeFace::Periodic => Face::Periodic,
        LatticeFace::Wall => Face::Wall,
        LatticeFace::MovingWall(u) => Face::MovingWall(u),
        LatticeFace::VelocityInlet(u) => Face::VelocityInlet(u),
        LatticeFace::PressureOutlet(rho) => Face::PressureOutlet(rho),
    };
    let operator = match units.operator.as_str() {
        "bgk" => Operator::Bgk,
        "trt" => Operator::Trt { magic: units.magic },
        _ => {
            let r = units.mrt;
            Operator::Mrt {
                rates: Rates {
                    nu: 1.0 / units.tau,
                    e: r.e,
                    epsilon: r.epsilon,
                    q: r.q,
                    pi: r.pi,
                    m: r.m,
                },
            }
        }
    };
    let mut setup = Setup::new(units.n, units.faces.map(|f| face(&f)), units.tau, operator);
    setup.solid = units.solid.clone();
    setup.force = units.force;
    setup.ramp_steps = units.ramp_steps;
    setup.storage = Storage::named(&units.storage).expect("a storage the scene accepted");
    setup
}

/// Below these taus TRT (magic 3/16, 1/4 or 0.01) blew up where BGK or MRT held
/// (validation/lbm/REPORT.md, "Stability near tau = 1/2", a sphere of 8 cells held in a stream of
/// 0.08): with a velocity inlet (at the inlet, from tau 0.5192; held at 0.538 in the sphere-drag
/// section), and with particles (at the sphere in a periodic box, from tau 0.5048; held at 0.5096).
const TRT_INLET_TAU: f64 = 0.53;
const TRT_PARTICLES_TAU: f64 = 0.51;
/// Below this tau BGK, and TRT with tau- at most [`BOUNDED_TAU_MINUS`] (`lattice.max_tau_minus`),
/// near the taus where they blew up in that table: both held the sphere to 0.5048 with inlet and
/// outlet and blew up at 0.5024; both blew up in the fluidized bed at 0.5034. BGK was refused
/// below it before that table was made.
const BGK_LIKE_TAU: f64 = 0.51;
const BOUNDED_TAU_MINUS: f64 = 1.0;

/// The warning for a lattice at a tau near where its operator was measured to blow up: TRT with
/// a velocity inlet below [`TRT_INLET_TAU`], with `particles` below [`TRT_PARTICLES_TAU`]; BGK,
/// or TRT with a bounded tau-, with an inlet or particles below [`BGK_LIKE_TAU`].
pub fn stability_warning(units: &LatticeUnits, particles: bool) -> Option<String> {
    let inlet = units
        .faces
        .iter()
        .any(|f| matches!(f, LatticeFace::VelocityInlet(_)));
    let tau = units.tau;
    let (name, measured, advice) = match units.operator.as_str() {
        "trt" if tau_minus(units.magic, tau) <= BOUNDED_TAU_MINUS + 1e-9 => (
            format!("TRT with tau- = {:.2}", tau_minus(units.magic, tau)),
            if (inlet || particles) && tau < BGK_LIKE_TAU {
                "with tau- <= 1 held to tau 0.5048 and blew up at 0.5024, in a periodic box and \
                 between inlet and outlet alike, where MRT held; a fluidized bed of 216 grains \
                 between walls (validation/imb/FLUIDIZED_BED.md) blew up at tau 0.5034 with both \
                 TRT and BGK, where MRT ran"
            } else {
                return None;
            },
            "",
        ),
        "trt" => (
            format!(
                "TRT: its antisymmetric modes relax with tau- = 1/2 + lattice.magic / (tau - 1/2) \
                 = {:.1}, hardly at all",
                tau_minus(units.magic, tau)
            ),
            if inlet && tau < TRT_INLET_TAU {
                "blew up at the velocity inlet from tau 0.5192 (magic 3/16 and 1/4; held at \
                 0.538), where MRT held to tau 0.5024"
            } else if particles && tau < TRT_PARTICLES_TAU {
                "blew up at the sphere in a periodic box from tau 0.5048 (magic 3/16, 1/4 and \
                 0.01; held at 0.5096), where BGK and MRT held to tau 0.5024"
            } else {
                return None;
            },
            " or lattice.max_tau_minus = 1",
        ),
        "bgk" if (inlet || particles) && tau < BGK_LIKE_TAU => (
            "BGK".to_string(),
            "held to tau 0.5024 in a periodic box and to 0.5048 between inlet and outlet, where \
             it blew up at 0.5024 and MRT held; a fluidized bed of 216 grains between walls \
             (validation/imb/FLUIDIZED_BED.md) blew up at tau 0.5034 with BGK, where MRT ran",
            "",
        ),
        _ => return None,
    };
    Some(format!(
        "lattice tau = {tau:.4} with {name}. A sphere of 8 cells held in a stream \
         (validation/lbm/REPORT.md, \"Stability near tau = 1/2\") {measured}; consider \
         lattice.operator = \"mrt\"{advice}"
    ))
}

/// Health limits: twice the operator's Mach limit, and a density deviation of 50%.
pub fn health_of(units: &LatticeUnits) -> Health {
    Health {
        max_speed: 2.0 * mach_limit(&units.operator) / 3f64.sqrt(),
        max_density_deviation: 0.5,
    }
}

#[derive(Debug, Serialize)]
struct FluidSummary {
    software: String,
    written_unix_s: u64,
    scene: String,
    scene_file: String,
    adapter: String,
    lattice: LatticeSummary,
    steps_requested: u64,
    steps_completed: u64,
    wall_time_s: f64,
    mlups: f64,
    exit_reason: String,
    exit_code: u8,
}

/// What stopped a run early.
enum Stop {
    Interrupted,
    Failed(String),
}

/// Runs a fluid-only scene (from its checkpoint where `checkpoints` resumes one); returns the
/// exit code.
pub fn run(
    scene: &Scene,
    scene_file: &str,
    steps: u64,
    out: &Path,
    interrupted: Arc<AtomicBool>,
    mut checkpoints: Checkpoints,
) -> u8 {
    let units = scene.lattice_units.as_ref().expect("fluid scenes have a lattice");
    let (gpu, mut lattice) = match start_lattice(scene, units, checkpoints.resumed.as_ref()) {
        Ok(started) => started,
        Err(e) => {
            protocol::say!("lbm-server: error: {e}");
            return 1;
        }
    };
    let started = Instant::now();
    let from = lattice.time;
    let at = checkpoints.resumed.as_ref().map(|l| l.header.outputs.clone());
    let result = FluidRun::new(scene, units, out, at.as_ref(), &mut checkpoints)
        .and_then(|mut r| r.steps(&mut lattice, steps, &interrupted));
    let result = result.and_then(|()| checkpoints.wait().map_err(Stop::Failed));
    let wall = started.elapsed().as_secs_f64();
    let (reason, code) = match &result {
        Ok(()) => ("completed".to_string(), 0),
        Err(Stop::Interrupted) => ("interrupted".to_string(), 130),
        Err(Stop::Failed(e)) => (format!("error: {e}"), 1),
    };
    match &result {
        Err(Stop::Failed(e)) => protocol::say!("lbm-server: error: {e}"),
        Err(Stop::Interrupted) => {
            let _ = checkpoints.wait();
            protocol::say!("lbm-server: interrupted after {} of {steps} steps", lattice.time)
        }
        Ok(()) => {}
    }
    let cells = units.n.iter().product::<usize>() as f64;
    let summary = FluidSummary {
        software: crate::output::software(),
        written_unix_s: crate::output::unix_seconds(),
        scene: scene.name.clone(),
        scene_file: scene_file.to_string(),
        adapter: gpu.adapter.name.clone(),
        lattice: LatticeSummary::of(units),
        steps_requested: steps,
        steps_completed: lattice.time,
        wall_time_s: wall,
        mlups: cells * (lattice.time - from) as f64 / wall.max(1e-9) / 1e6,
        exit_reason: reason,
        exit_code: code,
    };
    finish(&summary, out, lattice.time - from)
}

/// summary.json written, and the run's last line where it completed; the exit code (1 where
/// summary.json cannot be written).
fn finish(summary: &FluidSummary, out: &Path, stepped: u64) -> u8 {
    if let Err(e) = write_summary(summary, out) {
        protocol::say!("lbm-server: error: summary.json: {e}");
        return 1;
    }
    if summary.exit_code == 0 {
        protocol::say!(
            "lbm-server: {stepped} steps in {:.2} s ({:.2} MLUPS); output in {}",
            summary.wall_time_s,
            summary.mlups,
            out.display()
        );
    }
    summary.exit_code
}

/// The device and the scene's lattice on it (its state the checkpoint's where `resumed`), the
/// run's first line said once it is ready to step (and a warning where its tau is near 1/2).
fn start_lattice(
    scene: &Scene,
    units: &LatticeUnits,
    resumed: Option<&Loaded>,
) -> Result<(Arc<Gpu>, GpuLattice), String> {
    let gpu = Arc::new(Gpu::new()?);
    let mut lattice = GpuLattice::new(gpu.clone(), setup_of(units), health_of(units), None)?;
    if let Some(loaded) = resumed {
        lattice.restore_raw(&loaded.raw_state(lattice.population_bytes())?);
    }
    crate::run::started();
    protocol::say!(
        "lbm-server: scene '{}': {}x{}x{} cells, dx {:e} m, dt {:e} s, tau {:.4}, Mach {:.3}, {} on {}",
        scene.name,
        units.n[0],
        units.n[1],
        units.n[2],
        units.dx,
        units.dt,
        units.tau,
        units.mach,
        units.operator,
        gpu.adapter.name
    );
    if let Some(warning) = stability_warning(units, false) {
        protocol::say!("lbm-server: warning: {warning}");
    }
    Ok((gpu, lattice))
}

/// summary.json in `out` (the run's other outputs are written before it).
fn write_summary(summary: &FluidSummary, out: &Path) -> std::io::Result<()> {
    let text = serde_json::to_string_pretty(summary).unwrap_or_default();
    std::fs::write(out.join("summary.json"), text + "\n")
}

/// The outputs of one fluid run.
struct FluidRun<'a> {
    scene: &'a Scene,
    units: &'a LatticeUnits,
    fields: FieldOutput,
    checkpoints: &'a mut Checkpoints,
    /// The step of the last check that passed (its fields kept on the device).
    last_good: Option<u64>,
}

impl<'a> FluidRun<'a> {
    /// The outputs into `out`, resumed `at` a checkpoint's positions where given.
    fn new(
        scene: &'a Scene,
        units: &'a LatticeUnits,
        out: &'a Path,
        at: Option<&OutputPositions>,
        checkpoints: &'a mut Checkpoints,
    ) -> Result<Self, Stop> {
        Ok(Self {
            scene,
            units,
            fields: FieldOutput::new(scene, units, out, at).map_err(Stop::Failed)?,
            checkpoints,
            last_good: None,
        })
    }

    fn steps(&mut self, lattice: &mut GpuLattice, steps: u64, interrupted: &AtomicBool) -> Result<(), Stop> {
        let check = self.units.check_interval;
        let every = [
            check,
            self.scene.output.interval,
            self.scene.output.fields_interval,
            self.checkpoints.schedule.every(),
        ];
        let mut progress = Progress::new(steps);
        progress.update(lattice.time);
        while lattice.time < steps {
            let now = lattice.time;
            let next = every
                .iter()
                .filter(|e| **e > 0)
                .map(|e| (now / e + 1) * e)
                .chain([steps])
                .min()
                .expect("steps");
            lattice.step(next - now);
            // Interrupted (Ctrl-C), the run ends here: this step gets a last step's outputs.
            let stopping = interrupted.load(Ordering::SeqCst);
            self.outputs(lattice, next, next == steps || stopping)?;
            progress.update(next);
            if stopping {
                progress.abandon();
                self.fields.flush().map_err(Stop::Failed)?;
                return Err(Stop::Interrupted);
            }
        }
        progress.finish();
        self.fields.flush().map_err(Stop::Failed)
    }

    /// The outputs after step `step` (the `last` of the run: all of them): the probe lines and
    /// the snapshot where due, with the health check (or the check alone), and a checkpoint where
    /// due; its outputs' positions are those before a last step's outputs that are not due
    /// (a run resumed from it then writes what an uninterrupted one does).
    fn outputs(&mut self, lattice: &mut GpuLattice, step: u64, last: bool) -> Result<(), Stop> {
        let due = |every: u64| every > 0 && step.is_multiple_of(every);
        let (lines, snapshot) = (
            due(self.scene.output.interval),
            due(self.scene.output.fields_interval),
        );
        let checkpoint = self.checkpoints.enabled() && (last || self.checkpoints.schedule.due(step));
        // The whole field crosses the bus only when something is written from it; a check
        // alone reads the status and, if it fails, one cell.
        if lines || snapshot || last {
            let (fields, bad) = lattice.fields();
            if let Some(bad) = bad {
                return Err(self.blow_up(lattice, step, bad));
            }
            self.write(step, &fields, lines, snapshot)?;
            if checkpoint {
                self.checkpoint(lattice)?;
            }
            self.write(step, &fields, last && !lines, last && !snapshot)?;
        } else if let Some(bad) = lattice.health() {
            return Err(self.blow_up(lattice, step, bad));
        } else if checkpoint {
            self.checkpoint(lattice)?;
        }
        lattice.keep_fields();
        self.last_good = Some(step);
        Ok(())
    }

    /// The probe lines and the snapshot of `step`, those asked for.
    fn write(&mut self, step: u64, fields: &[[f32; 4]], lines: bool, snapshot: bool) -> Result<(), Stop> {
        if lines {
            self.fields.write_lines(step, fields).map_err(Stop::Failed)?;
        }
        if snapshot {
            self.fields.write_snapshot(step, fields).map_err(Stop::Failed)?;
        }
        Ok(())
    }

    /// A checkpoint of the lattice as it is now, and of where the outputs stand.
    fn checkpoint(&mut self, lattice: &GpuLattice) -> Result<(), Stop> {
        let mut at = OutputPositions::default();
        self.fields.positions(&mut at).map_err(Stop::Failed)?;
        self.checkpoints.stage().map_err(Stop::Failed)?;
        let time = lattice.time as f64 * self.units.dt;
        self.checkpoints.hold(lattice, time, 0, at, None);
        self.checkpoints.release();
        Ok(())
    }

    /// Describes the cell furthest out of bounds (`bad`, the first found, where none is further)
    /// and writes the last good snapshot.
    fn blow_up(&mut self, lattice: &GpuLattice, step: u64, bad: Unhealthy) -> Stop {
        let check = self.units.check_interval;
        let bad = lattice.furthest_unhealthy().unwrap_or(bad);
        let (origin, dx) = (self.scene.domain.min, self.units.dx);
        let mut msg = format!(
            "the fluid became unstable between steps {} and {step}: furthest out of bounds, {}",
            step.saturating_sub(check),
            bad.describe(&health_of(self.units), origin, dx)
        );
        if let Some((good, fields)) = self.last_good.take().zip(lattice.kept_fields()) {
            msg += &self.fields.write_last_good(good, &fields);
        }
        let _ = self.fields.flush();
        Stop::Failed(msg)
    }
}
