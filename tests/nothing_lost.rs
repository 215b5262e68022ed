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

/// `dem-client run SCENE --out OUT`, started.
fn start_dem_run(scene: &Path, out: &Path) -> Proc {
    let mut cmd = Command::new(bin("dem-client"));
    cmd.arg("run").arg(scene).arg("--out").arg(out);
    start(cmd)
}

/// A coupled run of 64 spheres for ever into DIR/out, stepping: (server, out).
fn long_coupled_run(tag: &str, interval: u64) -> (Proc, PathBuf) {
    let dir = temp_dir(tag);
    let scene = write_scene(&dir, &scene_text(tag, [4, 4, 4], 10_000_000, interval, 30.0));
    let out = dir.join("out");
    let server = start(server(&scene, &out, &[]));
    Proc::wait_line(&server.stderr, "lbm-server: scene", Duration::from_secs(30));
    (server, out)
}

/// A second run into a folder a run is writing is refused (exit 2), naming the running one's pid,
/// and leaves it alone; once the first is gone, even killed, the folder is free.
#[test]
fn a_second_coupled_run_into_the_same_folder_is_refused_naming_the_first() {
    let (mut first, out) = long_coupled_run("lock-coupled", 1000);
    let _first = KillOnDrop(first.child.id());
    let scene = out.parent().unwrap().join("scene.toml");
    let mut second = start(server(&scene, &out, &["--steps", "5"]));
    let (code, _) = second.wait_exit(Duration::from_secs(60));
    let stderr = Proc::drain(&second.stderr);
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
    let mut third = start(server(&scene, &out, &["--steps", "5"]));
    let (code, _) = third.wait_exit(Duration::from_secs(60));
    assert_eq!(code, Some(0), "{}", Proc::drain(&third.stderr));
}

/// The same for `dem-client run`, which shares the lock with `lbm-server run`.
#[test]
fn a_second_granular_run_into_the_same_folder_is_refused_naming_the_first() {
    let dir = temp_dir("lock-granular");
    let scene = write_scene(&dir, &granular(100_000_000, 1000));
    let out = dir.join("out");
    let mut first = start_dem_run(&scene, &out);
    Proc::wait_line(&first.stderr, "dem-client: scene", Duration::from_secs(30));
    let pid = first.child.id();
    let _first = KillOnDrop(pid);
    let short = write_scene(&out, &granular(5, 1));
    let mut second = start_dem_run(&short, &out);
    let (code, _) = second.wait_exit(Duration::from_secs(60));
    let stderr = Proc::drain(&second.stderr);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(
        stderr.contains(&format!("is in use by another run (pid {pid})")),
        "{stderr}"
    );
    assert!(first.child.try_wait().unwrap().is_none(), "the first run goes on");
    signal(pid, libc::SIGINT);
    let (code, _) = first.wait_exit(Duration::from_secs(30));
    assert_eq!(code, Some(130), "{}", Proc::drain(&first.stderr));
    let mut third = start_dem_run(&short, &out);
    let (code, _) = third.wait_exit(Duration::from_secs(60));
    assert_eq!(code, Some(0), "{}", Proc::drain(&third.stderr));
}
