//! A dead, suspended or silent and idle peer ends the run within a second, named, with outputs kept;
//! a silent peer that works is waited for, up to 60 x the timeout; Ctrl-C stops both processes
//! cleanly; shared-memory files never outlive a run.

mod common;
use common::*;
use std::sync::{RwLock, RwLockReadGuard, RwLockWriteGuard};
use std::time::Duration;

/// The tests that keep a core spinning for seconds run alone; the others, which time how fast a
/// failure is noticed, together.
static CORES: RwLock<()> = RwLock::new(());

fn shared_cores() -> RwLockReadGuard<'static, ()> {
    CORES.read().unwrap_or_else(|e| e.into_inner())
}

fn a_core_to_spin() -> RwLockWriteGuard<'static, ()> {
    CORES.write().unwrap_or_else(|e| e.into_inner())
}

/// Starts a long run (spawned DEM) and waits until it is stepping; returns (server, dem pid, out).
fn long_run(tag: &str, timeout_s: f64) -> (Proc, u32, std::path::PathBuf) {
    long_run_of(tag, &scene_text(tag, [4, 4, 4], 10_000_000, 1000, timeout_s))
}

/// Starts the long run of the scene `text`, as `long_run`.
fn long_run_of(tag: &str, text: &str) -> (Proc, u32, std::path::PathBuf) {
    let dir = temp_dir(tag);
    let scene = write_scene(&dir, text);
    let out = dir.join("out");
    let server = start(server(&scene, &out, &[]));
    server.stderr_line("lbm-server: scene");
    std::thread::sleep(Duration::from_millis(300));
    let dem = child_pid(server.child.id());
    (server, dem, out)
}

/// The server's stderr must name the DEM and the last completed step, and its summary agree.
fn assert_failure_reported(server: &mut Proc, out: &std::path::Path, words: &str) -> String {
    let stderr = Proc::drain(&server.stderr);
    assert!(stderr.contains("the DEM client"), "peer not named:\n{stderr}");
    assert!(stderr.contains(words), "expected {words:?}:\n{stderr}");
    let last: u64 = stderr
        .split("last completed step: ")
        .nth(1)
        .and_then(|rest| rest.split_whitespace().next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no last completed step in:\n{stderr}"));
    let s = summary(out);
    assert_eq!(s["last_completed_step"], last);
    assert!(s["exit_reason"].as_str().unwrap().starts_with("error: "), "{s}");
    let rows = std::fs::read_to_string(out.join("particles.csv")).unwrap();
    assert!(rows.lines().count() > 1, "particles.csv was flushed:\n{rows}");
    stderr
}

#[test]
fn killed_dem_is_noticed_within_a_second() {
    let _cores = shared_cores();
    let (mut server, dem, out) = long_run("kill-dem", 30.0);
    signal(dem, libc::SIGKILL);
    let (code, waited) = server.wait_exit(Duration::from_secs(10));
    assert_eq!(code, Some(1));
    assert!(waited < 1.0, "lbm-server took {waited:.3} s to notice");
    assert_failure_reported(&mut server, &out, "died");
}

#[test]
fn killed_server_is_noticed_by_the_dem_within_a_second() {
    let _cores = shared_cores();
    let (mut server, dem, out) = long_run("kill-server", 30.0);
    let run = wait_summary_run(&out, &mut server);
    signal(server.child.id(), libc::SIGKILL);
    let start = std::time::Instant::now();
    server.wait_exit(Duration::from_secs(5));
    while !is_gone(dem) && start.elapsed() < Duration::from_secs(10) {
        std::thread::sleep(Duration::from_millis(5));
    }
    let waited = start.elapsed().as_secs_f64();
    assert!(waited < 1.0, "dem-client took {waited:.3} s to notice");
    let stderr = Proc::drain(&server.stderr);
    assert!(
        stderr.contains("dem-client: error: the fluid server (lbm-server)"),
        "{stderr}"
    );
    assert!(stderr.contains("died; last completed step: "), "{stderr}");
    // The crashed run left files; the next run removes them.
    let dir = temp_dir("after-crash");
    let scene = write_scene(&dir, &scene_text("after", [1, 1, 1], 5, 1, 10.0));
    let mut next = start_and_wait(server_cmd(&scene, &dir.join("out")));
    assert_eq!(next.0, Some(0), "{}", next.1);
    assert!(
        leftover_files(&run).is_empty(),
        "stale files of {run}: {:?}",
        leftover_files(&run)
    );
    next.1.clear();
}

/// The run name, from the files the run created in shared memory.
fn wait_summary_run(_out: &std::path::Path, server: &mut Proc) -> String {
    let pid = server.child.id();
    let needle = format!("lbmdem_{pid}_");
    let files = leftover_files(&needle);
    let name = files[0].file_name().unwrap().to_string_lossy().to_string();
    let start = name.find(&needle).unwrap();
    name[start..].splitn(4, '_').take(3).collect::<Vec<_>>().join("_")
}

fn server_cmd(scene: &std::path::Path, out: &std::path::Path) -> std::process::Command {
    server(scene, out, &[])
}

fn start_and_wait(cmd: std::process::Command) -> (Option<i32>, String) {
    let mut p = start(cmd);
    let (code, _) = p.wait_exit(Duration::from_secs(60));
    (code, Proc::drain(&p.stderr))
}

#[test]
fn suspended_dem_is_caught_within_a_second() {
    let _cores = shared_cores();
    let (mut server, dem, out) = long_run("stop-dem", 30.0);
    signal(dem, libc::SIGSTOP);
    let (code, waited) = server.wait_exit(Duration::from_secs(10));
    assert_eq!(code, Some(1));
    assert!(waited < 1.0, "lbm-server took {waited:.3} s to notice");
    assert_failure_reported(&mut server, &out, "suspended");
    let start = std::time::Instant::now();
    while !is_gone(dem) && start.elapsed() < Duration::from_secs(5) {
        std::thread::sleep(Duration::from_millis(10));
    }
    assert!(is_gone(dem), "the hung DEM process was ended");
}

#[test]
fn silent_live_dem_is_caught_by_the_timeout() {
    let _cores = shared_cores();
    let (mut server, mut client, out) = stalled_run("stall", 0.5, &[]);
    let (code, waited) = server.wait_exit(Duration::from_secs(10));
    assert_eq!(code, Some(1));
    assert!(waited < 1.5, "timeout of 0.5 s took {waited:.3} s");
    let stderr = assert_failure_reported(&mut server, &out, "did not answer within 0.5 s");
    assert!(stderr.contains("used no CPU"), "{stderr}");
    assert!(stderr.contains("last completed step: 19"), "{stderr}");
    assert!(
        stderr.contains("raise coupling.timeout"),
        "names the setting: {stderr}"
    );
    let _ = client.child.kill();
    client.wait_exit(Duration::from_secs(5));
}

/// Starts a 1000-step run with an external DEM that stalls at step 20 with `stall` (its
/// `--stall-*` options); returns (server, DEM, out).
fn stalled_run(tag: &str, timeout_s: f64, stall: &[&str]) -> (Proc, Proc, std::path::PathBuf) {
    let dir = temp_dir(tag);
    let scene = write_scene(&dir, &scene_text(tag, [2, 2, 2], 1000, 10, timeout_s));
    let out = dir.join("out");
    let (server, run) = start_external(&scene, &out);
    let mut client = std::process::Command::new(bin("dem-client"));
    client
        .args(["connect", "--service", &run, "--stall-at", "20"])
        .args(stall)
        .arg("--scene")
        .arg(&scene);
    (server, start(client), out)
}

#[test]
fn a_working_dem_is_waited_for_beyond_the_timeout() {
    let _cores = a_core_to_spin();
    // Silent for 2 s, four times the timeout, but using the CPU all along: a long step.
    let (mut server, mut client, out) = stalled_run("busy", 0.5, &["--stall-for", "2", "--stall-busy"]);
    let (code, _) = server.wait_exit(Duration::from_secs(60));
    let stderr = Proc::drain(&server.stderr);
    assert_eq!(code, Some(0), "{stderr}");
    assert_eq!(client.wait_exit(Duration::from_secs(10)).0, Some(0));
    assert_eq!(summary(&out)["steps_completed"], 1000);
}

#[test]
fn a_dem_that_works_without_answering_is_caught_at_the_busy_limit() {
    let _cores = a_core_to_spin();
    let timeout = 0.1;
    let (mut server, mut client, out) = stalled_run("spin", timeout, &["--stall-busy"]);
    let (code, waited) = server.wait_exit(Duration::from_secs(30));
    // Ended before any assertion: a DEM left spinning for ever would slow every later test.
    let _ = client.child.kill();
    client.wait_exit(Duration::from_secs(5));
    assert_eq!(code, Some(1));
    let limit = timeout * protocol::transport::BUSY_FACTOR as f64;
    assert!(
        waited >= limit,
        "caught after {waited:.2} s, before the {limit} s limit"
    );
    let stderr = assert_failure_reported(&mut server, &out, "worked for");
    assert!(stderr.contains("without answering"), "{stderr}");
}

/// Ctrl-C ends both processes at once, and the run writes the field outputs of the step it
/// stopped at, as of a last step (its scene asks for snapshots far apart and a probe line).
#[test]
fn ctrl_c_stops_both_cleanly() {
    let _cores = shared_cores();
    let text = scene_text("ctrl-c", [4, 4, 4], 10_000_000, 1000, 30.0).replace(
        "interval = 1000\n",
        "interval = 1000\nfields_interval = 1000000\n[[output.line]]\naxis = \"z\"\nthrough = [0.008, 0.008, 0.008]\n",
    );
    let (mut server, dem, out) = long_run_of("ctrl-c", &text);
    // A terminal's Ctrl-C reaches the foreground process group: lbm-server (the DEM has its own).
    assert_eq!(
        unsafe { libc::kill(-(server.child.id() as i32), libc::SIGINT) },
        0
    );
    let (code, waited) = server.wait_exit(Duration::from_secs(10));
    assert_eq!(code, Some(130), "{}", Proc::drain(&server.stderr));
    assert!(waited < 1.0, "took {waited:.3} s");
    assert!(is_gone(dem));
    let stderr = Proc::drain(&server.stderr);
    assert!(
        stderr.contains("dem-client: finished after"),
        "the DEM ended cleanly:\n{stderr}"
    );
    let s = summary(&out);
    assert_eq!(s["exit_reason"], "interrupted");
    let completed = s["steps_completed"].as_u64().unwrap();
    let snapshot = out.join(format!("fields/step{completed:09}.vti"));
    assert!(snapshot.is_file(), "{} missing", snapshot.display());
    let pvd = std::fs::read_to_string(out.join("fields.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), 1, "{pvd}");
    let line = std::fs::read_to_string(out.join("line0.csv")).unwrap();
    let steps: Vec<&str> = line
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap())
        .collect();
    assert_eq!(
        steps.last().copied(),
        Some(completed.to_string().as_str()),
        "{line}"
    );
    let run = s["run"].as_str().unwrap();
    assert!(leftover_files(run).is_empty(), "{:?}", leftover_files(run));
}

/// A fluid-only run stopped by Ctrl-C writes the outputs of a last step where it stopped: the
/// snapshot and the probe line of that step (Poiseuille's scene, made long).
#[test]
fn ctrl_c_on_a_fluid_run_writes_the_step_it_stopped_at() {
    let _cores = shared_cores();
    let text = include_str!("../validation/scenes/poiseuille.toml");
    assert!(text.contains("steps = 3000"));
    let dir = temp_dir("ctrl-c-fluid");
    let scene = write_scene(&dir, &text.replace("steps = 3000", "steps = 100000000"));
    let out = dir.join("out");
    let mut server = start(server(&scene, &out, &[]));
    server.stderr_line("lbm-server: scene");
    std::thread::sleep(Duration::from_millis(500));
    signal(server.child.id(), libc::SIGINT);
    let (code, _) = server.wait_exit(Duration::from_secs(20));
    assert_eq!(code, Some(130), "{}", Proc::drain(&server.stderr));
    let s = summary(&out);
    assert_eq!(s["exit_reason"], "interrupted");
    let completed = s["steps_completed"].as_u64().unwrap();
    assert!(completed > 0 && completed < 100000000, "{completed}");
    let snapshot = out.join(format!("fields/step{completed:09}.vti"));
    assert!(snapshot.is_file(), "{} missing", snapshot.display());
    let line = std::fs::read_to_string(out.join("line0.csv")).unwrap();
    let last = line.lines().last().and_then(|l| l.split(',').next());
    assert_eq!(
        last,
        Some(completed.to_string().as_str()),
        "the probe line's last step"
    );
}
