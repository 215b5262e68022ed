//! `lbm-server bench-link`: placeholder filled below.
#[derive(clap::Args)]
pub struct BenchArgs {}
#[derive(clap::Args)]
pub struct PeerArgs {}
pub fn main(_: BenchArgs) -> std::process::ExitCode { std::process::ExitCode::FAILURE }
pub fn peer(_: PeerArgs) -> std::process::ExitCode { std::process::ExitCode::FAILURE }
