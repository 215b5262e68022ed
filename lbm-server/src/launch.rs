//! Starting and ending the DEM process that `lbm-server run` launches itself: `dem-client`
//! (`--dem builtin`), any command line (`--dem-command`), or YADE / LIGGGHTS on a script / deck
//! written from the scene (`--dem yade|liggghts`, `codes.rs`).

mod codes;

pub use codes::{liggghts, yade};
use protocol::liveness::die_with_parent;
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// The environment variable that carries the run name to a started DEM.
pub const RUN_ENV: &str = "LBMDEM_RUN";
/// The environment variable that carries the run's scene file (OUT/scene.toml, absolute).
pub const SCENE_ENV: &str = "LBMDEM_SCENE";
/// Where the Python clients are found when lbm-server runs away from its source tree.
pub const CLIENTS_ENV: &str = "LBMDEM_CLIENTS";
/// The staging folder a DEM writes its part of a checkpoint into (OUT/checkpoint.staging,
/// absolute), and the folder of the checkpoint a resumed run goes on from (PROTOCOL.md 6.4).
pub const CHECKPOINT_DIR_ENV: &str = "LBMDEM_CHECKPOINT_DIR";
pub const RESUME_DIR_ENV: &str = "LBMDEM_RESUME_DIR";

/// How the DEM side of a run starts.
pub enum DemStart {
    /// `dem-client connect`, found next to lbm-server or on PATH.
    Builtin,
    /// A command started and supervised as dem-client is.
    Command(DemCommand),
    /// Announced (`DEM service: RUN`); any client joins.
    External,
}

/// A DEM started from a command line, with the run name and scene in its environment and the
/// Python clients' folders (clients/python first) on its PYTHONPATH.
pub struct DemCommand {
    argv: Vec<OsString>,
    /// Working folder (None: lbm-server's own).
    dir: Option<PathBuf>,
    /// Folders put before any PYTHONPATH of the user's.
    python_path: Vec<PathBuf>,
}

impl DemCommand {
    /// `sh -c LINE` (`--dem-command`).
    pub fn shell(line: &str) -> DemCommand {
        DemCommand {
            argv: vec!["sh".into(), "-c".into(), line.into()],
            dir: None,
            python_path: vec![clients_dir().join("python")],
        }
    }

    /// What is started, for messages.
    pub fn describe(&self) -> String {
        let words: Vec<_> = self.argv.iter().map(|a| a.to_string_lossy()).collect();
        words.join(" ")
    }

    /// Starts the command for run `run` with the scene copy at `scene`, in a process group of
    /// its own, ended with lbm-server (as `spawn_dem_client`).
    pub fn spawn(&self, run: &str, scene: &Path, env: &[(&str, PathBuf)]) -> std::io::Result<Child> {
        use std::os::unix::process::CommandExt;
        let mut cmd = Command::new(&self.argv[0]);
        cmd.args(&self.argv[1..])
            .envs(env.iter().map(|(k, v)| (k, v)))
            .env(RUN_ENV, run)
            .env(SCENE_ENV, std::path::absolute(scene)?)
            .env("PYTHONPATH", python_path(&self.python_path)?)
            .process_group(0)
            .stdin(Stdio::null());
        if let Some(dir) = &self.dir {
            cmd.current_dir(dir);
        }
        die_with_parent(&mut cmd, libc::SIGTERM).spawn()
    }
}

/// PYTHONPATH with `dirs` before the user's own.
fn python_path(dirs: &[PathBuf]) -> std::io::Result<OsString> {
    let mut all = dirs.to_vec();
    all.extend(std::env::var_os("PYTHONPATH").map_or(vec![], |p| std::env::split_paths(&p).collect()));
    std::env::join_paths(all).map_err(std::io::Error::other)
}

/// The folder of the Python clients (python/, yade/, liggghts/): `$LBMDEM_CLIENTS`, else the
/// source tree's `clients/`.
pub fn clients_dir() -> PathBuf {
    std::env::var_os(CLIENTS_ENV)
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../clients")))
}

/// Finds `dem-client`: next to this executable first, then on PATH.
pub fn find_dem_client() -> Option<PathBuf> {
    let beside = std::env::current_exe().ok()?.with_file_name("dem-client");
    if beside.is_file() {
        return Some(beside);
    }
    find_on_path("dem-client")
}

/// The first `name` in a folder of PATH.
pub fn find_on_path(name: &str) -> Option<PathBuf> {
    std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|dir| dir.join(name))
            .find(|p| p.is_file())
    })
}

/// Starts `dem-client connect` for run `run` with the scene copy at `scene`, `--verbose` where
/// `verbose` (and `env`, the checkpoint folders).
///
/// The DEM gets a process group of its own, so a terminal's Ctrl-C reaches only lbm-server, which
/// then ends the run in order (STOP in its next reply) instead of racing the DEM's own handler.
/// It gets SIGTERM when lbm-server dies (killed: nothing ends the run in order), as from a Ctrl-C
/// of its own: joining, it ends at once; stepping, it says that the fluid died and ends
/// (PROTOCOL.md 7). Started from the main thread, which lives as long as lbm-server.
pub fn spawn_dem_client(
    exe: &Path,
    run: &str,
    scene: &Path,
    timeout_s: f64,
    verbose: bool,
    env: &[(&str, PathBuf)],
) -> std::io::Result<Child> {
    use std::os::unix::process::CommandExt;
    let mut cmd = Command::new(exe);
    cmd.process_group(0)
        .envs(env.iter().map(|(k, v)| (k, v)))
        .arg("connect")
        .arg("--service")
        .arg(run)
        .arg("--scene")
        .arg(scene)
        .arg("--timeout")
        .arg(timeout_s.to_string())
        .args(verbose.then_some("--verbose"))
        .stdin(Stdio::null());
    die_with_parent(&mut cmd, libc::SIGTERM).spawn()
}

/// Waits up to `grace` for the child to exit by itself, then kills its process group (a shell's
/// or YADE's children with it). Returns its exit code.
pub fn end_child(child: &mut Child, grace: Duration) -> Option<i32> {
    let start = Instant::now();
    loop {
        match child.try_wait() {
            Ok(Some(status)) => return status.code(),
            Ok(None) if start.elapsed() < grace => std::thread::sleep(Duration::from_millis(10)),
            _ => {
                // Not reaped yet: its pid (the group's id) cannot have been reused.
                unsafe { libc::kill(-(child.id() as i32), libc::SIGKILL) };
                let _ = child.kill();
                return child.wait().ok().and_then(|s| s.code());
            }
        }
    }
}
