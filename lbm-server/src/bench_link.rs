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

use protocol::transport::{new_run_name, LinkOptions};
use protocol::{
    DemLink, FluidLink, Hello, ParticleReply, ParticleState, Physics, StepFlags, StepHeader, Units, Welcome,
};
use std::io::{BufRead, BufReader, IoSlice, Read, Write};
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdout, Command, ExitCode, Stdio};
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

// --- iceoryx2 ---------------------------------------------------------------------------------

/// The DEM end of the iceoryx2 link.
struct IceoryxBench {
    link: DemLink,
    n: usize,
}

impl RoundTrip for IceoryxBench {
    fn round(&mut self, step: u64) -> Result<(), String> {
        let header = StepHeader::new(step, 0.0, self.n, 0);
        self.link
            .send_states(header, |i| state(i, step))
            .map_err(|e| e.to_string())?;
        let received = self.link.receive_forces(step).map_err(|e| e.to_string())?;
        touch_replies(received.particles(), self.n)
    }
}

/// Times `rounds` rounds of `n` particles over iceoryx2 against a spawned peer.
fn measure_iceoryx2(plan: &Plan, n: usize, rounds: usize) -> Result<Vec<f64>, String> {
    let run = new_run_name();
    let result = run_iceoryx2(plan, &run, n, rounds);
    protocol::cleanup::remove_run(&run);
    result
}

fn run_iceoryx2(plan: &Plan, run: &str, n: usize, rounds: usize) -> Result<Vec<f64>, String> {
    let steps = (plan.warmup + rounds) as u64;
    let mut peer = PeerProcess::spawn(
        &plan.exe,
        &[
            "--service".into(),
            run.into(),
            "--capacity".into(),
            n.to_string(),
            "--steps".into(),
            steps.to_string(),
            "--timeout".into(),
            plan.timeout.as_secs_f64().to_string(),
        ],
    )?;
    peer.wait_ready()?;
    let options = LinkOptions {
        run: run.to_string(),
        timeout: plan.timeout,
    };
    let hello = Hello::new(Units::SI, Physics::BALLISTIC_STANDIN, n, "lbm-server bench-link");
    let (link, _welcome) = DemLink::connect(options, hello).map_err(|e| format!("iceoryx2: {e}"))?;
    let mut bench = IceoryxBench { link, n };
    let times = time_rounds(&mut bench, plan.warmup, rounds).map_err(|e| format!("iceoryx2: {e}"))?;
    // The STOP step ends the peer; the link stays open until it has read it and exited.
    let stop = StepHeader::new(steps, 0.0, 0, StepFlags::STOP);
    bench
        .link
        .send_states(stop, |i| state(i, steps))
        .map_err(|e| format!("iceoryx2: {e}"))?;
    peer.finish(plan.timeout)?;
    Ok(times)
}

/// The fluid end of the iceoryx2 link: `--steps` steps, then the benchmark's STOP.
fn serve_iceoryx2(run: &str, args: &PeerArgs) -> Result<(), String> {
    let timeout = peer_timeout(args.timeout)?;
    let options = LinkOptions {
        run: run.to_string(),
        timeout,
    };
    let mut link = FluidLink::create(options, args.capacity).map_err(|e| e.to_string())?;
    announce_ready()?;
    let bench_pid = std::os::unix::process::parent_id();
    link.accept(Some(bench_pid), timeout, &|| false, |_hello| {
        let mut welcome = Welcome::accepted("lbm-server bench-link-peer");
        welcome.steps = args.steps;
        welcome.dt = 1.0;
        welcome
    })
    .map_err(|e| e.to_string())?;
    for step in 0..args.steps {
        let received = link.receive_states(step).map_err(|e| e.to_string())?;
        let states = received.particles();
        let header = StepHeader::new(step, received.header().time, states.len(), 0);
        link.send_forces(header, |i| reply_for(&states[i]))
            .map_err(|e| e.to_string())?;
    }
    let last = link.receive_states(args.steps).map_err(|e| e.to_string())?;
    if !last.header().has(StepFlags::STOP) {
        return Err(format!("step {} came without the STOP flag", args.steps));
    }
    Ok(())
}

/// Tells the benchmark process that the services exist.
fn announce_ready() -> Result<(), String> {
    let mut out = std::io::stdout().lock();
    writeln!(out, "{READY}")
        .and_then(|()| out.flush())
        .map_err(|e| format!("stdout: {e}"))
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

// --- Unix socket --------------------------------------------------------------------------------

/// The DEM end of the socket link, with buffers reused across rounds.
struct SocketBench {
    stream: UnixStream,
    states: Vec<ParticleState>,
    replies: Vec<ParticleReply>,
}

impl RoundTrip for SocketBench {
    fn round(&mut self, step: u64) -> Result<(), String> {
        let n = self.states.len();
        for (i, s) in self.states.iter_mut().enumerate() {
            *s = state(i, step);
        }
        let header = StepHeader::new(step, 0.0, n, 0);
        let io = |e: std::io::Error| format!("Unix socket, step {step}: {e}");
        write_parts(
            &mut self.stream,
            [bytes(std::slice::from_ref(&header)), bytes(&self.states)],
        )
        .map_err(io)?;
        let mut back = StepHeader::default();
        self.stream
            .read_exact(bytes_mut(std::slice::from_mut(&mut back)))
            .map_err(io)?;
        if back.step != step || back.count != n as u64 {
            return Err(format!(
                "Unix socket: step {step} of {n} answered as step {} of {}",
                back.step, back.count
            ));
        }
        self.stream.read_exact(bytes_mut(&mut self.replies)).map_err(io)?;
        touch_replies(&self.replies, n)
    }
}

/// Times `rounds` rounds of `n` particles over a Unix socket against a spawned peer.
fn measure_socket(plan: &Plan, n: usize, rounds: usize) -> Result<Vec<f64>, String> {
    let dir = TempDir::create()?;
    let path = dir.0.join("link.sock");
    let listener =
        UnixListener::bind(&path).map_err(|e| format!("cannot listen on {}: {e}", path.display()))?;
    let mut peer = PeerProcess::spawn(
        &plan.exe,
        &[
            "--socket".into(),
            path.display().to_string(),
            "--capacity".into(),
            n.to_string(),
            "--timeout".into(),
            plan.timeout.as_secs_f64().to_string(),
        ],
    )?;
    let stream = accept_peer(&listener, &mut peer, plan.timeout)?;
    let mut bench = SocketBench {
        stream,
        states: vec![ParticleState::default(); n],
        replies: vec![ParticleReply::default(); n],
    };
    let times = time_rounds(&mut bench, plan.warmup, rounds).map_err(|e| peer.explain(e))?;
    drop(bench); // end of stream: the peer exits
    peer.finish(plan.timeout)?;
    Ok(times)
}

/// Waits for the peer to connect, noticing if it exits first.
fn accept_peer(
    listener: &UnixListener,
    peer: &mut PeerProcess,
    timeout: Duration,
) -> Result<UnixStream, String> {
    let failed = |e: std::io::Error| format!("Unix socket: accept failed: {e}");
    listener.set_nonblocking(true).map_err(failed)?;
    let start = Instant::now();
    loop {
        match listener.accept() {
            Ok((stream, _)) => {
                stream.set_nonblocking(false).map_err(failed)?;
                stream.set_read_timeout(Some(timeout)).map_err(failed)?;
                return Ok(stream);
            }
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {}
            Err(e) => return Err(failed(e)),
        }
        peer.check_running()?;
        if start.elapsed() >= timeout {
            return Err(format!(
                "the peer did not connect within {:.1} s",
                timeout.as_secs_f64()
            ));
        }
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// The fluid end of the socket link: answers each step until the benchmark closes the socket.
fn serve_socket(path: &Path, args: &PeerArgs) -> Result<(), String> {
    let timeout = peer_timeout(args.timeout)?;
    let mut stream =
        UnixStream::connect(path).map_err(|e| format!("cannot connect to {}: {e}", path.display()))?;
    stream
        .set_read_timeout(Some(timeout))
        .map_err(|e| e.to_string())?;
    let mut states = Vec::with_capacity(args.capacity);
    let mut replies = Vec::with_capacity(args.capacity);
    let mut header = StepHeader::default();
    loop {
        match stream.read_exact(bytes_mut(std::slice::from_mut(&mut header))) {
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => return Ok(()),
            other => other.map_err(|e| format!("reading a step header: {e}"))?,
        }
        let n = header.count as usize;
        if n > args.capacity {
            return Err(format!(
                "step {} carries {n} particles, capacity {}",
                header.step, args.capacity
            ));
        }
        states.resize(n, ParticleState::default());
        stream
            .read_exact(bytes_mut(&mut states))
            .map_err(|e| format!("reading step {}: {e}", header.step))?;
        replies.clear();
        replies.extend(states.iter().map(reply_for));
        let back = StepHeader::new(header.step, header.time, n, 0);
        write_parts(&mut stream, [bytes(std::slice::from_ref(&back)), bytes(&replies)])
            .map_err(|e| format!("answering step {}: {e}", header.step))?;
    }
}

/// Writes both parts with as few system calls as the socket allows (one, if its buffer has room).
fn write_parts(stream: &mut UnixStream, parts: [&[u8]; 2]) -> std::io::Result<()> {
    let mut slices = parts.map(IoSlice::new);
    let mut rest = &mut slices[..];
    while !rest.is_empty() {
        match stream.write_vectored(rest) {
            Ok(0) => return Err(std::io::ErrorKind::WriteZero.into()),
            Ok(written) => IoSlice::advance_slices(&mut rest, written),
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(())
}

/// Wire structs that can be viewed as bytes and filled from bytes.
///
/// # Safety
/// Implementors are `#[repr(C)]`, made only of `u64` and `f64` fields, without padding (see the
/// layout tests in `protocol::wire`): every byte is initialised and every byte pattern is valid.
unsafe trait Plain: Copy {}
unsafe impl Plain for ParticleState {}
unsafe impl Plain for ParticleReply {}
unsafe impl Plain for StepHeader {}

fn bytes<T: Plain>(items: &[T]) -> &[u8] {
    // SAFETY: see `Plain`; the length is the slice's size in bytes.
    unsafe { std::slice::from_raw_parts(items.as_ptr().cast(), std::mem::size_of_val(items)) }
}

fn bytes_mut<T: Plain>(items: &mut [T]) -> &mut [u8] {
    // SAFETY: see `Plain`; any bytes written leave valid values.
    unsafe { std::slice::from_raw_parts_mut(items.as_mut_ptr().cast(), std::mem::size_of_val(items)) }
}

/// A private folder for the socket, removed on drop.
struct TempDir(PathBuf);

impl TempDir {
    fn create() -> Result<Self, String> {
        let path = std::env::temp_dir().join(format!("lbm-bench-link-{}", new_run_name()));
        std::fs::create_dir(&path).map_err(|e| format!("cannot create {}: {e}", path.display()))?;
        Ok(Self(path))
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

// --- the peer process -----------------------------------------------------------------------------

/// A running `bench-link-peer`; killed and reaped on drop if it has not exited by then.
struct PeerProcess {
    child: Child,
    stdout: BufReader<ChildStdout>,
}

impl PeerProcess {
    fn spawn(exe: &Path, args: &[String]) -> Result<Self, String> {
        let mut child = Command::new(exe)
            .arg("bench-link-peer")
            .args(args)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .spawn()
            .map_err(|e| format!("cannot start the peer process {}: {e}", exe.display()))?;
        let stdout = child.stdout.take().expect("stdout is piped");
        Ok(Self {
            child,
            stdout: BufReader::new(stdout),
        })
    }

    /// Waits for the peer's ready line; if it ends instead, says how it ended.
    fn wait_ready(&mut self) -> Result<(), String> {
        let mut line = String::new();
        let read = self.stdout.read_line(&mut line);
        if matches!(read, Ok(n) if n > 0) && line.trim() == READY {
            return Ok(());
        }
        let status = self
            .child
            .wait()
            .map_err(|e| format!("waiting for the peer: {e}"))?;
        Err(format!(
            "the peer process failed to start ({status}; its error is above)"
        ))
    }

    /// An error if the peer has already exited.
    fn check_running(&mut self) -> Result<(), String> {
        match self.child.try_wait() {
            Ok(None) => Ok(()),
            Ok(Some(status)) => Err(format!("the peer process ended ({status})")),
            Err(e) => Err(format!("cannot watch the peer process: {e}")),
        }
    }

    /// Adds to `error` how the peer ended, if it ends within a moment (a closed socket can be
    /// seen a little before its process has exited).
    fn explain(&mut self, error: String) -> String {
        let start = Instant::now();
        while start.elapsed() < Duration::from_millis(200) {
            if let Err(ended) = self.check_running() {
                return format!("{error}; {ended}");
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        error
    }

    /// Waits up to `grace` for the peer to exit by itself; an error unless it exited with 0.
    fn finish(mut self, grace: Duration) -> Result<(), String> {
        match crate::launch::end_child(&mut self.child, grace) {
            Some(0) => Ok(()),
            Some(code) => Err(format!(
                "the peer process exited with code {code} (its error is above)"
            )),
            None => Err("the peer process did not exit by itself and was killed".into()),
        }
    }
}

impl Drop for PeerProcess {
    fn drop(&mut self) {
        if matches!(self.child.try_wait(), Ok(None)) {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

fn peer_timeout(seconds: f64) -> Result<Duration, String> {
    Duration::try_from_secs_f64(seconds).map_err(|_| format!("--timeout = {seconds} s: must be >= 0"))
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

    #[test]
    fn plain_views_cover_the_whole_struct() {
        let mut header = StepHeader::new(3, 0.5, 7, 0);
        assert_eq!(bytes(std::slice::from_ref(&header)).len(), 32);
        bytes_mut(std::slice::from_mut(&mut header))[..8].copy_from_slice(&9u64.to_ne_bytes());
        assert_eq!(header.step, 9);
    }
}
