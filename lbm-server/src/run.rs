//! `lbm-server run`: load a scene, start (or wait for) the DEM side, step in lockstep, write output.

use crate::coupled::FluidSide;
use crate::launch;
use crate::output::{LatticeSummary, ParticleOutput, PeerInfo, Progress, Summary, TimeSplit};
use protocol::transport::{new_run_name, LinkOptions};
use protocol::{
    FluidLink, Hello, LinkError, ParticleReply, ParticleState, Physics, StepFlags, StepHeader, Units, Welcome,
};
use scene::Scene;
use std::path::PathBuf;
use std::process::{Child, ExitCode};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

#[derive(clap::Args)]
pub struct RunArgs {
    /// Scene file (TOML, SI units). Without it, the built-in default scene runs.
    scene: Option<PathBuf>,
    /// Number of steps (overrides the scene's time.steps).
    #[arg(long)]
    steps: Option<u64>,
    /// Simulated time [s] (overrides the scene's time.steps or time.duration): the steps that
    /// cover it.
    #[arg(long, conflicts_with = "steps")]
    duration: Option<f64>,
    /// Output folder (default: out/SCENE_NAME).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Who runs the DEM side: `spawn` starts dem-client; `external` prints the service name and
    /// waits for any client that speaks the protocol (PROTOCOL.md).
    #[arg(long, value_enum, default_value_t = DemMode::Spawn)]
    dem: DemMode,
    /// Longest wait for the DEM side to connect [s] (default: 30 when spawned, unlimited when external).
    #[arg(long)]
    connect_timeout: Option<f64>,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum DemMode {
    Spawn,
    External,
}

/// Exit codes.
const EXIT_FAILURE: u8 = 1;
const EXIT_BAD_INPUT: u8 = 2;
const EXIT_INTERRUPTED: u8 = 130;

/// How a run ended without failure.
enum Ending {
    Completed,
    Interrupted,
    StoppedByPeer,
}

/// A scene ready to run: validated, with its output folder made.
struct Prepared {
    scene: Scene,
    scene_file: String,
    steps: u64,
    out: PathBuf,
    scene_copy: PathBuf,
    connect_timeout: Duration,
}

fn prepare(args: &RunArgs) -> Result<Prepared, String> {
    let (scene, scene_file, text) = match &args.scene {
        Some(path) => {
            let scene = Scene::load(path).map_err(|e| e.to_string())?;
            let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
            (scene, path.display().to_string(), text)
        }
        None => (
            Scene::default_scene(),
            scene::DEFAULT_SCENE_FILE.to_string(),
            scene::DEFAULT_SCENE.to_string(),
        ),
    };
    require_lattice(&scene, &scene_file)?;
    let steps = match args.duration {
        Some(duration) => scene.steps_covering(duration, "--duration")?,
        None => args.steps.unwrap_or(scene.time.steps),
    };
    if steps == 0 {
        return Err("--steps = 0: must be at least 1".into());
    }
    let default_timeout = if args.dem == DemMode::External {
        f64::INFINITY
    } else {
        30.0
    };
    let connect_timeout = args.connect_timeout.unwrap_or(default_timeout);
    if connect_timeout.is_nan() || connect_timeout <= 0.0 {
        return Err(format!("--connect-timeout = {connect_timeout} s: must be > 0"));
    }
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(&scene.name));
    std::fs::create_dir_all(&out)
        .map_err(|e| format!("cannot create the output folder {}: {e}", out.display()))?;
    clear_earlier_outputs(&out)?;
    let scene_copy = out.join("scene.toml");
    std::fs::write(&scene_copy, text).map_err(|e| format!("{}: {e}", scene_copy.display()))?;
    Ok(Prepared {
        scene,
        scene_file,
        steps,
        out,
        scene_copy,
        connect_timeout: Duration::try_from_secs_f64(connect_timeout).unwrap_or(Duration::MAX),
    })
}

/// Removes what an earlier run wrote into `out` under this run's output names, saying so.
fn clear_earlier_outputs(out: &std::path::Path) -> Result<(), String> {
    let removed = scene::outputs::clear_earlier(out, scene::outputs::LBM_SERVER).map_err(|e| {
        format!(
            "cannot remove an earlier run's outputs from {}: {e}",
            out.display()
        )
    })?;
    if removed > 0 {
        protocol::say!(
            "lbm-server: removed {removed} output files of an earlier run from {}",
            out.display()
        );
    }
    Ok(())
}

/// A scene with particles runs coupled to the lattice: without a `[lattice]` it is refused.
fn require_lattice(scene: &Scene, file: &str) -> Result<(), String> {
    if scene.lattice.is_some() || scene.particle_count() == 0 {
        return Ok(());
    }
    let error = scene::SceneError {
        file: file.to_string(),
        field: "lattice".into(),
        value: "missing".into(),
        problem: format!(
            "lbm-server couples particles to a lattice-Boltzmann fluid: add a [lattice] section (dx or \
             resolution, velocity_scale, ...; see validation/scenes/default.toml) and remove time.dt, \
             which the lattice derives; or run a granular scene alone with `dem-client run {file}`"
        ),
    };
    Err(error.to_string())
}

pub fn main(args: RunArgs) -> ExitCode {
    let prepared = match prepare(&args) {
        Ok(p) => p,
        Err(e) => {
            protocol::say!("lbm-server: error: {e}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    let interrupted = Arc::new(AtomicBool::new(false));
    let flag = interrupted.clone();
    if let Err(e) = ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst)) {
        protocol::say!("lbm-server: warning: cannot install the Ctrl-C handler: {e}");
    }
    if prepared.scene.lattice.is_some() && prepared.scene.particle_count() == 0 {
        let p = &prepared;
        return ExitCode::from(crate::fluid::run(
            &p.scene,
            &p.scene_file,
            p.steps,
            &p.out,
            interrupted,
        ));
    }
    protocol::cleanup::remove_stale_runs();
    let run = new_run_name();
    let code = Session::start(prepared, &run, args.dem, interrupted);
    protocol::cleanup::remove_run(&run);
    ExitCode::from(code)
}

/// One run in progress.
struct Session {
    p: Prepared,
    link: FluidLink,
    child: Option<Child>,
    particles: ParticleOutput,
    fluid: FluidSide,
    interrupted: Arc<AtomicBool>,
    peer: Option<PeerInfo>,
    hello: Option<Hello>,
    last_completed: Option<u64>,
    /// Whether a reply carried FINAL or STOP: the DEM ends on its own and is given the time to.
    told_to_end: bool,
    particle_steps: u64,
    started: Instant,
    times: TimeSplit,
}

impl Session {
    /// Runs the whole session and returns the process exit code.
    fn start(p: Prepared, run: &str, mode: DemMode, interrupted: Arc<AtomicBool>) -> u8 {
        let timeout = Duration::from_secs_f64(p.scene.coupling.timeout);
        let capacity = p.scene.capacity() as usize;
        let link = match FluidLink::create(
            LinkOptions {
                run: run.to_string(),
                timeout,
            },
            capacity,
        ) {
            Ok(link) => link,
            Err(e) => {
                protocol::say!("lbm-server: error: {e}");
                return EXIT_FAILURE;
            }
        };
        let particles = match ParticleOutput::create(&p.out, p.scene.dem.output.vtk) {
            Ok(particles) => particles,
            Err(e) => {
                protocol::say!(
                    "lbm-server: error: {}: {e}",
                    p.out.join("particles.csv").display()
                );
                return EXIT_FAILURE;
            }
        };
        let fluid = match FluidSide::for_scene(&p.scene, p.steps, &p.out) {
            Ok(f) => f,
            Err(e) => {
                protocol::say!("lbm-server: error: {e}");
                return EXIT_FAILURE;
            }
        };
        let mut session = Session {
            p,
            link,
            child: None,
            particles,
            fluid,
            interrupted,
            peer: None,
            hello: None,
            last_completed: None,
            told_to_end: false,
            particle_steps: 0,
            started: Instant::now(),
            times: TimeSplit::default(),
        };
        let result = session.connect(mode).and_then(|()| session.step_loop());
        session.finish(result)
    }

    /// Starts or announces the DEM side and performs the handshake.
    fn connect(&mut self, mode: DemMode) -> Result<(), String> {
        let run = self.link.run().to_string();
        let spawned = match mode {
            DemMode::Spawn => {
                let exe = launch::find_dem_client()
                    .ok_or("cannot find dem-client next to lbm-server or on PATH (build it: cargo build)")?;
                let child =
                    launch::spawn_dem_client(&exe, &run, &self.p.scene_copy, self.p.scene.coupling.timeout)
                        .map_err(|e| format!("cannot start {}: {e}", exe.display()))?;
                let pid = child.id();
                self.child = Some(child);
                Some(pid)
            }
            DemMode::External => {
                println!("DEM service: {run}");
                println!(
                    "join with: dem-client connect --service {run} --scene {}",
                    self.p.scene_copy.display()
                );
                use std::io::Write;
                let _ = std::io::stdout().flush();
                None
            }
        };
        let (scene, steps) = (&self.p.scene, self.p.steps);
        let physics = self.fluid.physics();
        let interrupted = self.interrupted.clone();
        let hello = self
            .link
            .accept(
                spawned,
                self.p.connect_timeout,
                &|| interrupted.load(Ordering::SeqCst),
                |hello| welcome_for(scene, steps, hello, physics & !yielded(hello)),
            )
            .map_err(|e| e.to_string())?;
        if yielded(&hello) != 0 {
            self.fluid.leave_lubrication();
        }
        let fluid = self.fluid.describe();
        self.peer = Some(PeerInfo {
            software: protocol::handshake::field_text(&hello.software),
            pid: hello.pid,
            protocol_version: hello.version,
            physics: Physics::names(hello.physics),
        });
        protocol::say!(
            "lbm-server: scene '{}', {} steps ({:.4e} s), DEM: {} (pid {}); {fluid}",
            scene.name,
            steps,
            steps as f64 * scene.time.dt,
            protocol::handshake::field_text(&hello.software),
            hello.pid
        );
        self.hello = Some(hello);
        Ok(())
    }

    /// The lockstep loop: states(n) in, forces(n) out, each part timed (`TimeSplit`).
    fn step_loop(&mut self) -> Result<Ending, String> {
        let units = self.hello.expect("connected").units;
        let mut progress = Progress::new(self.p.steps);
        let (mut si, mut replies): (Vec<ParticleState>, Vec<ParticleReply>) = (Vec::new(), Vec::new());
        self.started = Instant::now();
        let mut clock = Clock::new();
        // A DEM that speaks SI: its states are read where it wrote them (the shared memory, no
        // copy) and the replies go out as they are; other units are converted both ways.
        let in_si = units == Units::SI;
        for step in 0..self.p.steps {
            let received = self.link.receive_states(step).map_err(|e| self.describe(e))?;
            self.times.waiting_for_dem += clock.lap();
            let header = received.header();
            if !in_si {
                si.clear();
                si.extend(received.particles().iter().map(|s| units.state_to_si(s)));
            }
            let last = step + 1 == self.p.steps;
            let (bad, count) = {
                let states = if in_si { received.particles() } else { &si[..] };
                self.times.exchange += clock.lap();
                let ended = answer(
                    &mut self.fluid,
                    states,
                    step,
                    last,
                    &self.p.scene.domain,
                    &mut replies,
                );
                self.times.fluid += clock.lap();
                (ended.map(|e| self.describe_fluid(e)), states.len())
            };
            let stop =
                header.has(StepFlags::STOP) || self.interrupted.load(Ordering::SeqCst) || bad.is_some();
            // A step that ends the run in failure gets no row: its loads are the zeros of the
            // STOP reply, and the error names what went wrong.
            let output = (step % self.p.scene.output.interval == 0 || last || stop) && bad.is_none();
            // The sample goes back before the reply (the DEM loans the next one once it has the
            // forces); particles.csv, written after the reply, gets a copy of its states.
            if in_si && output {
                si.clear();
                si.extend_from_slice(received.particles());
            }
            drop(received);
            let flags = if last { StepFlags::FINAL } else { 0 } | if stop { StepFlags::STOP } else { 0 };
            let reply = StepHeader::new(step, header.time, count, flags);
            let sent = if in_si {
                self.link.send_forces(reply, |i| replies[i])
            } else {
                self.link.send_forces(reply, |i| units.reply_from_si(&replies[i]))
            };
            sent.map_err(|e| self.describe(e))?;
            self.told_to_end = last || stop;
            self.last_completed = Some(step);
            self.particle_steps += count as u64;
            self.times.exchange += clock.lap();
            if output {
                let time = header.time * units.time_s;
                self.particles.write_step(step, time, &si, &replies)?;
            }
            progress.update(step + 1);
            self.times.output += clock.lap();
            if let Some(why) = bad {
                return Err(why);
            }
            if stop {
                progress.finish();
                return self.end_early(last);
            }
        }
        progress.finish();
        Ok(Ending::Completed)
    }

    /// A run stopped by Ctrl-C or the DEM's STOP: the field outputs of the step it stopped at
    /// (unless it was the last, which wrote them), and how it ended.
    fn end_early(&mut self, last: bool) -> Result<Ending, String> {
        if !last {
            self.fluid
                .write_fields_of_early_end()
                .map_err(|e| self.describe_fluid(e))?;
        }
        // Ctrl-C on a terminal reaches both processes: our own interrupt takes precedence.
        Ok(if self.interrupted.load(Ordering::SeqCst) {
            Ending::Interrupted
        } else {
            Ending::StoppedByPeer
        })
    }

    fn describe_fluid(&self, e: String) -> String {
        let last = self.last_completed.map_or("none".to_string(), |s| s.to_string());
        format!("{e}; last completed step: {last}")
    }

    fn describe(&self, e: LinkError) -> String {
        let last = self.last_completed.map_or("none".to_string(), |s| s.to_string());
        format!("{e}{}; last completed step: {last}", e.hint())
    }

    /// Flushes output, ends the DEM process, writes summary.json; returns the exit code.
    fn finish(mut self, result: Result<Ending, String>) -> u8 {
        let (reason, code) = match &result {
            Ok(Ending::Completed) => ("completed".to_string(), 0),
            Ok(Ending::Interrupted) => ("interrupted".to_string(), EXIT_INTERRUPTED),
            Ok(Ending::StoppedByPeer) => ("stopped by the DEM client".to_string(), 0),
            Err(_) if self.interrupted.load(Ordering::SeqCst) => {
                ("interrupted".to_string(), EXIT_INTERRUPTED)
            }
            Err(e) => (format!("error: {e}"), EXIT_FAILURE),
        };
        if let (Err(msg), false) = (&result, code == EXIT_INTERRUPTED) {
            protocol::say!("lbm-server: error: {msg}");
        }
        if let Err(e) = self.particles.flush() {
            protocol::say!("lbm-server: error: particles.csv: {e}");
        }
        // A DEM whose last reply said FINAL or STOP ends on its own: it is given the time to.
        let told = result.is_ok() || self.told_to_end;
        let grace = if told {
            Duration::from_secs(2)
        } else {
            Duration::ZERO
        };
        if let Some(child) = self.child.as_mut() {
            launch::end_child(child, grace);
        } else if told {
            // An external DEM: let it read the last reply before our ports close.
            self.link.linger(protocol::transport::LINGER);
        }
        let summary = self.summary(reason, code);
        if let Err(e) = summary.write(&self.p.out.join("summary.json")) {
            protocol::say!("lbm-server: error: summary.json: {e}");
        }
        if code == 0 {
            protocol::say!(
                "lbm-server: {} steps in {:.2} s ({:.0} steps/s; {}; the fluid's step at {:.1} \
                 MLUPS); output in {}",
                summary.steps_completed,
                summary.wall_time_s,
                summary.steps_per_second,
                summary.time_s.describe(summary.wall_time_s),
                summary.fluid_mlups,
                self.p.out.display()
            );
        }
        code
    }

    fn summary(&self, exit_reason: String, exit_code: u8) -> Summary {
        let wall = self.started.elapsed().as_secs_f64();
        let steps_completed = self.last_completed.map_or(0, |s| s + 1);
        let t = self.times;
        let other = wall - (t.waiting_for_dem + t.fluid + t.exchange + t.output);
        let cells: usize = self.fluid.units().n.iter().product();
        Summary {
            software: crate::output::software(),
            written_unix_s: crate::output::unix_seconds(),
            scene: self.p.scene.name.clone(),
            scene_file: self.p.scene_file.clone(),
            run: self.link.run().to_string(),
            steps_requested: self.p.steps,
            steps_completed,
            last_completed_step: self.last_completed,
            particles_initial: self.hello.map_or(0, |h| h.initial_count),
            wall_time_s: wall,
            time_s: TimeSplit {
                other: other.max(0.0),
                ..t
            },
            fluid_mlups: cells as f64 * steps_completed as f64 / t.fluid.max(1e-9) / 1e6,
            steps_per_second: steps_completed as f64 / wall.max(1e-9),
            particle_steps_per_second: self.particle_steps as f64 / wall.max(1e-9),
            fluid_physics: Physics::names(self.fluid.physics()),
            covered_cells: self.fluid.covered_cells().name(),
            lattice: LatticeSummary::of(self.fluid.units()),
            peer: self.peer.clone(),
            exit_reason,
            exit_code,
        }
    }
}

/// Laps of the lockstep loop: each call returns the seconds since the last.
struct Clock(Instant);

impl Clock {
    fn new() -> Self {
        Clock(Instant::now())
    }

    fn lap(&mut self) -> f64 {
        let now = Instant::now();
        let lap = now.duration_since(self.0).as_secs_f64();
        self.0 = now;
        lap
    }
}

/// The negotiable effects the fluid leaves to a DEM that declares them: lubrication (a DEM that
/// integrates the squeeze films in its own sub-steps does it better than a force held over the
/// fluid step; PROTOCOL.md 4.5).
fn yielded(hello: &Hello) -> u64 {
    hello.physics & Physics::LUBRICATION
}

/// The fluid's answer to a DEM's Hello, in the DEM's units.
fn welcome_for(scene: &Scene, steps: u64, hello: &Hello, physics: u64) -> Welcome {
    let u = hello.units;
    let accel = u.length_m / (u.time_s * u.time_s);
    let mut w = Welcome::accepted(&format!(
        "lbm-server {} (lattice-Boltzmann + IMB)",
        env!("CARGO_PKG_VERSION")
    ));
    w.steps = steps;
    w.dt = scene.time.dt / u.time_s;
    w.domain_min = scene.domain.min.map(|x| x / u.length_m);
    w.domain_max = scene.domain.max.map(|x| x / u.length_m);
    w.gravity = scene.gravity.map(|g| g / accel);
    w.fluid_density = scene.fluid.density / (u.mass_kg / u.length_m.powi(3));
    w.fluid_viscosity = scene.fluid.dynamic_viscosity / (u.mass_kg / (u.length_m * u.time_s));
    w.physics = physics;
    w.periodic = Welcome::periodic_bits(scene.periodic_axes());
    w
}

/// The fluid's replies to the states of `step` in `replies`, or why the run ends at this step
/// (then `replies` holds zero loads, for the reply that carries STOP): states the fluid rejects,
/// with the fluid's own blow-up first where it has one (a blown-up fluid sends forces that throw
/// the particles out or make them NaN), or the fluid's failure (a health check).
fn answer(
    fluid: &mut FluidSide,
    states: &[ParticleState],
    step: u64,
    last: bool,
    domain: &scene::Domain,
    replies: &mut Vec<ParticleReply>,
) -> Option<String> {
    replies.clear();
    let ended = match check_states(states, step, domain) {
        Some(why) => Some(match fluid.unstable_now() {
            Some(cause) => format!("{cause}; then {why}"),
            None => why,
        }),
        None => fluid
            .step(states, replies)
            .and_then(|()| if last { fluid.check_last_step() } else { Ok(()) })
            .err(),
    };
    if ended.is_some() {
        replies.clear();
        replies.extend(states.iter().map(|s| ParticleReply {
            id: s.id,
            force: [0.0; 3],
            torque: [0.0; 3],
        }));
    }
    ended
}

/// Health check of the DEM's states: every number finite, every radius positive.
fn check_states(states: &[ParticleState], step: u64, domain: &scene::Domain) -> Option<String> {
    states.iter().find_map(|s| {
        let finite = s
            .position
            .iter()
            .chain(&s.velocity)
            .chain(&s.angular_velocity)
            .all(|v| v.is_finite());
        if !finite || s.radius.is_nan() || s.radius <= 0.0 {
            return Some(format!(
                "the DEM client sent an invalid state at step {step}: particle id {} with position {:?}, \
                 velocity {:?}, radius {}",
                s.id, s.position, s.velocity, s.radius
            ));
        }
        let outside = (0..3).any(|a| s.position[a] < domain.min[a] || s.position[a] > domain.max[a]);
        outside.then(|| {
            format!(
                "particle id {} left the domain at step {step}: position {:?} m, velocity {:?} m/s \
                 (domain {:?} .. {:?} m); the fluid covers only the domain: an instability upstream, or \
                 a face without a wall",
                s.id, s.position, s.velocity, domain.min, domain.max
            )
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fluid applies lubrication unless the DEM declares it (then the DEM integrates it in its
    /// sub-steps); gravity and buoyancy are not negotiable.
    #[test]
    fn the_fluid_leaves_lubrication_to_a_dem_that_declares_it() {
        let scene = Scene::default_scene();
        let ours = Physics::LATTICE_BOLTZMANN | Physics::BUOYANCY | Physics::LUBRICATION;
        let welcome = |dem: u64| {
            let hello = Hello::new(protocol::Units::SI, dem, 1, "test");
            welcome_for(&scene, 1, &hello, ours & !yielded(&hello)).physics
        };
        assert_eq!(welcome(Physics::GRAVITY), ours);
        assert_eq!(
            welcome(Physics::GRAVITY | Physics::LUBRICATION),
            ours & !Physics::LUBRICATION
        );
        assert_eq!(
            welcome(Physics::GRAVITY | Physics::BUOYANCY),
            ours,
            "a conflict stays one"
        );
    }

    #[test]
    fn a_particle_outside_the_domain_or_not_finite_stops_the_run_with_its_id() {
        let domain = scene::Domain {
            min: [0.0; 3],
            max: [0.1, 0.1, 0.2],
            periodic: Vec::new(),
        };
        let state = |id: u64, z: f64| ParticleState {
            id,
            position: [0.05, 0.05, z],
            velocity: [0.0, 0.0, -22.0],
            radius: 0.002,
            ..Default::default()
        };
        assert_eq!(check_states(&[state(0, 0.1), state(1, 0.2)], 3, &domain), None);
        let out = check_states(&[state(0, 0.1), state(7, -0.01)], 3, &domain).expect("refused");
        assert!(out.contains("particle id 7 left the domain at step 3"), "{out}");
        let nan = check_states(&[state(2, f64::NAN)], 4, &domain).expect("refused");
        assert!(nan.contains("invalid state at step 4: particle id 2"), "{nan}");
    }
}
