//! YADE and LIGGGHTS as the DEM of a run (`--dem yade|liggghts`): checked to be installed before
//! anything runs, the scene's DEM (particles, materials, walls, contact law) written into OUT as a
//! YADE script / LIGGGHTS deck by the Python clients (clients/yade/scene_script.py,
//! clients/liggghts/scene_deck.py) for the user to read and edit, and the command that runs it.

use super::{clients_dir, find_on_path, python_path, DemCommand};
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::Command;

const YADE_MISSING: &str = "--dem yade: YADE is not installed (no `yade` on PATH); install it: \
     sudo apt-get install yade python3-yade (Debian and Ubuntu), or sh validation/dem/install.sh";

/// LIGGGHTS through clients/liggghts/lbm_liggghts.py on OUT/dem.liggghts.in.
pub fn liggghts(scene: &Path, out: &Path) -> Result<DemCommand, String> {
    let clients = clients_dir();
    let python_path = vec![clients.join("python")];
    let adapter = clients.join("liggghts").join("lbm_liggghts.py");
    let probe = [adapter.as_os_str().into(), "--probe".into()];
    python("--dem liggghts", "python3", &probe, &python_path)?;
    let deck = std::path::absolute(out.join("dem.liggghts.in")).map_err(|e| e.to_string())?;
    let writer = clients.join("liggghts").join("scene_deck.py");
    python(
        "--dem liggghts",
        "python3",
        &[writer.into(), scene.into(), deck.clone().into()],
        &python_path,
    )?;
    protocol::say!("lbm-server: the LIGGGHTS deck of the scene: {}", deck.display());
    Ok(DemCommand {
        argv: vec!["python3".into(), adapter.into(), "--deck".into(), deck.into()],
        dir: Some(out.to_path_buf()),
        python_path,
    })
}

/// YADE (`yade -n -x OUT/dem.yade.py`) through clients/yade/lbmdem_yade.py.
pub fn yade(scene: &Path, out: &Path) -> Result<DemCommand, String> {
    let exe = find_on_path("yade").ok_or(YADE_MISSING)?;
    let interpreter = interpreter_of(&exe);
    let clients = clients_dir();
    let python_path = vec![clients.join("python"), clients.join("yade")];
    let check = ["-c".into(), "import iceoryx2, numpy, lbmdem_scene".into()];
    python("--dem yade", &interpreter, &check, &python_path).map_err(|e| {
        format!(
            "{e}\n  YADE runs on {interpreter}: install iceoryx2 for it into a folder DIR \
             ({interpreter} -m pip install --target DIR iceoryx2==0.10.0) and run with PYTHONPATH=DIR"
        )
    })?;
    let script = std::path::absolute(out.join("dem.yade.py")).map_err(|e| e.to_string())?;
    let writer = clients.join("yade").join("scene_script.py");
    python(
        "--dem yade",
        &interpreter,
        &[writer.into(), scene.into(), script.clone().into()],
        &python_path,
    )?;
    protocol::say!("lbm-server: the YADE script of the scene: {}", script.display());
    Ok(DemCommand {
        argv: vec![exe.into(), "-n".into(), "-x".into(), script.into()],
        dir: Some(out.to_path_buf()),
        python_path,
    })
}

/// The interpreter of a script's `#!` line (YADE's python), else /usr/bin/python3.
fn interpreter_of(script: &Path) -> String {
    let text = std::fs::read(script).unwrap_or_default();
    let first = text.split(|&b| b == b'\n').next().unwrap_or_default();
    String::from_utf8_lossy(first)
        .strip_prefix("#!")
        .and_then(|l| l.split_whitespace().next())
        .unwrap_or("/usr/bin/python3")
        .to_string()
}

/// Runs `interpreter args` to completion with `paths` before the user's PYTHONPATH; the last line
/// of its stderr is the error where it fails.
fn python(what: &str, interpreter: &str, args: &[OsString], paths: &[PathBuf]) -> Result<(), String> {
    let output = Command::new(interpreter)
        .args(args)
        .env("PYTHONPATH", python_path(paths).map_err(|e| e.to_string())?)
        .output()
        .map_err(|e| format!("{what}: cannot run {interpreter}: {e}"))?;
    let said = String::from_utf8_lossy(&output.stderr);
    if output.status.success() {
        // A warning of the writer (another contact preset than the code's).
        if !said.trim().is_empty() {
            protocol::say!("lbm-server: {what}: {}", said.trim());
        }
        return Ok(());
    }
    // Its last line: the message (a traceback's exception line).
    let last = said
        .lines()
        .rev()
        .find(|l| !l.trim().is_empty())
        .unwrap_or("failed");
    Err(format!("{what}: {}", last.trim()))
}
