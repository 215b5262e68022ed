//! `lbm-server bench-link`: the round trip of one coupling step over iceoryx2 and over a Unix
//! socket, side by side.
//!
//! Both transports are measured between two real processes: this one plays the DEM side and times
//! each round, `lbm-server bench-link-peer` (this executable, spawned) plays the fluid side. One
//! round is what a coupled step costs the link: the DEM writes N particle states (a 32-byte
//! `StepHeader` and N x 88 bytes), the fluid reads them and answers with N replies (32 + N x 56
//! bytes) computed from them, the DEM reads every reply. Filling the states and reading the
//! replies are inside the timed region for both transports: over iceoryx2 the states are written
//! straight into shared memory, over the socket into a buffer that the kernel then copies.

mod iceoryx;
mod peer_process;
mod socket;

use iceoryx::{measure_iceoryx2, serve_iceoryx2};
use protocol::{ParticleReply, ParticleState, StepHeader};
use socket::{measure_socket, serve_socket};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};

/// Particle counts measured when `--particles` is not given.
const DEFAULT_PARTICLES: [usize; 4] = [1, 1000, 20_000, 100_000];

/// The line a peer prints on stdout once its iceoryx2 services exist.
const READY: &str = "ready";

/// Arguments of `lbm-server bench-link`.
#[derive(clap::Args)]
pub struct BenchArgs {
    /// Particle counts to measure, comma separated.
    #[arg(long, value_delimiter = ',', default_values_t = DEFAULT_PARTICLES)]
    particles: Vec<usize>,
    /// Timed rounds per particle count and transport [default: 2000, down to 300 for 100,000
    /// particles].
    #[arg(long)]
    rounds: Option<usize>,
    /// Untimed warm-up rounds before the timed ones.
    #[arg(long, default_value_t = 50)]
    warmup: usize,
    /// Longest wait for the peer process to answer [s].
    #[arg(long, default_value_t = 10.0)]
    timeout: f64,
}

/// Arguments of the hidden `lbm-server bench-link-peer`: the fluid side of one measurement.
#[derive(clap::Args)]
pub struct PeerArgs {
    /// iceoryx2 mode: create the services of this run and answer its steps.
    #[arg(long, conflicts_with = "socket", required_unless_present = "socket")]
    service: Option<String>,
    /// Socket mode: connect to this Unix socket and answer until it closes.
    #[arg(long)]
    socket: Option<PathBuf>,
    /// Most particles per step.
    #[arg(long)]
    capacity: usize,
    /// iceoryx2 mode: number of steps before the closing STOP message.
    #[arg(long, default_value_t = 0)]
    steps: u64,
    /// Longest wait for the benchmark process [s].
    #[arg(long, default_value_t = 10.0)]
    timeout: f64,
}

/// Runs the benchmark and prints the Markdown table on stdout.
pub fn main(args: BenchArgs) -> ExitCode {
    match bench(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            protocol::say!("lbm-server bench-link: error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Answers one measurement's rounds as the fluid side.
pub fn peer(args: PeerArgs) -> ExitCode {
    let result = match (&args.service, &args.socket) {
        (Some(run), _) => serve_iceoryx2(run, &args),
        (None, Some(path)) => serve_socket(path, &args),
        (None, None) => Err("give --service or --socket".to_string()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            protocol::say!("lbm-server bench-link-peer: error: {e}");
            ExitCode::FAILURE
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The benchmark process (DEM side)
// ---------------------------------------------------------------------------------------------

/// What one transport measured for one particle count, in microseconds.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Stats {
    median_us: f64,
    p99_us: f64,
}

/// One line of the table.
struct Row {
    particles: usize,
    rounds: usize,
    iceoryx2: Stats,
    socket: Stats,
}

/// Settings shared by every measurement.
struct Plan {
    exe: PathBuf,
    warmup: usize,
    timeout: Duration,
}

fn bench(args: &BenchArgs) -> Result<(), String> {
    let plan = plan(args)?;
    let mut rows = Vec::new();
    for &n in &args.particles {
        let rounds = args.rounds.unwrap_or_else(|| default_rounds(n));
        protocol::say!("bench-link: {n} particles, {rounds} rounds: iceoryx2 ...");
        let iceoryx2 = stats(measure_iceoryx2(&plan, n, rounds)?);
        protocol::say!("bench-link: {n} particles, {rounds} rounds: Unix socket ...");
        let socket = stats(measure_socket(&plan, n, rounds)?);
        rows.push(Row {
            particles: n,
            rounds,
            iceoryx2,
            socket,
        });
    }
    print!("{}", table(&rows));
    println!();
    println!("{}", machine_line());
    println!(
        "rounds per transport: {} timed after {} warm-up",
        rows.iter()
            .map(|r| r.rounds.to_string())
            .collect::<Vec<_>>()
            .join(" / "),
        plan.warmup
    );
    Ok(())
}

/// Checks the arguments and finds this executable (the peer).
fn plan(args: &BenchArgs) -> Result<Plan, String> {
    if args.particles.is_empty() || args.particles.contains(&0) {
        return Err("--particles: give one or more counts, each at least 1".into());
    }
    if args.rounds == Some(0) {
        return Err("--rounds = 0: must be at least 1".into());
    }
    let timeout = Duration::try_from_secs_f64(args.timeout)
        .ok()
        .filter(|t| !t.is_zero())
        .ok_or_else(|| format!("--timeout = {} s: must be > 0", args.timeout))?;
    let exe = std::env::current_exe().map_err(|e| format!("cannot find this executable: {e}"))?;
    Ok(Plan {
        exe,
        warmup: args.warmup,
        timeout,
    })
}

/// About 30 million particle round trips per transport: 2000 rounds for small counts, 300 at
/// 100,000 particles.
fn default_rounds(particles: usize) -> usize {
    (30_000_000 / particles.max(1)).clamp(300, 2000)
}

/// Something that performs one timed round: states of `step` out, replies back.
trait RoundTrip {
    fn round(&mut self, step: u64) -> Result<(), String>;
}

/// Runs `warmup` untimed rounds, then `rounds` timed ones; returns their durations in us.
fn time_rounds(link: &mut impl RoundTrip, warmup: usize, rounds: usize) -> Result<Vec<f64>, String> {
    for step in 0..warmup as u64 {
        link.round(step)?;
    }
    let mut times = Vec::with_capacity(rounds);
    for step in warmup as u64..(warmup + rounds) as u64 {
        let start = Instant::now();
        link.round(step)?;
        times.push(start.elapsed().as_secs_f64() * 1e6);
    }
    Ok(times)
}

/// Median and p99 (nearest rank) of round times.
fn stats(mut times: Vec<f64>) -> Stats {
    times.sort_by(f64::total_cmp);
    Stats {
        median_us: percentile(&times, 0.5),
        p99_us: percentile(&times, 0.99),
    }
}

/// The nearest-rank `q` quantile of sorted, non-empty `values`.
fn percentile(sorted: &[f64], q: f64) -> f64 {
    let rank = (q * sorted.len() as f64).ceil() as usize;
    sorted[rank.clamp(1, sorted.len()) - 1]
}

/// The state the benchmark sends for particle `i` at `step`.
fn state(i: usize, step: u64) -> ParticleState {
    let x = i as f64 * 1e-3;
    ParticleState {
        id: i as u64,
        position: [x, 0.5, step as f64 * 1e-6],
        velocity: [0.0, -0.01, x],
        angular_velocity: [0.0, 0.0, 1.0],
        radius: 1e-3,
    }
}

/// Reads every reply (sums forces and torques) and checks they answer particles 0..n in order.
fn touch_replies(replies: &[ParticleReply], n: usize) -> Result<(), String> {
    let mut sum = 0.0;
    let mut misordered = false;
    for (i, r) in replies.iter().enumerate() {
        sum += r.force[0] + r.force[1] + r.force[2] + r.torque[0] + r.torque[1] + r.torque[2];
        misordered |= r.id != i as u64;
    }
    std::hint::black_box(sum);
    if replies.len() != n || misordered {
        return Err(format!(
            "the peer answered {} replies out of order (of {n} particles)",
            replies.len()
        ));
    }
    Ok(())
}

/// The fluid's answer to one state: computed from all of it, so every byte is read.
fn reply_for(s: &ParticleState) -> ParticleReply {
    let r = s.radius;
    ParticleReply {
        id: s.id,
        force: [
            -r * s.velocity[0] + s.position[0],
            -r * s.velocity[1] + s.position[1],
            -r * s.velocity[2] + s.position[2],
        ],
        torque: s.angular_velocity.map(|w| -r * w),
    }
}

// --- output ---------------------------------------------------------------------------------------

/// The result table in Markdown.
fn table(rows: &[Row]) -> String {
    let mut out = String::from(
        "| particles | bytes out | bytes back | iceoryx2 median us | iceoryx2 p99 us | socket median us \
         | socket p99 us | speedup socket/iceoryx2 (median) |\n\
         |---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for r in rows {
        let header = std::mem::size_of::<StepHeader>();
        let out_bytes = header + r.particles * std::mem::size_of::<ParticleState>();
        let back_bytes = header + r.particles * std::mem::size_of::<ParticleReply>();
        out.push_str(&format!(
            "| {} | {} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.2}x |\n",
            r.particles,
            out_bytes,
            back_bytes,
            r.iceoryx2.median_us,
            r.iceoryx2.p99_us,
            r.socket.median_us,
            r.socket.p99_us,
            r.socket.median_us / r.iceoryx2.median_us
        ));
    }
    out
}

/// `machine: 2 cores, Linux 6.1.0, <CPU model>`.
fn machine_line() -> String {
    let cores = std::thread::available_parallelism().map_or("?".to_string(), |n| n.to_string());
    let read = |path: &str| std::fs::read_to_string(path).map(|s| s.trim().to_string()).ok();
    let os = read("/proc/sys/kernel/ostype").unwrap_or_else(|| std::env::consts::OS.to_string());
    let release = read("/proc/sys/kernel/osrelease").unwrap_or_else(|| "?".to_string());
    let cpu = read("/proc/cpuinfo")
        .and_then(|info| {
            info.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, name)| name.trim().to_string())
        })
        .map_or(String::new(), |name| format!(", {name}"));
    format!("machine: {cores} cores (nproc), {os} {release}{cpu}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_are_nearest_rank() {
        let values: Vec<f64> = (1..=100).map(f64::from).collect();
        assert_eq!(percentile(&values, 0.5), 50.0);
        assert_eq!(percentile(&values, 0.99), 99.0);
        assert_eq!(percentile(&[7.0], 0.99), 7.0);
        let s = stats(vec![3.0, 1.0, 2.0]);
        assert_eq!(
            s,
            Stats {
                median_us: 2.0,
                p99_us: 3.0
            }
        );
    }

    #[test]
    fn default_rounds_shrink_for_large_counts() {
        assert_eq!(default_rounds(1), 2000);
        assert_eq!(default_rounds(1000), 2000);
        assert_eq!(default_rounds(20_000), 1500);
        assert_eq!(default_rounds(100_000), 300);
    }

    #[test]
    fn table_counts_header_and_particle_bytes() {
        let s = Stats {
            median_us: 10.0,
            p99_us: 20.0,
        };
        let row = Row {
            particles: 1000,
            rounds: 1,
            iceoryx2: s,
            socket: Stats {
                median_us: 30.0,
                p99_us: 40.0,
            },
        };
        let text = table(&[row]);
        assert!(
            text.contains("| 1000 | 88032 | 56032 | 10.0 | 20.0 | 30.0 | 40.0 | 3.00x |"),
            "{text}"
        );
    }
}
