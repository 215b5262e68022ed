//! Starting and ending the DEM process that `lbm-server run` launches itself.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// Finds `dem-client`: next to this executable first, then on PATH.
pub fn find_dem_client() -> Option<PathBuf> {
    let beside = std::env::current_exe().ok()?.with_file_name("dem-client");
    if beside.is_file() {
        return Some(beside);
    }
    std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|dir| dir.join("dem-client"))
            .find(|p| p.is_file())
    })
}

/// Starts `dem-client connect` for run `run` with the scene copy at `scene`.
///
/// The DEM gets a process group of its own, so a terminal's Ctrl-C reaches only lbm-server, which
/// then ends the run in order (STOP in its next reply) instead of racing the DEM's own handler.
pub fn spawn_dem_client(exe: &Path, run: &str, scene: &Path, timeout_s: f64) -> std::io::Result<Child> {
    use std::os::unix::process::CommandExt;
    Command::new(exe)
        .process_group(0)
        .arg("connect")
        .arg("--service")
        .arg(run)
        .arg("--scene")
        .arg(scene)
        .arg("--timeout")
        .arg(timeout_s.to_string())
        .stdin(Stdio::null())
        .spawn()
}

/// Waits up to `grace` for the child to exit by itself, then kills it. Returns its exit code.
pub fn end_child(child: &mut Child, grace: Duration) -> Option<i32> {
    let start = Instant::now();
    loop {
        match child.try_wait() {
            Ok(Some(status)) => return status.code(),
            Ok(None) if start.elapsed() < grace => std::thread::sleep(Duration::from_millis(10)),
            _ => {
                let _ = child.kill();
                return child.wait().ok().and_then(|s| s.code());
            }
        }
    }
}
