//! `dem-client run SCENE.toml`: a granular scene alone (no fluid).
//!
//! The scene's `time.dt` is the output step (the fluid step when coupled) and `time.steps` their
//! number; each is sub-cycled into k DEM steps exactly as in a coupled run. `[fluid]` is ignored.

use crate::dem::timestep::substeps;
use crate::output::{EnergyCsv, ParticleCsv, Vtk};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

#[derive(clap::Args)]
pub struct RunArgs {
    /// Scene file (TOML, SI units).
    scene: PathBuf,
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
}

pub fn main(args: RunArgs) -> ExitCode {
    let file = args.scene.display().to_string();
    let prepared = scene::Scene::load(&args.scene)
        .inspect(crate::say_scene_warnings)
        .and_then(|s| crate::dem::setup(&s, &file).map(|d| (s, d)));
    let (scene, setup) = match prepared {
        Ok(ok) => ok,
        Err(e) => {
            protocol::say!("dem-client: error: {e}");
            return ExitCode::from(2);
        }
    };
    let steps = match args.duration.map(|d| scene.steps_covering(d, "--duration")) {
        Some(Ok(steps)) => steps,
        Some(Err(e)) => {
            protocol::say!("dem-client: error: {e}");
            return ExitCode::from(2);
        }
        None => args.steps.unwrap_or(scene.time.steps),
    };
    let out = args.out.unwrap_or_else(|| PathBuf::from("out").join(&scene.name));
    let _lock = match lock_output(&out) {
        Ok(lock) => lock,
        Err(e) => {
            protocol::say!("dem-client: error: {e}");
            return ExitCode::from(2);
        }
    };
    let interrupted = Arc::new(AtomicBool::new(false));
    let flag = interrupted.clone();
    if let Err(e) = ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst)) {
        protocol::say!("dem-client: warning: cannot install the Ctrl-C handler: {e}");
    }
    match simulate(&scene, setup, steps, &out, &interrupted) {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(130),
        Err(e) => {
            protocol::say!("dem-client: error: {}: {e}", out.display());
            ExitCode::from(1)
        }
    }
}

/// The output folder `out`, made and locked for this run (a run into it already is refused).
fn lock_output(out: &std::path::Path) -> Result<scene::output_lock::OutputLock, String> {
    std::fs::create_dir_all(out)
        .map_err(|e| format!("cannot create the output folder {}: {e}", out.display()))?;
    scene::output_lock::OutputLock::take(out)
}

/// Runs `steps` output steps; Ok(false) when interrupted.
fn simulate(
    scene: &scene::Scene,
    setup: crate::dem::SceneWorld,
    steps: u64,
    out: &std::path::Path,
    interrupted: &AtomicBool,
) -> std::io::Result<bool> {
    let removed = scene::outputs::clear_earlier(out, scene::outputs::DEM_CLIENT)?;
    if removed > 0 {
        protocol::say!("dem-client: removed {removed} output files of an earlier run");
    }
    let mut world = setup.world;
    let (k, dt) = substeps(scene.time.dt, setup.dt_max);
    world.dt = dt;
    protocol::say!(
        "dem-client: scene '{}', {} spheres, {} walls, DEM step {dt:.3e} s (t_c {:.3e} s), {k} per output step of {} s",
        scene.name,
        world.bodies.len(),
        world.walls.len(),
        setup.contact_time,
        scene.time.dt
    );
    let mut csv = ParticleCsv::create(&out.join("particles.csv"))?;
    let mut energy = EnergyCsv::create(&out.join("energy.csv"))?;
    let mut vtk = scene.dem.output.vtk.then(|| Vtk::new(out));
    let interval = scene.output.interval;
    let started = Instant::now();
    let mut done = 0;
    for step in 0..=steps {
        energy.write(step, &world)?;
        if step % interval == 0 || step == steps {
            csv.write(step, &world)?;
            energy.commit()?;
            if let Some(v) = vtk.as_mut() {
                v.write(step, &world)?;
            }
        }
        if step == steps || interrupted.load(Ordering::SeqCst) {
            break;
        }
        world.advance(k);
        done += 1;
    }
    energy.commit()?;
    let wall = started.elapsed().as_secs_f64();
    let particle_steps = (done * k) as f64 * world.bodies.len() as f64;
    protocol::say!(
        "dem-client: {} DEM steps in {wall:.2} s: {:.3e} particle-steps/s; {} contacts, kinetic energy {:.3e} J, {} neighbour-list builds",
        done * k,
        particle_steps / wall.max(1e-9),
        world.contact_count(),
        world.kinetic_energy(),
        world.builds
    );
    Ok(done == steps)
}
