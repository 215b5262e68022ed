//! `lbm-server`: the fluid side of the LBM-DEM co-simulation, and its launcher.

mod bench;
mod bench_link;
mod checkpoint;
mod coupled;
mod fields;
mod fluid;
mod launch;
mod lbm;
mod lubrication;
mod output;
mod parallel;
mod run;
mod storage_accuracy;
mod terminal;
mod trials;
mod validate;
mod vtk;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "lbm-server",
    version,
    about = "GPU lattice-Boltzmann fluid of the LBM-DEM co-simulation"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene: start the DEM client, step both in lockstep, write OUT/particles.csv and summary.json.
    Run(run::RunArgs),
    /// Measure lattice updates per second (MLUPS) against this device's copy bandwidth.
    Bench(bench::BenchArgs),
    /// Run the lattice's analytic validation cases and write validation/lbm/REPORT.md.
    Validate(validate::ValidateArgs),
    /// Measure the round trip of one coupling step over iceoryx2 and over a Unix socket.
    BenchLink(bench_link::BenchArgs),
    /// Peer process of bench-link (internal).
    #[command(hide = true)]
    BenchLinkPeer(bench_link::PeerArgs),
}

fn main() -> ExitCode {
    quiet_mesa();
    match Cli::parse().command {
        Command::Run(args) => run::main(args),
        Command::Bench(args) => bench::main(args),
        Command::Validate(args) => validate::main(args),
        Command::BenchLink(args) => bench_link::main(args),
        Command::BenchLinkPeer(args) => bench_link::peer(args),
    }
}

/// Mesa's software Vulkan prints "XDG_RUNTIME_DIR is invalid" twice unless this is set; done
/// before any thread starts.
fn quiet_mesa() {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() && std::env::var_os("NODEVICE_SELECT").is_none() {
        std::env::set_var("NODEVICE_SELECT", "1");
    }
}
