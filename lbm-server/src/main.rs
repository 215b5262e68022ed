//! `lbm-server`: the fluid side of the LBM-DEM co-simulation, and its launcher.

mod bench_link;
mod lbm;
mod launch;
mod output;
mod run;
mod standin;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser)]
#[command(name = "lbm-server", version, about = "GPU lattice-Boltzmann fluid of the LBM-DEM co-simulation")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene: start the DEM client, step both in lockstep, write OUT/particles.csv and summary.json.
    Run(run::RunArgs),
    /// Measure the round trip of one coupling step over iceoryx2 and over a Unix socket.
    BenchLink(bench_link::BenchArgs),
    /// Peer process of bench-link (internal).
    #[command(hide = true)]
    BenchLinkPeer(bench_link::PeerArgs),
}

fn main() -> ExitCode {
    match Cli::parse().command {
        Command::Run(args) => run::main(args),
        Command::BenchLink(args) => bench_link::main(args),
        Command::BenchLinkPeer(args) => bench_link::peer(args),
    }
}
