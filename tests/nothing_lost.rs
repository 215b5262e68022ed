//! Nothing lost when things go wrong: one run per output folder, whole rows after a crash, a run
//! stopped early never passes for a completed one, a write error named and kept.

mod common;
use common::*;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

/// Kills the process `0` when dropped (a failed assertion leaves no run going on for ever).
struct KillOnDrop(u32);

impl Drop for KillOnDrop {
    fn drop(&mut self) {
        if !is_gone(self.0) {
            unsafe { libc::kill(self.0 as i32, libc::SIGKILL) };
        }
    }
}

/// Runs `cmd` to its end (killed after `timeout_s`): its exit code and stderr.
fn run_to_end(cmd: Command, timeout_s: u64) -> (Option<i32>, String) {
    let mut run = start(cmd);
    let _run = KillOnDrop(run.child.id());
    let (code, _) = run.wait_exit(Duration::from_secs(timeout_s));
    (code, Proc::drain(&run.stderr))
}

/// A granular scene alone that runs for ever: eight spheres dropped in a box, `interval` steps
/// between output rows.
fn granular(steps: u64, interval: u64) -> String {
    format!(
        r#"name = "dropped"
[domain]
min = [0.0, 0.0, 0.0]
max = [0.02, 0.02, 0.02]
[fluid]
density = 1.2
dynamic_viscosity = 1.8e-5
[time]
dt = 1.0e-4
steps = {steps}
[output]
interval = {interval}
[particles]
density = 2500.0
[[particles.block]]
origin = [0.005, 0.005, 0.005]
count = [2, 2, 2]
spacing = 0.01
radius = 0.002
"#
    )
}

/// `dem-client run SCENE --out OUT`.
fn dem_run(scene: &Path, out: &Path) -> Command {
    let mut cmd = Command::new(bin("dem-client"));
    cmd.arg("run").arg(scene).arg("--out").arg(out);
    cmd
}

/// A coupled run of 64 spheres for ever into DIR/out, stepping: (server, out).
fn long_coupled_run(tag: &str, interval: u64) -> (Proc, PathBuf) {
    let dir = temp_dir(tag);
    let scene = write_scene(&dir, &scene_text(tag, [4, 4, 4], 10_000_000, interval, 30.0));
    let out = dir.join("out");
    let server = start(server(&scene, &out, &[]));
    server.stderr_line("lbm-server: scene");
    (server, out)
}

/// A second run into a folder a run is writing is refused (exit 2), naming the running one's pid,
/// and leaves it alone; once the first is gone, even killed, the folder is free.
#[test]
fn a_second_coupled_run_into_the_same_folder_is_refused_naming_the_first() {
    let (mut first, out) = long_coupled_run("lock-coupled", 1000);
    let _first = KillOnDrop(first.child.id());
    let scene = out.parent().unwrap().join("scene.toml");
    let (code, stderr) = run_to_end(server(&scene, &out, &["--steps", "5"]), 60);
    assert_eq!(code, Some(2), "{stderr}");
    let pid = first.child.id();
    assert!(
        stderr.contains(&format!("is in use by another run (pid {pid})")),
        "{stderr}"
    );
    assert!(first.child.try_wait().unwrap().is_none(), "the first run goes on");
    assert!(out.join("particles.csv").is_file(), "the first run's output kept");
    signal(pid, libc::SIGKILL);
    first.wait_exit(Duration::from_secs(10));
    let (code, stderr) = run_to_end(server(&scene, &out, &["--steps", "5"]), 60);
    assert_eq!(code, Some(0), "{stderr}");
}

/// The same for `dem-client run`, which shares the lock with `lbm-server run`.
#[test]
fn a_second_granular_run_into_the_same_folder_is_refused_naming_the_first() {
    let dir = temp_dir("lock-granular");
    let scene = write_scene(&dir, &granular(100_000_000, 1000));
    let out = dir.join("out");
    let mut first = start(dem_run(&scene, &out));
    first.stderr_line("dem-client: scene");
    let pid = first.child.id();
    let _first = KillOnDrop(pid);
    let short = write_scene(&out, &granular(5, 1));
    let (code, stderr) = run_to_end(dem_run(&short, &out), 60);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(
        stderr.contains(&format!("is in use by another run (pid {pid})")),
        "{stderr}"
    );
    assert!(first.child.try_wait().unwrap().is_none(), "the first run goes on");
    signal(pid, libc::SIGINT);
    let (code, _) = first.wait_exit(Duration::from_secs(30));
    assert_eq!(code, Some(130), "{}", Proc::drain(&first.stderr));
    let (code, stderr) = run_to_end(dem_run(&short, &out), 60);
    assert_eq!(code, Some(0), "{stderr}");
}

/// The rows of the CSV file `path` after its header, each asserted whole: `columns` numbers and
/// a line end.
fn whole_rows(path: &Path, columns: usize) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    assert!(text.ends_with('\n'), "{}: a torn last row", path.display());
    let parse = |line: &str| -> Vec<f64> {
        let row: Vec<f64> = line.split(',').filter_map(|v| v.parse().ok()).collect();
        assert_eq!(row.len(), columns, "{}: row {line:?}", path.display());
        row
    };
    text.lines().skip(1).map(parse).collect()
}

/// The steps done as the latest progress line (`lbm-server: step N/M ...`) says, waiting for the
/// `count`-th such line.
fn steps_done_after(server: &Proc, count: usize) -> u64 {
    let mut done = 0;
    for _ in 0..count {
        let line = server.stderr_line("lbm-server: step ");
        let n = line.split("step ").nth(1).and_then(|r| r.split('/').next());
        done = n.and_then(|n| n.parse().ok()).unwrap_or_else(|| panic!("{line}"));
    }
    done
}

/// kill -9 of a coupled run leaves particles.csv with whole rows only, up to the last output
/// step before the last progress line it printed.
#[test]
fn a_killed_coupled_run_leaves_whole_rows_up_to_a_recent_output_step() {
    let interval = 10;
    let (mut server, out) = long_coupled_run("kill-rows", interval);
    let _server = KillOnDrop(server.child.id());
    let done = steps_done_after(&server, 2);
    signal(server.child.id(), libc::SIGKILL);
    server.wait_exit(Duration::from_secs(10));
    let rows = whole_rows(&out.join("particles.csv"), 18);
    let last = rows.last().map_or(0, |r| r[0] as u64);
    let due = (done - 1) / interval * interval;
    assert!(
        last >= due,
        "{done} steps done: rows up to step {last}, not {due}"
    );
    let at_last = rows.iter().filter(|r| r[0] as u64 == last).count();
    assert_eq!(at_last, 64, "every particle of step {last}");
}

/// kill -9 of a granular run leaves particles.csv and energy.csv with whole rows only.
#[test]
fn a_killed_granular_run_leaves_whole_rows() {
    let dir = temp_dir("kill-granular");
    let scene = write_scene(&dir, &granular(100_000_000, 1));
    let out = dir.join("out");
    let mut run = start(dem_run(&scene, &out));
    let _run = KillOnDrop(run.child.id());
    run.stderr_line("dem-client: scene");
    std::thread::sleep(Duration::from_millis(1500));
    signal(run.child.id(), libc::SIGKILL);
    run.wait_exit(Duration::from_secs(10));
    let rows = whole_rows(&out.join("particles.csv"), 18);
    assert!(rows.len() > 8, "{} rows", rows.len());
    let last = rows.last().unwrap()[0];
    assert_eq!(
        rows.iter().filter(|r| r[0] == last).count(),
        8,
        "every sphere of step {last}"
    );
    let energy = whole_rows(&out.join("energy.csv"), 4);
    assert!(energy.last().unwrap()[0] >= last, "energy.csv up to step {last}");
}

/// SIGTERM or SIGINT to the DEM process stops a coupled run before its last step: the run does
/// not pass for a completed one (exit 130, summary.json says the DEM client stopped it).
#[test]
fn a_signal_to_the_dem_ends_the_run_as_stopped_not_completed() {
    for (name, sig) in [("term", libc::SIGTERM), ("int", libc::SIGINT)] {
        let (mut server, out) = long_coupled_run(&format!("dem-{name}"), 1000);
        let _server = KillOnDrop(server.child.id());
        steps_done_after(&server, 1);
        signal(child_pid(server.child.id()), sig);
        let (code, _) = server.wait_exit(Duration::from_secs(20));
        let stderr = Proc::drain(&server.stderr);
        assert_eq!(code, Some(130), "{name}: {stderr}");
        assert!(!stderr.contains(" steps/s;"), "{name}: a success line:\n{stderr}");
        assert!(
            stderr.contains("lbm-server: stopped by the DEM client after "),
            "{name}: {stderr}"
        );
        assert!(
            stderr.contains("dem-client: interrupted after "),
            "{name}: {stderr}"
        );
        let s = summary(&out);
        assert_eq!(s["exit_reason"], "stopped by the DEM client", "{name}");
        assert_eq!(s["exit_code"], 130, "{name}");
        assert!(s["steps_completed"].as_u64().unwrap() < 10_000_000, "{name}");
    }
}

/// A lattice far too large for any device (1.07e9 cells: 17 GB of fields in one buffer) is
/// refused with exit 2, naming the need and the device's limit, before the output folder is
/// touched: an earlier run's outputs stay.
#[test]
fn a_lattice_too_large_for_the_device_is_refused_before_anything_is_removed() {
    let dir = temp_dir("too-large");
    let text = include_str!("../validation/scenes/poiseuille.toml")
        .replace("max = [0.002, 0.016, 0.002]", "max = [1.024, 1.024, 1.024]")
        .replace("through = [0.001, 0.008, 0.001]", "through = [0.5, 0.5, 0.5]");
    let scene = write_scene(&dir, &text);
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    for earlier in ["summary.json", "line0.csv", "particles.csv"] {
        std::fs::write(out.join(earlier), "an earlier run's\n").unwrap();
    }
    let (code, stderr) = run_to_end(server(&scene, &out, &[]), 120);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(
        stderr.contains("1024x1024x1024 (1073741824 cells) needs 17179869184 bytes"),
        "the need: {stderr}"
    );
    assert!(
        stderr.contains("storage binding limit of "),
        "the limit: {stderr}"
    );
    for earlier in ["summary.json", "line0.csv", "particles.csv"] {
        let text = std::fs::read_to_string(out.join(earlier)).unwrap();
        assert_eq!(text, "an earlier run's\n", "{earlier} kept");
    }
}

/// A summary.json that cannot be written (a full disk: here a link to /dev/full) fails the run
/// (exit 1), naming the file; particles.csv is kept whole.
#[test]
fn a_summary_that_cannot_be_written_fails_the_run_by_name() {
    let dir = temp_dir("full-summary");
    let scene = write_scene(&dir, &scene_text("full-summary", [2, 2, 2], 20, 5, 30.0));
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    std::os::unix::fs::symlink("/dev/full", out.join("summary.json")).unwrap();
    let (code, stderr) = run_to_end(server(&scene, &out, &[]), 120);
    assert_eq!(code, Some(1), "{stderr}");
    assert!(
        stderr.contains("lbm-server: error: summary.json: No space left on device"),
        "{stderr}"
    );
    let rows = whole_rows(&out.join("particles.csv"), 18);
    assert_eq!(rows.len(), 8 * 5, "steps 0, 5, 10, 15 and 19");
}

/// A particles.csv that stops growing mid-run (its size limited, as on a full disk) fails the run
/// (exit 1) naming it; the rows written before are kept, whole, and summary.json says why.
#[test]
fn a_write_error_mid_run_keeps_the_rows_written_and_names_the_file() {
    use std::os::unix::process::CommandExt;
    let dir = temp_dir("full-rows");
    let scene = write_scene(&dir, &scene_text("full-rows", [4, 4, 4], 10_000_000, 1, 30.0));
    let out = dir.join("out");
    let mut cmd = server(&scene, &out, &[]);
    const LIMIT: u64 = 1 << 20;
    unsafe {
        cmd.pre_exec(|| {
            let limit = libc::rlimit {
                rlim_cur: LIMIT,
                rlim_max: LIMIT,
            };
            libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
            match libc::setrlimit(libc::RLIMIT_FSIZE, &limit) {
                0 => Ok(()),
                _ => Err(std::io::Error::last_os_error()),
            }
        });
    }
    let (code, stderr) = run_to_end(cmd, 300);
    assert_eq!(code, Some(1), "{stderr}");
    assert!(
        stderr.contains("lbm-server: error: particles.csv: File too large"),
        "{stderr}"
    );
    let rows = whole_rows(&out.join("particles.csv"), 18);
    assert!(rows.len() > 64, "{} rows kept", rows.len());
    assert_eq!(rows.len() % 64, 0, "whole steps");
    let s = summary(&out);
    let reason = s["exit_reason"].as_str().unwrap();
    assert!(
        reason.starts_with("error: particles.csv: File too large"),
        "{reason}"
    );
}

/// A blow-up caught at a check (the unstable lid-driven cavity, checked every 50 steps, by when
/// it has spread) is named where it is furthest out of bounds, near the moving lid at z_max (16
/// cells high), with its centre in SI; not at cell (0, 0, 0), the first in memory order.
#[test]
fn a_blow_up_is_named_where_it_is_furthest_out_of_bounds() {
    let dir = temp_dir("blow-up-cell");
    let scene = write_scene(&dir, include_str!("../validation/scenes/cavity-unstable.toml"));
    let out = dir.join("out");
    let (code, stderr) = run_to_end(server(&scene, &out, &[]), 120);
    assert_eq!(code, Some(1), "{stderr}");
    let named = stderr
        .split("furthest out of bounds, cell ")
        .nth(1)
        .unwrap_or_else(|| panic!("no cell named furthest out:\n{stderr}"));
    let coords: Vec<usize> = named
        .split(['(', ')'])
        .nth(1)
        .unwrap()
        .split(", ")
        .map(|c| c.parse().unwrap())
        .collect();
    assert!(coords[2] >= 12, "{coords:?}: not near the lid:\n{stderr}");
    assert!(named.contains(") m: "), "its centre in SI: {named}");
}

/// Ctrl-C while a run starts (its device opened, its kernels compiled: seconds on a CPU driver)
/// ends it at once, saying so, with exit 130: a coupled run and a fluid-only one.
#[test]
fn ctrl_c_during_start_up_acts_at_once() {
    let coupled = scene_text("start-up", [2, 2, 2], 100, 10, 30.0);
    let fluid = include_str!("../validation/scenes/poiseuille.toml").to_string();
    for (tag, text) in [("coupled", coupled), ("fluid", fluid)] {
        let dir = temp_dir(&format!("start-up-{tag}"));
        let scene = write_scene(&dir, &text);
        let out = dir.join("out");
        std::fs::create_dir_all(&out).unwrap();
        // An earlier run's summary: its removal is said once the Ctrl-C handler is in place.
        std::fs::write(out.join("summary.json"), "{}\n").unwrap();
        let mut run = start(server(&scene, &out, &[]));
        let _run = KillOnDrop(run.child.id());
        run.stderr_line("output files of an earlier run");
        signal(run.child.id(), libc::SIGINT);
        let (code, waited) = run.wait_exit(Duration::from_secs(60));
        let stderr = Proc::drain(&run.stderr);
        assert_eq!(code, Some(130), "{tag}: {stderr}");
        assert!(waited < 0.5, "{tag}: took {waited:.2} s:\n{stderr}");
        assert!(
            stderr.contains("lbm-server: interrupted during start-up"),
            "{tag}: {stderr}"
        );
    }
}
