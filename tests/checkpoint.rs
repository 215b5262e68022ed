//! Checkpoints and `--resume` (docs/checkpoint.md): a fluid-only run stopped and resumed writes
//! the same bytes as one that ran through; a coupled run killed (kill -9) mid-run and resumed
//! gives particles.csv byte-identical to an uninterrupted run's; a corrupt, truncated or
//! mismatched checkpoint is refused (exit 2) naming what differs, with nothing overwritten.

mod common;
use common::*;
use std::path::Path;
use std::time::Duration;

const POISEUILLE: &str = include_str!("../validation/scenes/poiseuille.toml");

/// The Poiseuille channel, short: 200 steps, rows every 50, snapshots every 100, checkpoints
/// every 60.
fn channel() -> String {
    POISEUILLE
        .replace("steps = 3000", "steps = 200")
        .replace("check_interval = 500", "check_interval = 25")
        .replace(
            "interval = 3000                      # steps between rows of line0.csv",
            "interval = 50\ncheckpoint_interval = 60",
        )
        .replace("fields_interval = 1000", "fields_interval = 100")
}

fn run_ok(cmd: std::process::Command) -> String {
    let mut cmd = cmd;
    let out = cmd.output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(0), "{err}");
    err
}

fn resume(out: &Path, extra: &[&str]) -> std::process::Output {
    std::process::Command::new(bin("lbm-server"))
        .arg("run")
        .arg("--resume")
        .arg(out)
        .args(extra)
        .output()
        .unwrap()
}

fn same_file(a: &Path, b: &Path) {
    let (x, y) = (std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
    assert!(x == y, "{} and {} differ", a.display(), b.display());
}

#[test]
fn a_fluid_run_stopped_and_resumed_writes_the_same_bytes() {
    let dir = temp_dir("ckpt-fluid");
    let scene = write_scene(&dir, &channel());
    let (full, part) = (dir.join("full"), dir.join("part"));
    let err = run_ok(server(&scene, &full, &[]));
    assert!(err.contains("checkpoint at step 60 written"), "{err}");
    // Stopped at an odd step (the AA pattern's odd phase), then resumed to the end.
    run_ok(server(&scene, &part, &["--steps", "75"]));
    let resumed = resume(&part, &[]);
    let err = String::from_utf8_lossy(&resumed.stderr);
    assert_eq!(resumed.status.code(), Some(0), "{err}");
    assert!(err.contains("resuming") && err.contains("at step 75"), "{err}");
    for file in [
        "line0.csv",
        "fields.pvd",
        "fields/step000000200.vti",
        "checkpoint/populations.bin",
    ] {
        same_file(&full.join(file), &part.join(file));
    }
    assert!(
        !part.join("fields/step000000075.vti").exists(),
        "the stopped run's last snapshot, after its checkpoint, is removed"
    );
}

#[test]
fn a_resumed_run_keeps_the_checkpoint_interval_given_on_the_command_line() {
    let dir = temp_dir("ckpt-interval");
    let scene = write_scene(&dir, &channel());
    let out = dir.join("out");
    let err = run_ok(server(
        &scene,
        &out,
        &["--steps", "50", "--checkpoint-interval", "40"],
    ));
    assert!(err.contains("checkpoint at step 40 written"), "{err}");
    let header = std::fs::read_to_string(out.join("checkpoint/header.json")).unwrap();
    assert!(header.contains("\"checkpoint_interval\": 40"), "{header}");
    let resumed = resume(&out, &["--steps", "130"]);
    let err = String::from_utf8_lossy(&resumed.stderr);
    assert_eq!(resumed.status.code(), Some(0), "{err}");
    assert!(
        err.contains("checkpoint at step 80 written") && err.contains("checkpoint at step 120 written"),
        "every 40 steps, as the first run was told: {err}"
    );
    assert!(
        !err.contains("checkpoint at step 60 written"),
        "not the scene's 60: {err}"
    );
    let resumed = resume(&out, &["--steps", "140", "--checkpoint-interval", "135"]);
    let err = String::from_utf8_lossy(&resumed.stderr);
    assert_eq!(resumed.status.code(), Some(0), "{err}");
    assert!(
        err.contains("checkpoint at step 135 written"),
        "given anew: {err}"
    );
}

#[test]
fn a_corrupt_truncated_or_mismatched_checkpoint_is_refused() {
    let dir = temp_dir("ckpt-bad");
    let scene = write_scene(&dir, &channel());
    let out = dir.join("out");
    run_ok(server(&scene, &out, &["--steps", "120"]));
    let lines = std::fs::read(out.join("line0.csv")).unwrap();
    let populations = out.join("checkpoint/populations.bin");
    let good = std::fs::read(&populations).unwrap();
    let refused = |what: &str| {
        let result = resume(&out, &[]);
        let err = String::from_utf8_lossy(&result.stderr).into_owned();
        assert_eq!(result.status.code(), Some(2), "{what}: {err}");
        assert_eq!(
            std::fs::read(out.join("line0.csv")).unwrap(),
            lines,
            "{what}: outputs kept"
        );
        err
    };
    let mut bad = good.clone();
    bad[100] ^= 1;
    std::fs::write(&populations, &bad).unwrap();
    let err = refused("a flipped bit");
    assert!(
        err.contains("populations.bin has checksum") && err.contains("corrupt"),
        "{err}"
    );
    std::fs::write(&populations, &good[..good.len() - 8]).unwrap();
    let err = refused("a truncated file");
    assert!(err.contains("truncated"), "{err}");
    std::fs::write(&populations, &good).unwrap();
    let text = std::fs::read_to_string(out.join("scene.toml")).unwrap();
    std::fs::write(out.join("scene.toml"), text.replace("tau = 0.8", "tau = 0.81")).unwrap();
    let err = refused("another scene");
    assert!(err.contains("is of another scene"), "{err}");
    std::fs::write(out.join("scene.toml"), &text).unwrap();
    let header = std::fs::read_to_string(out.join("checkpoint/header.json")).unwrap();
    let other = header.replacen("\"version\": 1", "\"version\": 9", 1);
    std::fs::write(out.join("checkpoint/header.json"), other).unwrap();
    let err = refused("another format version");
    assert!(err.contains("version 9") && err.contains("reads"), "{err}");
    std::fs::write(out.join("checkpoint/header.json"), header).unwrap();
    let result = resume(&out, &["--steps", "100"]);
    assert_eq!(result.status.code(), Some(2), "a checkpoint past the last step");
    assert_eq!(
        resume(&out, &[]).status.code(),
        Some(0),
        "the good checkpoint resumes"
    );
}

/// A coupled scene of 8 spheres falling in a 16^3 box for `steps` steps, rows every 5 steps,
/// checkpoints every 10.
fn falling(steps: u64) -> String {
    scene_text("ckpt-coupled", [2, 2, 2], steps, 5, 10.0)
        .replace("interval = 5\n", "interval = 5\ncheckpoint_interval = 10\n")
}

#[test]
fn a_coupled_run_killed_and_resumed_writes_the_same_particles() {
    let dir = temp_dir("ckpt-coupled");
    let scene = write_scene(&dir, &falling(60));
    let (full, part) = (dir.join("full"), dir.join("part"));
    run_ok(server(&scene, &full, &[]));
    let mut server = start(server(&scene, &part, &[]));
    server.stderr_line("checkpoint at step 30 written");
    signal(server.child.id(), libc::SIGKILL);
    let _ = server.wait_exit(Duration::from_secs(10));
    let resumed = resume(&part, &[]);
    let err = String::from_utf8_lossy(&resumed.stderr);
    assert_eq!(resumed.status.code(), Some(0), "{err}");
    same_file(&full.join("particles.csv"), &part.join("particles.csv"));
    same_file(
        &full.join("checkpoint/populations.bin"),
        &part.join("checkpoint/populations.bin"),
    );
    same_file(&full.join("checkpoint/dem.bin"), &part.join("checkpoint/dem.bin"));
}

/// A coupled run resumed with a DEM that cannot checkpoint (the Python example: no CHECKPOINT
/// in its Hello) is refused in the Welcome: exit 2, a message naming the DEM and the capability,
/// and OUT exactly as it was (particles.csv's rows after the checkpoint, the snapshots,
/// summary.json).
#[test]
fn a_resume_with_a_dem_that_cannot_checkpoint_is_refused_changing_nothing() {
    let dir = temp_dir("ckpt-nocap");
    let scene = write_scene(&dir, &falling(60));
    let out = dir.join("out");
    // The last checkpoint at step 17 records particles.csv before the rows of its last step.
    run_ok(server(&scene, &out, &["--steps", "17"]));
    let before = files_under(&out);
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/clients/python/example_dem.py");
    let line = format!("exec python3 {script} --particles 8");
    let result = resume(&out, &["--dem-command", &line]);
    let said = output_text(&result);
    assert_eq!(result.status.code(), Some(2), "{said}");
    assert!(
        said.contains("does not declare the CHECKPOINT capability") && said.contains("example_dem.py"),
        "{said}"
    );
    assert!(said.contains("CANNOT_RESUME"), "the DEM is told why: {said}");
    let after = files_under(&out);
    assert_eq!(
        before.keys().collect::<Vec<_>>(),
        after.keys().collect::<Vec<_>>(),
        "the same files"
    );
    for (path, bytes) in &before {
        assert!(&after[path] == bytes, "{} changed", path.display());
    }
}

/// The pour of `POUR`, with checkpoints every 10 steps and VTK on.
fn settling() -> String {
    POUR.replace("interval = 25\n", "interval = 25\ncheckpoint_interval = 10\n")
        + "[dem.output]\nvtk = true\n"
}

fn dem_client(args: &[&std::ffi::OsStr]) -> std::process::Output {
    std::process::Command::new(bin("dem-client"))
        .arg("run")
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn a_granular_run_stopped_and_resumed_writes_the_same_bytes() {
    let dir = temp_dir("ckpt-dem");
    let scene = write_scene(&dir, &settling());
    let (full, part) = (dir.join("full"), dir.join("part"));
    let os = |s: &'static str| std::ffi::OsStr::new(s);
    let ok = |run: std::process::Output| {
        let err = String::from_utf8_lossy(&run.stderr).into_owned();
        assert_eq!(run.status.code(), Some(0), "{err}");
        err
    };
    ok(dem_client(&[scene.as_os_str(), os("--out"), full.as_os_str()]));
    let err = ok(dem_client(&[
        scene.as_os_str(),
        os("--out"),
        part.as_os_str(),
        os("--steps"),
        os("23"),
    ]));
    assert!(err.contains("checkpoint at step 23 written"), "{err}");
    let err = ok(dem_client(&[os("--resume"), part.as_os_str()]));
    assert!(err.contains("resumed at step 23"), "{err}");
    for file in [
        "particles.csv",
        "energy.csv",
        "particles.pvd",
        "particles_000050.vtp",
        "checkpoint/dem.bin",
    ] {
        same_file(&full.join(file), &part.join(file));
    }
    let text = std::fs::read_to_string(part.join("scene.toml")).unwrap();
    std::fs::write(
        part.join("scene.toml"),
        text.replace("count = [5, 5, 6]", "count = [5, 5, 5]"),
    )
    .unwrap();
    let run = dem_client(&[os("--resume"), part.as_os_str(), os("--steps"), os("60")]);
    let err = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{err}");
    assert!(err.contains("is of another scene"), "{err}");
}
