//! `dem-client connect`: the DEM side of the lockstep loop.

use crate::checkpoint;
use crate::dem::lubrication::SqueezeFilm;
use crate::dem::timestep::substeps;
use crate::dem::world::{Body, World, CHUNK};
use crate::dem::V3;
use crate::lockstep::Lockstep;
use protocol::substep_drag::substep_drag;
use protocol::transport::LinkOptions;
use protocol::{
    Capabilities, DemLink, Hello, LinkError, ParticleReply, ParticleState, Physics, Units, Welcome,
};
use rayon::prelude::*;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

#[derive(clap::Args)]
pub struct ConnectArgs {
    /// Run name printed by lbm-server ("DEM service: NAME").
    #[arg(long)]
    service: String,
    /// Scene file holding the particles (default: the built-in default scene).
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Longest wait for a live fluid server that is silent and idle (no CPU) [s]; one that works
    /// is waited for up to 60 times as long.
    #[arg(long, default_value_t = 10.0)]
    timeout: f64,
    /// Say the DEM step's limits (contacts, the drag within a fluid step, the squeeze films), the
    /// walls and the films at the start, and the run's figures (DEM steps, neighbour-list builds,
    /// free flight, islands) at the end; without it a line each.
    #[arg(long, short)]
    verbose: bool,
    /// The folder to write this DEM's part of a checkpoint into when the fluid asks (default:
    /// $LBMDEM_CHECKPOINT_DIR, which lbm-server sets for a DEM it starts). Without one the Hello
    /// declares no CHECKPOINT capability.
    #[arg(long, value_name = "DIR")]
    checkpoint_dir: Option<PathBuf>,
    /// The checkpoint folder a resumed run goes on from (default: $LBMDEM_RESUME_DIR).
    #[arg(long, value_name = "DIR")]
    resume_from: Option<PathBuf>,
    /// Testing: announce this protocol version instead of ours.
    #[arg(long, hide = true)]
    protocol_version: Option<u32>,
    /// Testing: insert or remove one particle every step.
    #[arg(long, hide = true)]
    churn: bool,
    /// Testing: send the wrong step index at this step.
    #[arg(long, hide = true)]
    skip_step: Option<u64>,
    /// Testing: stop answering (stay alive, silent) at this step.
    #[arg(long, hide = true)]
    stall_at: Option<u64>,
    /// Testing: the stall ends after this many seconds (else never).
    #[arg(long, hide = true)]
    stall_for: Option<f64>,
    /// Testing: the stall spins on the CPU (a long step, an endless loop) instead of sleeping.
    #[arg(long, hide = true)]
    stall_busy: bool,
}

/// Deliberate misbehaviour, for the tests of the failure rules.
#[derive(Clone, Copy, Default)]
pub(crate) struct Faults {
    pub churn: bool,
    pub skip_step: Option<u64>,
    stall_at: Option<u64>,
    stall_for: Option<Duration>,
    stall_busy: bool,
}

impl Faults {
    /// The faults the testing arguments ask for.
    fn of(args: &ConnectArgs) -> Faults {
        Faults {
            churn: args.churn,
            skip_step: args.skip_step,
            stall_at: args.stall_at,
            stall_for: args.stall_for.map(Duration::from_secs_f64),
            stall_busy: args.stall_busy,
        }
    }

    /// Stays silent at `stall_at`: asleep or spinning, for `stall_for` or for ever.
    pub fn stall(&self, step: u64) {
        if self.stall_at != Some(step) {
            return;
        }
        let start = std::time::Instant::now();
        let mut x = 0u64;
        while self.stall_for.is_none_or(|d| start.elapsed() < d) {
            if self.stall_busy {
                x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
            } else {
                std::thread::sleep(Duration::from_millis(10));
            }
        }
    }
}

/// Physics this side applies: gravity and contacts (buoyancy is the fluid's), and the squeeze
/// films of `coupling.lubrication` in a scene with a lattice (the fluid then leaves them to us).
fn physics(scene: &scene::Scene) -> u64 {
    let films = if wet_films(scene) { Physics::LUBRICATION } else { 0 };
    Physics::GRAVITY | Physics::CONTACTS | films
}

fn wet_films(scene: &scene::Scene) -> bool {
    scene.coupling.lubrication && scene.lattice_units.is_some()
}

/// The squeeze films integrated in the DEM steps: the fluid's viscosity (Welcome), the cut-off one
/// lattice cell of the scene.
fn lubrication(scene: &scene::Scene, welcome: &Welcome) -> Option<SqueezeFilm> {
    let units = scene.lattice_units.as_ref().filter(|_| wet_films(scene))?;
    Some(SqueezeFilm {
        viscosity: welcome.fluid_viscosity,
        cutoff: units.dx,
    })
}

pub fn main(args: ConnectArgs) -> ExitCode {
    let (scene, setup) = match load(&args) {
        Ok(ok) => ok,
        Err(e) => {
            protocol::say!("dem-client: error: {e}");
            return ExitCode::from(2);
        }
    };
    let interrupted = crate::catch_ctrl_c(on_ctrl_c);
    let mut particles = CoupledParticles::new(setup.world, &scene);
    let joined = join(&args, &scene, &particles);
    JOINING.store(false, Ordering::SeqCst);
    let (link, welcome) = match joined {
        Ok(ok) => ok,
        Err(e) => {
            protocol::say!("dem-client: error: {e}");
            return ExitCode::from(1);
        }
    };
    let mut last = None;
    let faults = Faults::of(&args);
    let (sub, limits) = particles.couple(&scene, &welcome, setup.dt_max);
    say_coupling(args.verbose, &particles, sub, setup.contact_time, limits);
    if let Err(e) = resume(&args, &welcome, &mut particles) {
        protocol::say!("dem-client: error: {e}");
        return ExitCode::from(2);
    }
    let checkpoint_dir = checkpoint::folder(args.checkpoint_dir.as_ref(), checkpoint::CHECKPOINT_DIR_ENV);
    let lockstep = Lockstep {
        link: &link,
        welcome: &welcome,
        substeps: sub,
        interrupted: &interrupted,
        faults,
        checkpoint_dir: checkpoint_dir.as_deref(),
    };
    match lockstep.run(&mut particles, &mut last) {
        Ok(steps) => {
            let stopped = steps < welcome.steps && !interrupted.load(Ordering::SeqCst);
            say_finish(args.verbose, &particles, steps, stopped.then_some(welcome.steps));
            if steps < welcome.steps && interrupted.load(Ordering::SeqCst) {
                protocol::say!("dem-client: interrupted after {steps} of {} steps", welcome.steps);
                return ExitCode::from(130);
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            protocol::say!("dem-client: error: {}", failure(&e, last));
            ExitCode::from(1)
        }
    }
}

/// Whether the DEM is still joining the run (waiting for the fluid's services and its Welcome),
/// with no step to stop in order: Ctrl-C then ends the process at once.
static JOINING: AtomicBool = AtomicBool::new(true);

/// Ctrl-C (SIGINT, SIGTERM; SIGTERM too when the lbm-server that started this DEM dies): while
/// joining, the process ends at once (exit 130); later the run stops at its next step
/// (`interrupted`), or ends on the fluid's death, which the wait for its forces sees first.
fn on_ctrl_c(interrupted: &AtomicBool) {
    if JOINING.load(Ordering::SeqCst) {
        protocol::say!("dem-client: interrupted while joining the run");
        std::process::exit(130);
    }
    interrupted.store(true, Ordering::SeqCst);
}

/// A resumed run (Welcome's `first_step` above 0): the particles' state of that step, from
/// dem.bin in the checkpoint folder (`--resume-from`, $LBMDEM_RESUME_DIR).
fn resume(args: &ConnectArgs, welcome: &Welcome, particles: &mut CoupledParticles) -> Result<(), String> {
    if welcome.first_step == 0 {
        return Ok(());
    }
    let dir = checkpoint::folder(args.resume_from.as_ref(), checkpoint::RESUME_DIR_ENV).ok_or_else(|| {
        format!(
            "the fluid resumes the run at step {}, but no checkpoint folder was given (--resume-from, ${})",
            welcome.first_step,
            checkpoint::RESUME_DIR_ENV
        )
    })?;
    checkpoint::read_coupled(&dir, welcome.first_step, particles)?;
    protocol::say!(
        "dem-client: resumed at step {} from {}",
        welcome.first_step,
        dir.display()
    );
    Ok(())
}

/// The scene (or the default one) and its DEM set up, with the arguments checked.
fn load(args: &ConnectArgs) -> Result<(scene::Scene, crate::dem::SceneWorld), String> {
    let scene = crate::scene_or_default(args.scene.as_ref()).map_err(|e| e.to_string())?;
    if !(args.timeout.is_finite() && args.timeout > 0.0) {
        return Err(format!(
            "--timeout = {} s: must be a finite number > 0",
            args.timeout
        ));
    }
    let file = args
        .scene
        .as_ref()
        .map_or(scene::DEFAULT_SCENE_FILE.to_string(), |p| p.display().to_string());
    let setup = crate::dem::setup(&scene, &file).map_err(|e| e.to_string())?;
    Ok((scene, setup))
}

/// The handshake with the fluid server: Hello (this DEM's physics and spheres), Welcome; both
/// sides must wrap the same axes.
fn join(
    args: &ConnectArgs,
    scene: &scene::Scene,
    particles: &CoupledParticles,
) -> Result<(DemLink, Welcome), String> {
    let mut hello = Hello::new(
        Units::SI,
        physics(scene),
        particles.world.bodies.len(),
        &format!("dem-client {} (soft-sphere DEM)", env!("CARGO_PKG_VERSION")),
    );
    if checkpoint::folder(args.checkpoint_dir.as_ref(), checkpoint::CHECKPOINT_DIR_ENV).is_some() {
        hello.capabilities |= Capabilities::CHECKPOINT;
    }
    if let Some(v) = args.protocol_version {
        hello.version = v;
    }
    let options = LinkOptions {
        run: args.service.clone(),
        timeout: Duration::from_secs_f64(args.timeout),
    };
    let (link, welcome) = DemLink::connect(options, hello).map_err(|e| e.to_string())?;
    if welcome.periodic_axes() != scene.periodic_axes() {
        let names =
            |axes: [bool; 3]| -> Vec<&str> { (0..3).filter(|&a| axes[a]).map(|a| scene::AXES[a]).collect() };
        return Err(format!(
            "the fluid's domain is periodic along {:?} (Welcome.periodic), this scene's along {:?}: \
             both sides must wrap the same axes",
            names(welcome.periodic_axes()),
            names(scene.periodic_axes())
        ));
    }
    Ok((link, welcome))
}

/// What the DEM says at the start: its step against the fluid's; with `verbose` what limits it,
/// the walls, free flight and the films.
fn say_coupling(
    verbose: bool,
    particles: &CoupledParticles,
    sub: Substeps,
    contact_time: f64,
    limits: [f64; 3],
) {
    if verbose {
        let line = coupling_line(particles, sub, contact_time, limits);
        protocol::say!("dem-client: {line}");
    } else {
        protocol::say!(
            "dem-client: DEM step {:.3e} s = fluid step / {} (--verbose: what limits it)",
            particles.world.dt,
            sub.contact
        );
    }
}

/// What the DEM says after a run of `steps` fluid steps (of `stopped_of` where the fluid server
/// stopped it early): the DEM steps taken; with `verbose` its figures and the islands' timing.
fn say_finish(verbose: bool, particles: &CoupledParticles, steps: u64, stopped_of: Option<u64>) {
    if verbose {
        protocol::say!("dem-client: {}", finish_line(particles, steps));
    } else {
        protocol::say!(
            "dem-client: finished after {steps} steps ({} DEM steps)",
            particles.dem_steps
        );
    }
    if let Some(of) = stopped_of {
        protocol::say!("dem-client: the fluid server stopped the run after {steps} of {of} steps");
    }
    if let Some(line) = particles.world.everyone.summary().filter(|_| verbose) {
        protocol::say!("dem-client: {line}");
    }
}

/// The DEM step against the fluid's and what limits it, the walls, free flight and lubrication.
fn coupling_line(particles: &CoupledParticles, sub: Substeps, contact_time: f64, limits: [f64; 3]) -> String {
    format!(
        "DEM step {:.3e} s = fluid step / {} (shortest contact time {contact_time:.3e} s, step limits: \
         contacts {:.3e} s, sub-step drag {:.3e} s, squeeze films {:.3e} s){}, {} walls{}",
        particles.world.dt,
        sub.contact,
        limits[0],
        limits[1],
        limits[2],
        if sub.free_flight {
            "; free flight: a sphere that can touch nothing within a fluid step moves in one exact step"
        } else {
            ""
        },
        particles.world.walls.len(),
        match particles.world.lubrication() {
            Some(l) => format!(", lubrication below {:.3e} m", l.cutoff),
            None => String::new(),
        }
    )
}

/// What the DEM did over the run's `steps` fluid steps.
fn finish_line(particles: &CoupledParticles, steps: u64) -> String {
    format!(
        "finished after {steps} steps ({} DEM steps, {} neighbour-list builds, {} steps in free \
         flight, {} with an island ({} dropped for a sphere beyond its reach); {:.1}% of the \
         sphere-steps flown)",
        particles.dem_steps,
        particles.world.builds,
        particles.free_steps,
        particles.world.islands,
        particles.world.dropped_islands,
        particles.flown_percent()
    )
}

/// What the DEM says when the lockstep fails: the error, for a silent fluid server what to raise,
/// and the last completed step.
fn failure(e: &LinkError, last: Option<u64>) -> String {
    let last = last.map_or("none".to_string(), |s| s.to_string());
    format!("{e}{}; last completed step: {last}", e.hint())
}

#[cfg(test)]
mod tests {
    use super::*;
    use protocol::transport::Peer;

    #[test]
    fn a_silent_fluid_server_names_the_setting_to_raise() {
        let waited = std::time::Duration::from_secs_f64(10.1);
        let silent = LinkError::Timeout {
            peer: Peer::Fluid,
            waited,
            idle: None,
        };
        let said = failure(&silent, Some(136));
        assert!(
            said.contains("did not answer within 10.1 s")
                && said.contains("raise coupling.timeout")
                && said.ends_with("last completed step: 136"),
            "{said}"
        );
        let died = LinkError::PeerDied {
            peer: Peer::Fluid,
            pid: 7,
        };
        assert!(!failure(&died, None).contains("raise"));
        assert!(failure(&died, None).ends_with("last completed step: none"));
    }
}

/// rho_f / dt_fluid (the fluid's Welcome) with `coupling.substep_drag` in a scene with a lattice,
/// else 0 (the fluid force held constant over the fluid step).
fn covered_mass_rate(scene: &scene::Scene, welcome: &Welcome) -> f64 {
    let on = scene.coupling.substep_drag && scene.lattice.is_some();
    if on {
        welcome.fluid_density / welcome.dt
    } else {
        0.0
    }
}

/// How a fluid step is advanced: in `contact` DEM sub-steps, or, with `free_flight`
/// (`coupling.free_flight`), the spheres that can touch nothing within it in one exact step of
/// their free motion and the others in the sub-steps (`World::advance_span`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Substeps {
    pub contact: u64,
    pub free_flight: bool,
}

/// The DEM side's particles in a coupled run.
pub(crate) struct CoupledParticles {
    pub world: World,
    density: f64,
    next_id: u64,
    /// Fluid density / fluid step [kg/m^3/s] for the drag within a fluid step (0: the force is
    /// held constant).
    covered_mass_rate: f64,
    /// DEM steps taken, fluid steps taken in free flight (every sphere flown), sphere-steps flown
    /// of all (the steps with an island are counted by the world).
    pub dem_steps: u64,
    pub free_steps: u64,
    pub flown_sphere_steps: u64,
    pub sphere_steps: u64,
}

impl CoupledParticles {
    pub fn new(world: World, scene: &scene::Scene) -> CoupledParticles {
        CoupledParticles {
            world,
            density: scene.particles.density,
            next_id: scene.particle_count(),
            covered_mass_rate: 0.0,
            dem_steps: 0,
            free_steps: 0,
            flown_sphere_steps: 0,
            sphere_steps: 0,
        }
    }

    /// Takes the fluid's terms from its Welcome (time step, gravity, density and viscosity): the
    /// drag within a fluid step, the squeeze films, the DEM step (the largest that divides the
    /// fluid step and keeps within `dt_max` and the limits of the drag and the films). Returns how
    /// a fluid step is advanced and the three step limits [s].
    pub fn couple(&mut self, scene: &scene::Scene, welcome: &Welcome, dt_max: f64) -> (Substeps, [f64; 3]) {
        self.covered_mass_rate = covered_mass_rate(scene, welcome);
        self.world.set_lubrication(lubrication(scene, welcome));
        let limits = [dt_max, self.drag_step_limit(), self.film_step_limit()];
        let (k, dt) = substeps(welcome.dt, limits.into_iter().fold(f64::INFINITY, f64::min));
        self.world.dt = dt;
        self.world.gravity = V3::from(welcome.gravity);
        let sub = Substeps {
            contact: k,
            free_flight: scene.coupling.free_flight && scene.lattice.is_some(),
        };
        (sub, limits)
    }

    /// The fraction of the sphere-steps flown so far [%].
    pub fn flown_percent(&self) -> f64 {
        100.0 * self.flown_sphere_steps as f64 / self.sphere_steps.max(1) as f64
    }

    pub(crate) fn states_into(&self, out: &mut Vec<ParticleState>) {
        out.clear();
        out.par_extend(
            self.world
                .bodies
                .par_iter()
                .with_min_len(CHUNK)
                .map(|b| ParticleState {
                    id: b.id,
                    position: b.x.into(),
                    velocity: b.v.into(),
                    angular_velocity: b.w.into(),
                    radius: b.r,
                }),
        );
    }

    /// Takes the fluid's force and torque (same order as the states), held over the fluid step
    /// (following the velocity change since the states were sent at the immersed boundary's own
    /// rate, when `coupling.substep_drag` is on), and advances the fluid step `dt` in
    /// `substeps.contact` DEM steps; with `substeps.free_flight`, each sphere that can touch
    /// nothing within it in one exact step.
    pub(crate) fn advance(&mut self, replies: &[ParticleReply], substeps: Substeps, dt: f64) {
        let (g, rate) = (self.world.gravity, self.covered_mass_rate);
        let bodies = self.world.bodies.par_iter_mut().with_min_len(CHUNK);
        bodies.zip(replies).for_each(|(b, r)| {
            let (force, torque) = (V3::from(r.force), V3::from(r.torque));
            (b.drag, b.spin_drag) = substep_drag(rate, b.r);
            b.f_ext = force + b.drag * b.v;
            b.t_ext = torque + b.spin_drag * b.w;
            // The reference velocity moves as the held force, gravity and the previous step's mean
            // contact force would move the sphere: only the change of the contacts within the step
            // is damped.
            let contact = b.contact_impulse / dt;
            let contact_torque = b.contact_angular_impulse / dt;
            b.f_ext_rate = b.drag * ((force + contact) / b.m + g);
            b.t_ext_rate = b.spin_drag * (torque + contact_torque) / b.inertia;
            b.contact_impulse = V3::zeros();
            b.contact_angular_impulse = V3::zeros();
        });
        if !substeps.free_flight {
            self.world.advance(substeps.contact);
            self.dem_steps += substeps.contact;
            return;
        }
        let flown = self.world.advance_span(dt, substeps.contact);
        let n = self.world.bodies.len();
        self.sphere_steps += n as u64;
        self.flown_sphere_steps += flown as u64;
        if flown == n {
            self.free_steps += 1;
            self.dem_steps += 1;
        } else {
            self.dem_steps += substeps.contact;
        }
    }

    /// The longest DEM step at which the drag within a fluid step stays accurate: a tenth of the
    /// shortest relaxation time m / drag = (rho_p / rho_f) dt_fluid (infinite without that drag).
    fn drag_step_limit(&self) -> f64 {
        let relaxation = |b: &Body| b.m / substep_drag(self.covered_mass_rate, b.r).0;
        let shortest = self
            .world
            .bodies
            .iter()
            .map(relaxation)
            .fold(f64::INFINITY, f64::min);
        0.1 * shortest
    }

    /// The longest DEM step at which no squeeze film, at its roughness floor, changes a sphere's
    /// approach speed by more than a fraction `MAX_FILM_LAMBDA` per step (infinite without
    /// lubrication). The wall film of the sphere with the least m / r is the stiffest (m*/R* of a
    /// pair is never below its smaller sphere's m / r).
    fn film_step_limit(&self) -> f64 {
        let Some(lub) = self.world.lubrication() else {
            return f64::INFINITY;
        };
        self.world
            .bodies
            .iter()
            .map(|b| lub.step_limit(b.r, b.m))
            .fold(f64::INFINITY, f64::min)
    }

    /// The counters a checkpoint carries: the next id, the DEM steps, the steps in free flight and
    /// the sphere-steps flown of all.
    pub fn counters(&self) -> [u64; 5] {
        [
            self.next_id,
            self.dem_steps,
            self.free_steps,
            self.flown_sphere_steps,
            self.sphere_steps,
        ]
    }

    /// The counters of a checkpoint (`counters`).
    pub fn set_counters(&mut self, c: &[u64]) -> Result<(), String> {
        let [next_id, dem_steps, free_steps, flown, spheres] = c else {
            return Err(format!(
                "dem.bin holds {} counters of a coupled run, not 5",
                c.len()
            ));
        };
        (self.next_id, self.dem_steps, self.free_steps) = (*next_id, *dem_steps, *free_steps);
        (self.flown_sphere_steps, self.sphere_steps) = (*flown, *spheres);
        Ok(())
    }

    /// Test aid: removes the last particle or inserts a copy of the first with a fresh id, next to
    /// it where there is room, so the particle count changes between steps.
    pub(crate) fn churn(&mut self, step: u64) {
        if step % 2 == 1 && self.world.bodies.len() > 1 {
            self.world.pop();
            return;
        }
        let first = self.world.bodies[0];
        let free = |x: V3| self.world.bodies.iter().all(|b| (b.x - x).norm() > b.r + first.r);
        let offsets = [V3::x(), -V3::x(), V3::y(), -V3::y(), V3::z(), -V3::z()];
        let x = offsets
            .iter()
            .map(|o| first.x + 2.5 * first.r * o)
            .find(|x| free(*x))
            .unwrap_or(first.x + 2.5 * first.r * V3::z());
        let body = Body::sphere(
            self.next_id,
            x,
            first.v,
            first.w,
            first.r,
            self.density,
            first.material,
        );
        self.next_id += 1;
        self.world.insert(body);
    }
}
