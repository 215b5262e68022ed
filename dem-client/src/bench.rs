//! `dem-client bench`: the DEM side of a coupled scene timed without the fluid.
//!
//! The spheres, walls, contact law, DEM step, squeeze films, sub-step drag and free flight are
//! those `dem-client connect` would use for the scene; the fluid's reply is a stand-in, computed
//! on this side each fluid step: buoyancy plus the Stokes drag and spin drag of a fluid at rest,
//! each taken as the force that relaxes the sphere's velocity exactly over the fluid step (so it
//! stays stable at any step). The figure is the DEM's share of a coupled step: the fluid's step
//! and the exchange come on top (`lbm-server run` splits a whole run's time in summary.json).

use crate::connect::{CoupledParticles, Substeps};
use crate::dem::V3;
use protocol::{ParticleReply, ParticleState, Welcome};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

#[derive(clap::Args)]
pub struct BenchArgs {
    /// Coupled scene (with a `[lattice]`, which sets the fluid step) whose particles to time.
    scene: PathBuf,
    /// Fluid steps to time.
    #[arg(long, default_value_t = 40)]
    steps: u64,
    /// Worker threads (default: one per core).
    #[arg(long)]
    threads: Option<usize>,
    /// Free flight "on", "off" (every sphere takes the DEM steps) or "both" (one after the other,
    /// each from the scene's initial state).
    #[arg(long, default_value = "both")]
    free_flight: String,
}

/// What one timed run measured.
struct Timing {
    /// Wall time of each fluid step's DEM work (states out, advance) [s].
    steps: Vec<f64>,
    build_seconds: f64,
    builds: u64,
    contacts: (usize, usize),
}

pub fn main(args: BenchArgs) -> ExitCode {
    match bench(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            protocol::say!("dem-client bench: error: {e}");
            ExitCode::from(2)
        }
    }
}

fn bench(args: &BenchArgs) -> Result<(), String> {
    let modes: &[bool] = match args.free_flight.as_str() {
        "on" => &[true],
        "off" => &[false],
        "both" => &[true, false],
        other => {
            return Err(format!(
                "--free-flight = {other:?}: must be \"on\", \"off\" or \"both\""
            ))
        }
    };
    if args.steps == 0 {
        return Err("--steps = 0: must be at least 1".into());
    }
    if args.threads == Some(0) {
        return Err("--threads = 0: must be at least 1".into());
    }
    let scene = scene::Scene::load(&args.scene).map_err(|e| e.to_string())?;
    crate::say_scene_warnings(&scene);
    if scene.lattice.is_none() {
        return Err(format!(
            "{}: the scene has no [lattice]: `dem-client bench` times the DEM side of a coupled scene \
             (a granular scene alone: `dem-client run`)",
            args.scene.display()
        ));
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .map_err(|e| e.to_string())?;
    let welcome = stand_in_welcome(&scene);
    for &free_flight in modes {
        let file = args.scene.display().to_string();
        let setup = crate::dem::setup(&scene, &file).map_err(|e| e.to_string())?;
        let mut particles = CoupledParticles::new(setup.world, &scene);
        let (mut sub, _) = particles.couple(&scene, &welcome, setup.dt_max);
        sub.free_flight = free_flight;
        let timing = pool.install(|| time_steps(&mut particles, sub, &welcome, args.steps));
        report(
            &scene,
            &particles,
            sub,
            &timing,
            pool.current_num_threads(),
            welcome.dt,
        );
    }
    Ok(())
}

/// The Welcome `lbm-server` would send for the scene (SI units): its fluid step, gravity and fluid.
fn stand_in_welcome(scene: &scene::Scene) -> Welcome {
    let mut w = Welcome::accepted("dem-client bench (stand-in fluid)");
    w.dt = scene.time.dt;
    w.gravity = scene.gravity;
    w.fluid_density = scene.fluid.density;
    w.fluid_viscosity = scene.fluid.dynamic_viscosity;
    w.domain_min = scene.domain.min;
    w.domain_max = scene.domain.max;
    w
}

/// `steps` fluid steps of the coupled DEM with the stand-in fluid reply, each timed.
fn time_steps(particles: &mut CoupledParticles, sub: Substeps, welcome: &Welcome, steps: u64) -> Timing {
    let mut states: Vec<ParticleState> = Vec::new();
    let mut replies: Vec<ParticleReply> = Vec::new();
    let contacts_before = particles.world.contact_count();
    let (builds_before, seconds_before) = (particles.world.builds, particles.world.build_seconds);
    let mut times = Vec::with_capacity(steps as usize);
    for _ in 0..steps {
        stand_in_replies(particles, welcome, &mut replies);
        let start = Instant::now();
        particles.states_into(&mut states);
        particles.advance(&replies, sub, welcome.dt);
        times.push(start.elapsed().as_secs_f64());
    }
    Timing {
        steps: times,
        build_seconds: particles.world.build_seconds - seconds_before,
        builds: particles.world.builds - builds_before,
        contacts: (contacts_before, particles.world.contact_count()),
    }
}

/// The stand-in fluid's force and torque on every sphere: buoyancy, and the drag of a fluid at
/// rest that relaxes the sphere's velocity as Stokes' law would over the fluid step, exactly
/// (-m v (1 - exp(-dt / t_r)) / dt, t_r = m / (3 pi mu d); the spin with I / (8 pi mu r^3)).
fn stand_in_replies(particles: &CoupledParticles, welcome: &Welcome, out: &mut Vec<ParticleReply>) {
    let (rho, mu, dt) = (welcome.fluid_density, welcome.fluid_viscosity, welcome.dt);
    let g = V3::from(welcome.gravity);
    let relax = |inertia: f64, resistance: f64| inertia * -(-dt * resistance / inertia).exp_m1() / dt;
    out.clear();
    out.extend(particles.world.bodies.iter().map(|b| {
        let volume = 4.0 / 3.0 * std::f64::consts::PI * b.r.powi(3);
        let pi_mu = std::f64::consts::PI * mu;
        let force = -rho * volume * g - relax(b.m, 6.0 * pi_mu * b.r) * b.v;
        let torque = -relax(b.inertia, 8.0 * pi_mu * b.r.powi(3)) * b.w;
        ParticleReply {
            id: b.id,
            force: force.into(),
            torque: torque.into(),
        }
    }));
}

fn report(scene: &scene::Scene, p: &CoupledParticles, sub: Substeps, t: &Timing, threads: usize, dt: f64) {
    let n = p.world.bodies.len();
    let steps = t.steps.len();
    let total: f64 = t.steps.iter().sum();
    let mut sorted = t.steps.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[steps / 2];
    let mean = total / steps as f64;
    protocol::say!(
        "dem-client bench: scene '{}', {n} spheres, {steps} fluid steps of {dt:.4e} s, {} DEM steps of {:.4e} s \
         each when sub-stepped, {threads} threads, free flight {}; the fluid a stand-in (buoyancy, Stokes drag at rest)",
        scene.name,
        sub.contact,
        p.world.dt,
        if sub.free_flight { "on" } else { "off" },
    );
    protocol::say!(
        "  {:.3} ms per fluid step (median {:.3}, fastest {:.3}, slowest {:.3}); neighbour-list builds {:.3} ms \
         per fluid step ({} builds, {:.2} ms each); {:.1} ns per sphere per fluid step",
        1e3 * mean,
        1e3 * median,
        1e3 * sorted[0],
        1e3 * sorted[steps - 1],
        1e3 * t.build_seconds / steps as f64,
        t.builds,
        1e3 * t.build_seconds / t.builds.max(1) as f64,
        1e9 * mean / n.max(1) as f64,
    );
    protocol::say!(
        "  {} DEM steps, {} fluid steps flown whole, {} with an island ({} dropped), {:.1}% of the sphere-steps \
         flown; \
         contacts {} at the start, {} at the end, of {} listed pairs",
        p.dem_steps,
        p.free_steps,
        p.world.islands,
        p.world.dropped_islands,
        p.flown_percent(),
        t.contacts.0,
        t.contacts.1,
        p.world.pair_count(),
    );
    if let Some(line) = p.world.everyone.summary() {
        protocol::say!("  {line}");
    }
}
