//! `lbm-server run`: load a scene, start (or wait for) the DEM side, step in lockstep, write output.
//!
//! A coupled run, file by file, in the order it happens:
//! - `prepare.rs`: the scene loaded and checked, its output folder made ([`prepare`]).
//! - `session.rs`: the run in progress ([`Session`]): opened, connected to the DEM (the handshake,
//!   with the fluid's answer to its Hello in `welcome.rs`), finished.
//! - `lockstep.rs`: the coupled step, as a list of named passes (`Session::coupled_step`); the
//!   fluid's answer to a step's states in `answer.rs`.
//! - `counters.rs`: what the run counts, and where its wall time goes (summary.json's `time_s`).
//! - `summary.rs`: summary.json.
//!
//! A scene with a lattice and no particles runs the fluid alone (`fluid.rs`).

mod answer;
mod counters;
mod lockstep;
mod prepare;
mod session;
mod summary;
mod welcome;

use prepare::prepare;
use protocol::transport::new_run_name;
use session::Session;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

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
