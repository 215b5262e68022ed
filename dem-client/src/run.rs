//! `dem-client run SCENE.toml`: a granular scene alone (no fluid); `--resume OUT` goes on from
//! the last checkpoint in OUT (`run_checkpoint.rs`).
//!
//! The scene's `time.dt` is the output step (the fluid step when coupled) and `time.steps` their
//! number; each is sub-cycled into k DEM steps exactly as in a coupled run. `[fluid]` is ignored.

use crate::dem::timestep::substeps;
use crate::dem::world::World;
use crate::output::{EnergyCsv, ParticleCsv, Vtk};
use crate::run_checkpoint::{resume, Outputs, RunCheckpoints};
use scene::checkpoint::OutputPositions;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

#[derive(clap::Args)]
pub struct RunArgs {
    /// Scene file (TOML, SI units).
    #[arg(required_unless_present = "resume")]
    scene: Option<PathBuf>,
    /// Number of output steps (overrides the scene's time.steps).
    #[arg(long)]
    steps: Option<u64>,
    /// Simulated time [s] (overrides the scene's time.steps or time.duration): the steps that
    /// cover it.
    #[arg(long, conflicts_with = "steps")]
    duration: Option<f64>,
    /// Output folder (default: out/SCENE_NAME).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Steps between two checkpoints (OUT/checkpoint/; overrides `output.checkpoint_interval`).
    #[arg(long, value_name = "N")]
    checkpoint_interval: Option<u64>,
    /// Goes on from the last checkpoint in OUT, with the scene of OUT/scene.toml, to its last
    /// step or `--steps`, appending to the outputs there.
    #[arg(long, value_name = "OUT", conflicts_with_all = ["scene", "out"])]
    resume: Option<PathBuf>,
}

/// A run ready to go: the scene (its file's text), its DEM, steps and output folder (locked).
struct Prepared {
    scene: scene::Scene,
    text: String,
    setup: crate::dem::SceneWorld,
    steps: u64,
    out: PathBuf,
    _lock: scene::output_lock::OutputLock,
}

pub fn main(args: RunArgs) -> ExitCode {
    let p = match prepare(&args) {
        Ok(p) => p,
        Err(e) => {
            protocol::say!("dem-client: error: {e}");
            return ExitCode::from(2);
        }
    };
    let interrupted = crate::catch_ctrl_c(|flag| flag.store(true, Ordering::SeqCst));
    match simulate(p, args.resume.is_some(), args.checkpoint_interval, &interrupted) {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(130),
        Err(Failure::BadInput(e)) => {
            protocol::say!("dem-client: error: {e}");
            ExitCode::from(2)
        }
        Err(Failure::Output(e)) => {
            protocol::say!("dem-client: error: {e}");
            ExitCode::from(1)
        }
    }
}

/// Why a run failed: its input (a checkpoint that does not fit: exit 2), or its outputs (1).
enum Failure {
    BadInput(String),
    Output(String),
}

impl From<std::io::Error> for Failure {
    fn from(e: std::io::Error) -> Self {
        Failure::Output(e.to_string())
    }
}

/// The scene (OUT/scene.toml where resumed) loaded and set up, the steps, the output folder made
/// and locked.
fn prepare(args: &RunArgs) -> Result<Prepared, String> {
    let path = match (&args.resume, &args.scene) {
        (Some(out), _) => out.join("scene.toml"),
        (None, Some(scene)) => scene.clone(),
        (None, None) => return Err("give a scene file, or --resume OUT".into()),
    };
    let file = path.display().to_string();
    let scene = scene::Scene::load(&path).map_err(|e| e.to_string())?;
    crate::say_scene_warnings(&scene);
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{file}: {e}"))?;
    let setup = crate::dem::setup(&scene, &file).map_err(|e| e.to_string())?;
    let steps = match args.duration {
        Some(d) => scene.steps_covering(d, "--duration")?,
        None => args.steps.unwrap_or(scene.time.steps),
    };
    let out = args
        .resume
        .clone()
        .or_else(|| args.out.clone())
        .unwrap_or_else(|| PathBuf::from("out").join(&scene.name));
    let lock = lock_output(&out)?;
    Ok(Prepared {
        scene,
        text,
        setup,
        steps,
        out,
        _lock: lock,
    })
}

/// The output folder `out`, made and locked for this run (a run into it already is refused).
fn lock_output(out: &Path) -> Result<scene::output_lock::OutputLock, String> {
    std::fs::create_dir_all(out)
        .map_err(|e| format!("cannot create the output folder {}: {e}", out.display()))?;
    scene::output_lock::OutputLock::take(out)
}

/// A fresh run's output folder: an earlier run's outputs and checkpoints removed, the scene
/// copied in (OUT/scene.toml, which `--resume` reads).
fn fresh_outputs(out: &Path, text: &str) -> std::io::Result<()> {
    let removed = scene::outputs::clear_earlier(out, scene::outputs::DEM_CLIENT)?;
    if removed > 0 {
        protocol::say!("dem-client: removed {removed} output files of an earlier run");
    }
    for dir in [
        scene::checkpoint::DIR,
        scene::checkpoint::OLD,
        scene::checkpoint::STAGING,
    ] {
        if out.join(dir).is_dir() {
            std::fs::remove_dir_all(out.join(dir))?;
        }
    }
    std::fs::write(out.join("scene.toml"), text)
}

/// The outputs: made anew, or reopened where the checkpoint `at` found them.
fn open_outputs(
    scene: &scene::Scene,
    out: &Path,
    at: Option<&OutputPositions>,
) -> Result<(ParticleCsv, EnergyCsv, Option<Vtk>), Failure> {
    let (csv_path, energy_path) = (out.join("particles.csv"), out.join("energy.csv"));
    let vtk = scene.dem.output.vtk;
    Ok(match at {
        None => (
            ParticleCsv::create(&csv_path)?,
            EnergyCsv::create(&energy_path)?,
            vtk.then(|| Vtk::new(out)),
        ),
        Some(at) => (
            ParticleCsv::resume(&csv_path, at).map_err(Failure::Output)?,
            EnergyCsv::resume(&energy_path, at).map_err(Failure::Output)?,
            vtk.then(|| Vtk::resume(out, at))
                .transpose()
                .map_err(Failure::Output)?,
        ),
    })
}

/// The run's first step, where the outputs stood and the `--checkpoint-interval` its first run
/// was given: the checkpoint's, restored into `world` (`resumed`), or 0 with the folder cleared of
/// an earlier run's outputs.
fn first_step(
    (out, text, steps): (&Path, &str, u64),
    world: &mut World,
    resumed: bool,
) -> Result<(u64, Option<OutputPositions>, Option<u64>), Failure> {
    if !resumed {
        fresh_outputs(out, text)?;
        return Ok((0, None, None));
    }
    let header = resume(out, text, world).map_err(Failure::BadInput)?;
    let step = header.step;
    if step >= steps {
        return Err(Failure::BadInput(format!(
            "the checkpoint is at step {step}, the run's last step is {}: nothing to resume \
             (give a larger --steps)",
            steps
        )));
    }
    scene::checkpoint::cut_back(out, &header.outputs).map_err(Failure::Output)?;
    Ok((step, Some(header.outputs), header.checkpoint_interval))
}

/// Runs the output steps (from the checkpoint's where `resumed`); Ok(false) when interrupted.
fn simulate(
    p: Prepared,
    resumed: bool,
    every: Option<u64>,
    interrupted: &AtomicBool,
) -> Result<bool, Failure> {
    let crate::dem::SceneWorld {
        mut world,
        contact_time,
        dt_max,
    } = p.setup;
    let (k, dt) = substeps(p.scene.time.dt, dt_max);
    world.dt = dt;
    let (first, at, given) = first_step((&p.out, &p.text, p.steps), &mut world, resumed)?;
    protocol::say!(
        "dem-client: scene '{}', {} spheres, {} walls, DEM step {dt:.3e} s (t_c {:.3e} s), {k} per output step of {} s{}",
        p.scene.name,
        world.bodies.len(),
        world.walls.len(),
        contact_time,
        p.scene.time.dt,
        if resumed { format!("; resumed at step {first}") } else { String::new() }
    );
    let (mut csv, mut energy, mut vtk) = open_outputs(&p.scene, &p.out, at.as_ref())?;
    let mut checkpoints = RunCheckpoints::new(&p.out, &p.scene, &p.text, every.or(given));
    let interval = p.scene.output.interval;
    let started = Instant::now();
    let mut done = 0;
    for step in first..=p.steps {
        let stop = interrupted.load(Ordering::SeqCst);
        if step > first && (checkpoints.schedule.due(step) || step == p.steps || stop) {
            let outputs = Outputs {
                csv: &csv,
                energy: &mut energy,
                vtk: vtk.as_ref(),
            };
            checkpoints
                .write(step, &world, outputs)
                .map_err(Failure::Output)?;
        }
        energy.write(step, &world)?;
        if step % interval == 0 || step == p.steps {
            write_output_step(step, &world, (&mut csv, &mut energy, vtk.as_mut()))?;
        }
        if step == p.steps || stop {
            break;
        }
        world.advance(k);
        done += 1;
    }
    energy.commit()?;
    say_done(&world, done * k, started.elapsed().as_secs_f64());
    Ok(first + done == p.steps)
}

/// Writes an output step's rows: the particles, the energy rows so far, the particle .vtp.
fn write_output_step(
    step: u64,
    world: &World,
    (csv, energy, vtk): (&mut ParticleCsv, &mut EnergyCsv, Option<&mut Vtk>),
) -> Result<(), Failure> {
    csv.write(step, world)?;
    energy.commit()?;
    if let Some(v) = vtk {
        v.write(step, world)?;
    }
    Ok(())
}

/// Says how many DEM steps ran in `wall` seconds and how the world ended.
fn say_done(world: &World, dem_steps: u64, wall: f64) {
    let particle_steps = dem_steps as f64 * world.bodies.len() as f64;
    protocol::say!(
        "dem-client: {dem_steps} DEM steps in {wall:.2} s: {:.3e} particle-steps/s; {} contacts, kinetic energy {:.3e} J, {} neighbour-list builds",
        particle_steps / wall.max(1e-9),
        world.contact_count(),
        world.kinetic_energy(),
        world.builds
    );
}
