//! Helpers of the integration tests: find the binaries, write scenes, start and watch processes.
#![allow(dead_code)]

pub mod mpi;

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::mpsc::{channel, Receiver, RecvTimeoutError};
use std::time::{Duration, Instant};

/// A binary of the workspace, built next to the test executable (`cargo build` builds it).
pub fn bin(name: &str) -> PathBuf {
    let exe = std::env::current_exe().expect("test executable path");
    let dir = exe.parent().and_then(Path::parent).expect("target/<profile>");
    let path = dir.join(name);
    assert!(
        path.is_file(),
        "{} is missing: run `cargo build --workspace --bins` first",
        path.display()
    );
    path
}

/// A fresh, empty folder for one test.
pub fn temp_dir(tag: &str) -> PathBuf {
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_nanos();
    let dir = std::env::temp_dir().join(format!("lbmdem-test-{tag}-{}-{nanos}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A coupled scene with a block of `count` spheres, `steps` steps, as TOML text: a box of viscous
/// liquid (1 Pa s) on a lattice of 1 mm cells with tau 0.8 (dt = 0.1 ms), fast on a CPU Vulkan.
///
/// Up to 4 spheres per axis: a 16 mm box (16^3 cells), radius 1.2 mm, 4 mm apart, centred. More:
/// radius 0.3 mm, 1 mm apart, one per cell centre, in a box of max(16, count + 2) mm per axis (the
/// 20 000-sphere block: 42 x 27 x 22 cells). The contacts are a linear spring with a 5 ms contact
/// time, so the DEM takes one step per fluid step whatever the sphere size, and lubrication is off
/// (its one-cell cut-off would pair every sub-cell sphere with its neighbours): these scenes test
/// the coupling's transport, lockstep and failure rules, not contact or lubrication physics.
pub fn scene_text(name: &str, count: [u64; 3], steps: u64, interval: u64, timeout_s: f64) -> String {
    let big = count.iter().any(|&c| c > 4);
    let (spacing_mm, radius_mm) = if big { (1.0, 0.3) } else { (4.0, 1.2) };
    let cells = count.map(|c| if big { (c + 2).max(16) } else { 16 });
    let origin_mm: [f64; 3] = std::array::from_fn(|a| {
        if big {
            ((cells[a] - count[a]) / 2) as f64 + 0.5
        } else {
            0.5 * (cells[a] as f64 - (count[a] - 1) as f64 * spacing_mm)
        }
    });
    let mm = |v: f64| v / 1000.0;
    format!(
        r#"name = "{name}"
[domain]
min = [0.0, 0.0, 0.0]
max = [{}, {}, {}]
[fluid]
density = 1000.0
dynamic_viscosity = 1.0
[time]
steps = {steps}
[lattice]
dx = 0.001
tau = 0.8
velocity_scale = 0.01
[output]
interval = {interval}
[coupling]
timeout = {timeout_s}
lubrication = false
[particles]
density = 2500.0
[[particles.block]]
origin = [{}, {}, {}]
count = [{}, {}, {}]
spacing = {}
radius = {}
[dem.contact]
normal = "linear"
contact_time = 0.005
"#,
        mm(cells[0] as f64),
        mm(cells[1] as f64),
        mm(cells[2] as f64),
        mm(origin_mm[0]),
        mm(origin_mm[1]),
        mm(origin_mm[2]),
        count[0],
        count[1],
        count[2],
        mm(spacing_mm),
        mm(radius_mm),
    )
}

/// Writes a scene file into `dir` and returns its path.
pub fn write_scene(dir: &Path, text: &str) -> PathBuf {
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// How long a test waits for a process it started to print a line, start its DEM or reach a
/// moment of its run. Generous, as a debug build compiles its kernels for lavapipe and a loaded
/// machine (load 10+ on 2 cores) slows its start-up many times over: the wait ends as soon as the
/// line comes, so a test that passes never waits it out. No result is compared against it.
pub const PROCESS_WAIT: Duration = Duration::from_secs(180);

/// A started process whose stderr (and optionally stdout) lines arrive on channels.
pub struct Proc {
    pub child: Child,
    pub stderr: Receiver<String>,
    pub stdout: Receiver<String>,
    pub started: Instant,
    /// The command that started it, program file name and arguments, for messages.
    pub name: String,
}

fn pump(stream: impl std::io::Read + Send + 'static) -> Receiver<String> {
    let (tx, rx) = channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stream).lines().map_while(Result::ok) {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    rx
}

/// Makes the process `cmd` starts die with the thread that starts it (the test's: call this and
/// start processes from the test's own thread, not from a helper thread that ends first), so
/// that a test that ends, passes or fails, or a harness killed at its timeout or by Ctrl-C
/// leaves no process behind (`protocol::liveness::die_with_parent`). With SIGKILL, which ends a
/// stopped process too; mpirun with SIGTERM, which it passes on to its ranks, so that they stop
/// in order (killed, it leaves them to notice its death themselves, about 2 s later). The same
/// command tied twice (`start(server(..))`) is asked twice.
pub fn die_with_test(cmd: &mut Command) -> &mut Command {
    let mpirun = Path::new(cmd.get_program()).ends_with("mpirun");
    let signal = if mpirun { libc::SIGTERM } else { libc::SIGKILL };
    protocol::liveness::die_with_parent(cmd, signal)
}

/// Starts `cmd` in a process group of its own, capturing stdout and stderr; it dies with the
/// test ([`die_with_test`]).
pub fn start(mut cmd: Command) -> Proc {
    use std::os::unix::process::CommandExt;
    die_with_test(&mut cmd)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .stdin(Stdio::null())
        .process_group(0);
    let name = command_name(&cmd);
    let mut child = cmd.spawn().expect("spawn");
    let stderr = pump(child.stderr.take().unwrap());
    let stdout = pump(child.stdout.take().unwrap());
    Proc {
        child,
        stderr,
        stdout,
        started: Instant::now(),
        name,
    }
}

/// `cmd`'s program file name and arguments, as a message names the process.
fn command_name(cmd: &Command) -> String {
    let program = Path::new(cmd.get_program());
    let program = program.file_name().unwrap_or(program.as_os_str());
    std::iter::once(program)
        .chain(cmd.get_args())
        .map(|part| part.to_string_lossy().into_owned())
        .collect::<Vec<_>>()
        .join(" ")
}

impl Proc {
    /// Waits up to [`PROCESS_WAIT`] for a line containing `needle` on the process's stderr;
    /// returns it, or panics naming the process and the line, with what it printed.
    pub fn stderr_line(&self, needle: &str) -> String {
        self.wait_line(&self.stderr, "stderr", needle)
    }

    /// [`Proc::stderr_line`] on the process's stdout.
    pub fn stdout_line(&self, needle: &str) -> String {
        self.wait_line(&self.stdout, "stdout", needle)
    }

    fn wait_line(&self, rx: &Receiver<String>, stream: &str, needle: &str) -> String {
        let deadline = Instant::now() + PROCESS_WAIT;
        let mut seen = Vec::new();
        let closed = loop {
            let Some(left) = deadline.checked_duration_since(Instant::now()) else {
                break false;
            };
            match rx.recv_timeout(left) {
                Ok(line) if line.contains(needle) => return line,
                Ok(line) => seen.push(line),
                Err(RecvTimeoutError::Disconnected) => break true,
                Err(RecvTimeoutError::Timeout) => break false,
            }
        };
        let when = if closed {
            format!("before it closed its {stream}")
        } else {
            format!("on its {stream} within {PROCESS_WAIT:?}")
        };
        panic!(
            "`{}` (pid {}) printed no line containing {needle:?} {when}; saw:\n{}",
            self.name,
            self.child.id(),
            seen.join("\n")
        );
    }

    /// Waits for exit; returns (exit code, seconds waited). Kills and panics after `timeout`.
    pub fn wait_exit(&mut self, timeout: Duration) -> (Option<i32>, f64) {
        let start = Instant::now();
        loop {
            if let Some(status) = self.child.try_wait().unwrap() {
                return (status.code(), start.elapsed().as_secs_f64());
            }
            if start.elapsed() > timeout {
                let _ = self.child.kill();
                panic!(
                    "`{}` (pid {}) did not exit within {timeout:?}",
                    self.name,
                    self.child.id()
                );
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    /// All lines received so far on `rx`.
    pub fn drain(rx: &Receiver<String>) -> String {
        let mut text = String::new();
        while let Ok(line) = rx.recv_timeout(Duration::from_millis(200)) {
            text += &line;
            text.push('\n');
        }
        text
    }
}

/// `lbm-server run SCENE --out OUT extra...`, dying with the test ([`die_with_test`]).
pub fn server(scene: &Path, out: &Path, extra: &[&str]) -> Command {
    let mut cmd = Command::new(bin("lbm-server"));
    die_with_test(&mut cmd)
        .arg("run")
        .arg(scene)
        .arg("--out")
        .arg(out)
        .args(extra);
    cmd
}

/// `lbm-server run SCENE --dem external`: the running server and the run name it printed.
/// Writes the scene `text` into a fresh temporary folder named after `tag`, runs `lbm-server run`
/// on it: (exit code, stderr, the output folder).
pub fn run_scene(tag: &str, text: &str) -> (Option<i32>, String, std::path::PathBuf) {
    run_scene_with(tag, text, &[])
}

/// `run_scene` with `--verbose`: the whole explanations, the run's settings and the DEM's figures.
pub fn run_scene_verbose(tag: &str, text: &str) -> (Option<i32>, String, std::path::PathBuf) {
    run_scene_with(tag, text, &["--verbose"])
}

pub fn run_scene_with(tag: &str, text: &str, extra: &[&str]) -> (Option<i32>, String, std::path::PathBuf) {
    let dir = temp_dir(tag);
    let scene = write_scene(&dir, text);
    let out = dir.join("out");
    let result = server(&scene, &out, extra).output().unwrap();
    (
        result.status.code(),
        String::from_utf8_lossy(&result.stderr).into_owned(),
        out,
    )
}

pub fn start_external(scene: &Path, out: &Path) -> (Proc, String) {
    let server = start(server(scene, out, &["--dem", "external"]));
    let line = server.stdout_line("DEM service:");
    let run = line.split_whitespace().last().expect("a run name").to_string();
    (server, run)
}

/// Reads OUT/summary.json.
pub fn summary(out: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(out.join("summary.json")).expect("summary.json written");
    serde_json::from_str(&text).expect("summary.json is JSON")
}

/// Files of run `run` left in shared memory or under the iceoryx2 root.
pub fn leftover_files(run: &str) -> Vec<PathBuf> {
    let mut found = Vec::new();
    for root in ["/dev/shm", "/tmp/iceoryx2"] {
        collect(Path::new(root), run, &mut found);
    }
    found
}

fn collect(dir: &Path, needle: &str, found: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        if entry.file_type().is_ok_and(|t| t.is_dir()) {
            collect(&entry.path(), needle, found);
        }
        if entry.file_name().to_string_lossy().contains(needle) {
            found.push(entry.path());
        }
    }
}

/// Sends `signal` to a process.
pub fn signal(pid: u32, signal: i32) {
    assert_eq!(
        unsafe { libc::kill(pid as i32, signal) },
        0,
        "kill({pid}, {signal})"
    );
}

/// The first child process of `pid`, if any.
fn first_child(pid: u32) -> Option<u32> {
    let children = std::fs::read_to_string(format!("/proc/{pid}/task/{pid}/children")).unwrap_or_default();
    children.split_whitespace().next().map(|c| c.parse().unwrap())
}

/// Pid of the dem-client started by the lbm-server `server_pid`.
pub fn child_pid(server_pid: u32) -> u32 {
    let deadline = Instant::now() + PROCESS_WAIT;
    while Instant::now() < deadline {
        if let Some(pid) = first_child(server_pid) {
            return pid;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    panic!("lbm-server {server_pid} started no dem-client within {PROCESS_WAIT:?}");
}

/// Pid of the dem-client of the lbm-server `server` once it starts it (its start-up may take a
/// while on a loaded machine); panics with its stderr where it ends first.
pub fn dem_of(server: &mut Proc) -> u32 {
    let pid = server.child.id();
    let deadline = Instant::now() + PROCESS_WAIT;
    while Instant::now() < deadline {
        if let Some(child) = first_child(pid) {
            return child;
        }
        assert!(
            server.child.try_wait().unwrap().is_none(),
            "{}",
            Proc::drain(&server.stderr)
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    panic!("lbm-server {pid} started no dem-client within {PROCESS_WAIT:?}");
}

/// Is the process gone (or a zombie)?
pub fn is_gone(pid: u32) -> bool {
    match std::fs::read_to_string(format!("/proc/{pid}/stat")) {
        Err(_) => true,
        Ok(stat) => stat
            .rsplit(')')
            .next()
            .is_some_and(|rest| rest.trim_start().starts_with(['Z', 'X'])),
    }
}

/// Every row of a run's particles.csv as numbers (step, time, id, x, y, z, vx, vy, vz, ...).
pub fn particle_rows(out: &Path) -> Vec<Vec<f64>> {
    std::fs::read_to_string(out.join("particles.csv"))
        .expect("particles.csv")
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().expect("a number")).collect())
        .collect()
}

/// Every row of the CSV file `path` (a header line, then numbers) as numbers.
pub fn csv_numbers(path: &Path) -> Vec<Vec<f64>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect()
}

/// Rows of particles.csv grouped by step: step -> ids.
pub fn csv_steps(out: &Path) -> std::collections::BTreeMap<u64, Vec<u64>> {
    let text = std::fs::read_to_string(out.join("particles.csv")).expect("particles.csv");
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("step,time,id,x,y,z,vx,vy,vz,wx,wy,wz,fx,fy,fz,tx,ty,tz")
    );
    let mut steps = std::collections::BTreeMap::new();
    for line in lines {
        let cols: Vec<&str> = line.split(',').collect();
        assert_eq!(cols.len(), 18, "row {line}");
        let entry: &mut Vec<u64> = steps.entry(cols[0].parse().unwrap()).or_default();
        entry.push(cols[2].parse().unwrap());
    }
    steps
}

/// The LIGGGHTS adapter, and the Python clients it imports from PYTHONPATH.
pub const LIGGGHTS_ADAPTER: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/clients/liggghts/lbm_liggghts.py");
pub const PYTHON_CLIENTS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/clients/python");

/// Whether LIGGGHTS can be loaded; where it cannot, prints that `test` was skipped and why.
pub fn liggghts_present(test: &str) -> bool {
    let probe = Command::new("python3")
        .args([LIGGGHTS_ADAPTER, "--probe"])
        .env("PYTHONPATH", PYTHON_CLIENTS)
        .output()
        .expect("python3 runs");
    let text = String::from_utf8_lossy(&probe.stderr).into_owned();
    match probe.status.code() {
        Some(0) => true,
        Some(2) => {
            eprintln!("{test}: skipped: {}", text.trim());
            false
        }
        _ => panic!("the adapter's probe failed (iceoryx2 for python3?):\n{text}"),
    }
}

/// A finished process's stdout and stderr, one after the other.
pub fn output_text(output: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    )
}

/// A granular pour alone (`dem-client run`): 150 spheres of two sizes settling in a box, 50
/// steps, rows every 25.
pub const POUR: &str = r#"name = "small-pour"
[domain]
min = [0.0, 0.0, 0.0]
max = [0.03, 0.03, 0.06]
[fluid]
density = 1.2
dynamic_viscosity = 1.8e-5
[time]
dt = 2.0e-3
steps = 50
[output]
interval = 25
[particles]
density = 2500.0
[[dem.material]]
name = "glass"
restitution = 0.5
friction = 0.4
[[dem.insert]]
origin = [0.004, 0.004, 0.004]
count = [5, 5, 6]
spacing = 0.005
radius = [0.0017, 0.002]
jitter = 0.0004
"#;

/// Every file under `dir` but the lock (which holds the pid of the last run) and its bytes.
pub fn files_under(dir: &Path) -> std::collections::BTreeMap<std::path::PathBuf, Vec<u8>> {
    let mut files = std::collections::BTreeMap::new();
    for entry in std::fs::read_dir(dir).unwrap().map(Result::unwrap) {
        let path = entry.path();
        if path.is_dir() {
            files.extend(files_under(&path));
        } else if entry.file_name() != ".lock" {
            files.insert(path.clone(), std::fs::read(&path).unwrap());
        }
    }
    files
}
