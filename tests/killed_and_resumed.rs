//! A coupled run killed (kill -9) at a moment that is not one of its checkpoints, and resumed
//! (`lbm-server run --resume`), writes the same bytes as a run that went through (docs/checkpoint.md):
//! the DEM process killed alone, or lbm-server alone, between two checkpoints or while one is
//! being written; particles.csv, the fluid's populations and the DEM's state compared byte for
//! byte.

mod common;
use common::*;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, OnceLock};
use std::time::{Duration, Instant};

/// 8 spheres falling in a 16^3 box for 40 steps, rows every 5, checkpoints every 10.
fn falling() -> String {
    scene_text("ckpt-killed", [2, 2, 2], 40, 5, 10.0)
        .replace("interval = 5\n", "interval = 5\ncheckpoint_interval = 10\n")
}

/// One run at a time (the machine's cores are few; a kill's moment is watched for).
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

/// The scene's file and the output of its uninterrupted run (made once).
fn reference() -> &'static (PathBuf, PathBuf) {
    static FULL: OnceLock<(PathBuf, PathBuf)> = OnceLock::new();
    FULL.get_or_init(|| {
        let dir = temp_dir("killed-full");
        let scene = write_scene(&dir, &falling());
        let full = dir.join("full");
        let out = server(&scene, &full, &[]).output().unwrap();
        assert_eq!(out.status.code(), Some(0), "{}", output_text(&out));
        (scene, full)
    })
}

/// Which process is killed, and when.
#[derive(Clone, Copy)]
enum Victim {
    Dem,
    Fluid,
}

#[derive(Clone, Copy, Debug)]
enum Moment {
    /// Once particles.csv holds the rows of step 25 (checkpoints at 20 and 30).
    BetweenCheckpoints,
    /// Once this file appears in OUT/checkpoint.staging while a checkpoint is in place (the one
    /// after the first being written).
    Writing(&'static str),
}

/// Waits until `moment` in the run writing into `out` (true), or the run ended first (false).
fn wait_for(moment: Moment, out: &Path, server: &mut Proc) -> bool {
    let deadline = Instant::now() + PROCESS_WAIT;
    while Instant::now() < deadline {
        let now = match moment {
            Moment::BetweenCheckpoints => {
                std::fs::read_to_string(out.join("particles.csv")).is_ok_and(|t| t.contains("\n25,"))
            }
            Moment::Writing(file) => {
                out.join("checkpoint/header.json").exists()
                    && out.join("checkpoint.staging").join(file).exists()
            }
        };
        if now {
            return true;
        }
        if server.child.try_wait().unwrap().is_some() {
            return false;
        }
        std::thread::sleep(Duration::from_micros(300));
    }
    panic!(
        "`{}` (pid {}) did not reach the moment {moment:?} in {} within {PROCESS_WAIT:?}",
        server.name,
        server.child.id(),
        out.display()
    );
}

fn same_file(a: &Path, b: &Path) {
    let (x, y) = (std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
    assert!(x == y, "{} and {} differ", a.display(), b.display());
}

/// Runs the scene, kills `victim` at `moment`, resumes and compares with the uninterrupted run;
/// the killed run's own stderr and the resumed run's.
fn kill_and_resume(tag: &str, victim: Victim, moment: Moment) -> (String, String) {
    let (scene, full) = reference();
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let part = temp_dir(tag).join("part");
    let mut server = start(server(scene, &part, &[]));
    let dem = dem_of(&mut server);
    let hit = wait_for(moment, &part, &mut server);
    assert!(
        hit,
        "the run ended before the moment: {}",
        Proc::drain(&server.stderr)
    );
    match victim {
        Victim::Dem => signal(dem, libc::SIGKILL),
        Victim::Fluid => signal(server.child.id(), libc::SIGKILL),
    }
    let (code, _) = server.wait_exit(Duration::from_secs(60));
    let said = Proc::drain(&server.stderr);
    let staged = part.join("checkpoint.staging").exists();
    eprintln!("{tag}: killed with a checkpoint being written: {staged}");
    if let Victim::Fluid = victim {
        // The DEM notices the fluid's death on its own; not waited for.
        let _ = unsafe { libc::kill(dem as i32, libc::SIGKILL) };
    } else {
        assert_eq!(code, Some(1), "{said}");
    }
    let resumed = std::process::Command::new(bin("lbm-server"))
        .args(["run", "--resume"])
        .arg(&part)
        .output()
        .unwrap();
    let err = output_text(&resumed);
    assert_eq!(
        resumed.status.code(),
        Some(0),
        "killed run:\n{said}\nresumed:\n{err}"
    );
    for file in [
        "particles.csv",
        "checkpoint/populations.bin",
        "checkpoint/dem.bin",
    ] {
        same_file(&full.join(file), &part.join(file));
    }
    (said, err)
}

/// The DEM killed: the fluid's run fails (exit 1) naming the last complete checkpoint, from which
/// `--resume` goes on.
#[test]
fn the_dem_killed_between_checkpoints() {
    let (said, resumed) = kill_and_resume("kill-dem-between", Victim::Dem, Moment::BetweenCheckpoints);
    let line = said
        .lines()
        .find(|l| l.contains("the last complete checkpoint, at step"))
        .unwrap_or_else(|| panic!("the run says what to resume from:\n{said}"));
    assert!(line.contains("lbm-server run --resume"), "{line}");
    let step = line
        .split("at step ")
        .nth(1)
        .and_then(|r| r.split(',').next())
        .unwrap();
    assert!(
        resumed.contains(&format!("from its checkpoint at step {step} ")),
        "{line}\n{resumed}"
    );
}

#[test]
fn the_dem_killed_while_it_writes_its_part() {
    let (said, _) = kill_and_resume("kill-dem-writing", Victim::Dem, Moment::Writing("dem.bin"));
    assert!(said.contains("the last complete checkpoint, at step"), "{said}");
}

#[test]
fn the_fluid_killed_between_checkpoints() {
    kill_and_resume("kill-fluid-between", Victim::Fluid, Moment::BetweenCheckpoints);
}

#[test]
fn the_fluid_killed_while_it_writes_its_part() {
    kill_and_resume(
        "kill-fluid-writing",
        Victim::Fluid,
        Moment::Writing("populations.bin"),
    );
}
