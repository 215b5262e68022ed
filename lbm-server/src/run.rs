//! `lbm-server run`: load a scene, start (or wait for) the DEM side, step in lockstep, write output.
//!
//! A coupled run, file by file, in the order it happens:
//! - `prepare.rs`: the scene loaded and checked, its output folder made ([`prepare`]).
//! - `session.rs`: the run in progress ([`Session`]): opened, connected to the DEM (the handshake,
//!   with the fluid's answer to its Hello in `welcome.rs`), finished.
//! - here: the lockstep loop (`Session::step_loop`), each coupled step a list of named passes
//!   (`Session::coupled_step`): `exchange.rs` receives the DEM's states and sends the replies,
//!   `answer.rs` is the fluid's answer to the states, `ending.rs` how a step ends the run.
//! - `checkpointing.rs`: the run's checkpoints, with the DEM's part (PROTOCOL.md 6.4); `resume.rs`:
//!   a run prepared to go on from one (`--resume`).
//! - `counters.rs`: what the run counts, and where its wall time goes (summary.json's `time_s`).
//! - `summary.rs`: summary.json.
//!
//! A scene with a lattice and no particles runs the fluid alone (`fluid.rs`).

mod answer;
mod checkpointing;
mod counters;
mod ending;
mod exchange;
mod prepare;
mod resume;
mod session;
mod summary;
mod welcome;

use crate::checkpoint::OutputPositions;
use crate::launch::{self, DemStart};
use crate::parallel::{wait_for_rank_0, Communicator};
use crate::terminal::Progress;
use exchange::SiStates;
use prepare::prepare;
use protocol::transport::new_run_name;
use protocol::{ParticleReply, StepFlags, StepHeader};
use session::Session;
use std::path::PathBuf;
use std::process::ExitCode;
use std::rc::Rc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};

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
    /// Who runs the DEM side: `builtin` starts dem-client; `yade` / `liggghts` write the scene's
    /// DEM as OUT/dem.yade.py / OUT/dem.liggghts.in and run it (clients/yade, clients/liggghts);
    /// `external` prints the service name and waits for any client that speaks the protocol
    /// (PROTOCOL.md).
    #[arg(long, value_enum, default_value_t = DemMode::Builtin)]
    dem: DemMode,
    /// Starts CMD (through sh) as the DEM side, the run name in $LBMDEM_RUN, the scene in
    /// $LBMDEM_SCENE, clients/python on PYTHONPATH; supervised as dem-client is.
    #[arg(long, value_name = "CMD", conflicts_with = "dem")]
    dem_command: Option<String>,
    /// Longest wait for the DEM side to connect [s] (default: 30 when spawned, unlimited when external).
    #[arg(long)]
    connect_timeout: Option<f64>,
    /// Say everything: each warning in full (what was measured and what to change), the run's
    /// settings, the DEM's step limits and figures, each trial's times, each health check's
    /// dropped covers. Without it a run says a short header, its progress, a line per warning
    /// and its last line.
    #[arg(long, short)]
    verbose: bool,
    /// Steps between two checkpoints (OUT/checkpoint/; overrides `output.checkpoint_interval`;
    /// 0: none by steps). docs/checkpoint.md.
    #[arg(long, value_name = "N")]
    checkpoint_interval: Option<u64>,
    /// Goes on from the last checkpoint in OUT, with the scene of OUT/scene.toml, to its last
    /// step or `--steps`, appending to the outputs there.
    #[arg(long, value_name = "OUT", conflicts_with_all = ["scene", "out"])]
    resume: Option<PathBuf>,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum DemMode {
    #[value(alias = "spawn")]
    Builtin,
    External,
    Yade,
    Liggghts,
}

/// Exit codes.
const EXIT_FAILURE: u8 = 1;
const EXIT_BAD_INPUT: u8 = 2;
const EXIT_INTERRUPTED: u8 = 130;

/// How a run ended without failure: only a completed run exits 0; one stopped before its last
/// step, by Ctrl-C or the DEM's STOP, exits 130.
enum Ending {
    Completed,
    Interrupted,
    StoppedByPeer,
}

/// A run, step by step: Ctrl-C caught, the ranks started, the scene prepared on each, then the
/// fluid alone, or the DEM started on rank 0 and the coupled run (the other ranks following it).
pub fn main(args: RunArgs) -> ExitCode {
    let interrupted = catch_ctrl_c();
    crate::terminal::set_verbose(args.verbose);
    let comm = match crate::parallel::start() {
        Ok(comm) => comm,
        Err(e) => {
            protocol::say!("lbm-server: error: {e}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    let prepared = match prepare_on_every_rank(&args, &*comm) {
        Ok(prepared) => prepared,
        Err(code) => return code,
    };
    if prepared.scene.lattice.is_some() && prepared.scene.particle_count() == 0 {
        return run_fluid_alone(&prepared, interrupted, &*comm);
    }
    let dem = match dem_start_on_rank_0(&args, &prepared, &*comm) {
        Ok(dem) => dem,
        Err(code) => return code,
    };
    let comm: Rc<dyn Communicator> = Rc::from(comm);
    match dem {
        Some(dem) => run_coupled(prepared, dem, interrupted, comm),
        None => follow_rank_0(&prepared, comm),
    }
}

/// Installs the Ctrl-C handler ([`on_ctrl_c`]); the flag it sets once the run has started.
fn catch_ctrl_c() -> Arc<AtomicBool> {
    let interrupted = Arc::new(AtomicBool::new(false));
    let flag = interrupted.clone();
    if let Err(e) = ctrlc::set_handler(move || on_ctrl_c(&flag)) {
        protocol::say!("lbm-server: warning: cannot install the Ctrl-C handler: {e}");
    }
    interrupted
}

/// The scene prepared on every rank, or the exit code where a rank refuses it: every rank checks
/// the same scene; rank 0 alone says why it is refused.
fn prepare_on_every_rank(args: &RunArgs, comm: &dyn Communicator) -> Result<prepare::Prepared, ExitCode> {
    let prepared = prepare(args, comm);
    if !crate::parallel::all(comm, prepared.is_ok()) {
        if let (0, Err(e)) = (comm.rank(), &prepared) {
            protocol::say!("lbm-server: error: {e}");
        }
        return Err(ExitCode::from(EXIT_BAD_INPUT));
    }
    Ok(prepared.expect("prepared on every rank"))
}

/// A scene with a lattice and no particles: the fluid alone (`fluid.rs`).
fn run_fluid_alone(p: &prepare::Prepared, interrupted: Arc<AtomicBool>, comm: &dyn Communicator) -> ExitCode {
    let checkpoints = p.checkpoints_on(comm);
    ExitCode::from(crate::fluid::run(
        &p.scene,
        &p.scene_file,
        p.steps,
        &p.out,
        interrupted,
        comm,
        p.blocks,
        checkpoints,
    ))
}

/// How the DEM side starts, on rank 0 (the DEM joins rank 0; the other ranks follow it:
/// coupled/ranks.rs): Some there, None on the other ranks, or the exit code where rank 0 cannot
/// start it.
fn dem_start_on_rank_0(
    args: &RunArgs,
    prepared: &prepare::Prepared,
    comm: &dyn Communicator,
) -> Result<Option<DemStart>, ExitCode> {
    let dem = match comm.rank() {
        0 => dem_start(args, prepared).map(Some),
        _ => Ok(None),
    };
    if !crate::parallel::all(comm, dem.is_ok()) {
        if let Err(e) = &dem {
            protocol::say!("lbm-server: error: {e}");
        }
        return Err(ExitCode::from(EXIT_BAD_INPUT));
    }
    Ok(dem.expect("agreed"))
}

/// Rank 0's coupled run: the stale runs' files removed, the run named, its session, its files
/// removed.
fn run_coupled(
    prepared: prepare::Prepared,
    dem: DemStart,
    interrupted: Arc<AtomicBool>,
    comm: Rc<dyn Communicator>,
) -> ExitCode {
    protocol::cleanup::remove_stale_runs();
    let run = new_run_name();
    let _ = RUN.set(run.clone());
    let code = Session::start(prepared, &run, dem, interrupted, comm.clone());
    protocol::cleanup::remove_run(&run);
    wait_for_rank_0(&*comm);
    ExitCode::from(code)
}

/// Another rank's part of a coupled run: it follows rank 0 (coupled/ranks.rs).
fn follow_rank_0(p: &prepare::Prepared, comm: Rc<dyn Communicator>) -> ExitCode {
    let code = crate::coupled::follow(&p.scene, p.steps, &p.out, (comm.clone(), p.blocks));
    wait_for_rank_0(&*comm);
    ExitCode::from(code)
}

/// Whether the run is still starting (the scene loaded, the device opened, its kernels compiled:
/// seconds on a CPU driver), with nothing yet to end in order: Ctrl-C then ends the process at
/// once. Over once the DEM is started or the fluid alone steps ([`started`]).
static STARTING: AtomicBool = AtomicBool::new(true);

/// The run's name, for Ctrl-C during start-up to remove the services made under it.
static RUN: OnceLock<String> = OnceLock::new();

/// Ctrl-C (SIGINT, SIGTERM): during start-up the process ends at once (exit 130, no outputs yet
/// but the scene's copy); later the run stops at its next step (`interrupted`).
fn on_ctrl_c(interrupted: &AtomicBool) {
    if STARTING.load(Ordering::SeqCst) {
        protocol::say!("lbm-server: interrupted during start-up");
        if let Some(run) = RUN.get() {
            protocol::cleanup::remove_run(run);
        }
        // _exit: the main thread may be inside the device's driver, whose exit handlers must not
        // run under it.
        unsafe { libc::_exit(i32::from(EXIT_INTERRUPTED)) };
    }
    interrupted.store(true, Ordering::SeqCst);
    crate::parallel::interrupted();
}

/// Start-up is over: Ctrl-C from now on stops the run in order.
pub(crate) fn started() {
    STARTING.store(false, Ordering::SeqCst);
}

/// How the DEM side starts (`--dem`, `--dem-command`); YADE and LIGGGHTS checked and their
/// script / deck written now, before the fluid starts.
fn dem_start(args: &RunArgs, p: &prepare::Prepared) -> Result<DemStart, String> {
    Ok(match (&args.dem_command, args.dem) {
        (Some(line), _) => DemStart::Command(launch::DemCommand::shell(line)),
        (None, DemMode::Builtin) => DemStart::Builtin,
        (None, DemMode::External) => DemStart::External,
        (None, DemMode::Yade) => DemStart::Command(launch::yade(&p.scene_copy, &p.out)?),
        (None, DemMode::Liggghts) => DemStart::Command(launch::liggghts(&p.scene_copy, &p.out)?),
    })
}

impl Session {
    /// The lockstep loop: states(n) in, forces(n) out, until the last step or a step that ends
    /// the run.
    fn step_loop(&mut self) -> Result<Ending, String> {
        let mut si = SiStates::new(self.hello.expect("connected").units);
        let mut replies = Vec::new();
        let mut progress = Progress::new(self.p.steps);
        progress.update(self.first_step);
        self.counters.start();
        for step in self.first_step..self.p.steps {
            if let Some(ending) = self.coupled_step(step, &mut si, &mut replies, &mut progress)? {
                return Ok(ending);
            }
        }
        progress.finish();
        Ok(Ending::Completed)
    }

    /// One coupled step, pass by pass, each timed (`counters.rs`): the DEM's states received
    /// (waiting for the DEM; a checkpoint held for the DEM's part then complete) and read in SI
    /// (exchange), the fluid's answer (fluid: the states checked, the fluid's step, its health
    /// check), how the step ends, the reply sent (exchange; CHECKPOINT where one is due), the
    /// particles written and a checkpoint taken (output); how the run ends where this step ends it.
    fn coupled_step(
        &mut self,
        step: u64,
        si: &mut SiStates,
        replies: &mut Vec<ParticleReply>,
        progress: &mut Progress,
    ) -> Result<Option<Ending>, String> {
        let last = step + 1 == self.p.steps;
        let received = self.receive_states(step)?;
        if self.checkpoints.holding() {
            self.release_checkpoint()?;
        }
        self.counters.lap_waiting_for_dem();
        let states = si.read(&received);
        self.counters.lap_exchange();
        let failure = self.answer(states, step, last, replies);
        self.counters.lap_fluid();
        let count = states.len();
        let header = received.header();
        let end = self.step_end(step, last, header, failure);
        let checkpoint = self.checkpoint_due(step, last, &end);
        if checkpoint {
            self.stage_checkpoint()?;
        }
        si.keep_for_output(&received, end.output);
        drop(received);
        let flags = end.flags(last) | if checkpoint { StepFlags::CHECKPOINT } else { 0 };
        if end.flags(last) != 0 {
            // The reply ends the run: the bar leaves the terminal before the DEM's last line.
            progress.finish();
        }
        self.reply(
            StepHeader::new(step, header.time, count, flags),
            si.units,
            replies,
        )?;
        self.counters.completed(step, count);
        self.counters.lap_exchange();
        let time = header.time * si.units.time_s;
        self.write_particles(step, time, (end.output, checkpoint), si, replies)?;
        progress.update(step + 1);
        self.counters.lap_output();
        let ending = self.end_at(end, last, progress)?;
        if ending.is_some() || last {
            self.finish_checkpoint();
        }
        Ok(ending)
    }

    /// The particles of `step` where `output` says, and where `checkpoint` says the fluid's state
    /// held for a checkpoint, with where the outputs stood: before this step's rows where only a
    /// last or stopped step gets them (a run resumed from it writes what an uninterrupted one does).
    fn write_particles(
        &mut self,
        step: u64,
        time: f64,
        (output, checkpoint): (bool, bool),
        si: &SiStates,
        replies: &[ParticleReply],
    ) -> Result<(), String> {
        // Where the outputs stand is read only for a checkpoint (the per-step path stays as it was).
        let mut at = OutputPositions::default();
        let regular = step.is_multiple_of(self.p.scene.output.interval);
        if checkpoint && !regular {
            self.particles.positions(&mut at);
        }
        if output {
            self.particles.write_step(step, time, &si.states, replies)?;
        }
        if checkpoint {
            if regular {
                self.particles.positions(&mut at);
            }
            self.hold_checkpoint(at, replies.len() as u64)?;
        }
        Ok(())
    }
}
