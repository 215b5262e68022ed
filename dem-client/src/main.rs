//! `dem-client`: the particle side of the co-simulation.
//!
//! A soft-sphere DEM in f64 (nalgebra, rayon): `run` steps a granular scene alone, `connect` joins
//! a running `lbm-server` as the DEM side of the co-simulation. See docs/dem.md.

mod bench;
mod checkpoint;
mod connect;
mod dem;
mod lockstep;
mod output;
mod run;
mod run_checkpoint;

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

#[derive(Parser)]
#[command(
    name = "dem-client",
    version,
    about = "DEM particle solver of the LBM-DEM co-simulation"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Join a running `lbm-server` as its DEM side.
    Connect(connect::ConnectArgs),
    /// Run a granular scene alone (no fluid): particles.csv, energy.csv, VTK polydata.
    Run(run::RunArgs),
    /// Time the DEM side of a coupled scene, the fluid replaced by a stand-in.
    Bench(bench::BenchArgs),
}

/// Scene file argument shared by subcommands.
pub fn scene_or_default(path: Option<&PathBuf>) -> Result<scene::Scene, scene::SceneError> {
    match path {
        Some(p) => scene::Scene::load(p),
        None => Ok(scene::Scene::default_scene()),
    }
}

/// Says the scene's warnings (a box that does nothing), where this process runs the scene alone
/// (`run`, `bench`); a coupled run's lbm-server says them, not the dem-client it starts.
pub fn say_scene_warnings(scene: &scene::Scene) {
    for warning in &scene.warnings {
        protocol::say!("dem-client: warning: {warning}");
    }
}

/// Installs `on_ctrl_c` as the handler of Ctrl-C (SIGINT, SIGTERM), given the flag it sets;
/// the flag, which the run looks at to stop in order.
pub fn catch_ctrl_c(on_ctrl_c: fn(&AtomicBool)) -> Arc<AtomicBool> {
    let interrupted = Arc::new(AtomicBool::new(false));
    let flag = interrupted.clone();
    if let Err(e) = ctrlc::set_handler(move || on_ctrl_c(&flag)) {
        protocol::say!("dem-client: warning: cannot install the Ctrl-C handler: {e}");
    }
    interrupted
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Connect(args) => connect::main(args),
        Command::Run(args) => run::main(args),
        Command::Bench(args) => bench::main(args),
    }
}
