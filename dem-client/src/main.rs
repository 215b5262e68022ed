//! `dem-client`: the particle side of the co-simulation.
//!
//! Until the DEM physics issue lands, the particles move by a stand-in rule (ballistic flight under
//! gravity and the fluid's force, elastic reflection at the domain faces), named as such everywhere.

mod connect;
mod standin;

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

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
}

/// Scene file argument shared by subcommands.
pub fn scene_or_default(path: Option<&PathBuf>) -> Result<scene::Scene, scene::SceneError> {
    match path {
        Some(p) => scene::Scene::load(p),
        None => Ok(scene::Scene::default_scene()),
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Connect(args) => connect::main(args),
    }
}
