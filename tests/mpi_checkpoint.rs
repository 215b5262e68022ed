//! Checkpoints and `--resume` on MPI ranks (docs/checkpoint.md): a run on 2 ranks stopped early
//! writes, byte for byte, the checkpoint one process writes at that step, and resumed on 1, 2
//! and 4 ranks writes the outputs of one uninterrupted single-process run byte for byte (a
//! fluid-only run's probe lines and snapshots, a coupled run's particles.csv and snapshots) and
//! its last checkpoint. The runs need mpirun and an lbm-server built with `--features mpi`;
//! where either is missing they say so and pass.

mod common;
use common::mpi::{coupled_outputs, coupled_scene, fluid_outputs, mpirun, mpirun_run, scene, text};
use common::mpi::{Files, SOLID, WALLED};
use common::*;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A file's bytes.
fn read(path: &Path) -> Vec<u8> {
    std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The checkpoint in `out`, as it must not depend on the ranks: every file header.json lists,
/// and header.json with the snapshots named as one process names them (a .pvti on several ranks).
fn checkpoint_files(out: &Path) -> Files {
    let dir = out.join("checkpoint");
    let header = String::from_utf8(read(&dir.join("header.json"))).unwrap();
    let listed: serde_json::Value = serde_json::from_str(&header).unwrap();
    let mut files = vec![(
        "header.json".to_string(),
        header.replace(".pvti\"", ".vti\"").into_bytes(),
    )];
    for f in listed["files"].as_array().unwrap() {
        let name = f["file"].as_str().unwrap();
        files.push((name.to_string(), read(&dir.join(name))));
    }
    assert!(files.iter().any(|(f, _)| f == "populations.bin"), "{header}");
    files
}

/// The files `have` are the files `want`, name by name and byte for byte.
fn same(want: &[(String, Vec<u8>)], have: &[(String, Vec<u8>)], what: &str) {
    let names = |f: &[(String, Vec<u8>)]| f.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>();
    assert_eq!(names(want), names(have), "{what}");
    for ((file, w), (_, h)) in want.iter().zip(have) {
        assert!(w == h, "{what}: {file} differs from the single process's");
    }
}

/// Runs `cmd`, which must exit 0.
fn ok(cmd: &mut Command, what: &str) -> Output {
    let o = cmd.output().unwrap();
    assert_eq!(o.status.code(), Some(0), "{what}: {}", text(&o));
    o
}

/// `lbm-server run --resume OUT` on `ranks` ranks (one: the plain process, no mpirun).
fn resume(mpirun: &Path, ranks: usize, out: &Path) -> Command {
    let mut cmd = match ranks {
        1 => {
            let mut cmd = Command::new(bin("lbm-server"));
            cmd.arg("run");
            cmd
        }
        _ => mpirun_run(mpirun, ranks),
    };
    cmd.arg("--resume").arg(out);
    cmd
}

/// The scene `text_` run through on one process, and to `stop` on 2 ranks and on one process
/// (checkpoints as the scene says, or every `every` steps where given): the same checkpoint at
/// `stop`; the 2 ranks' run then resumed on 1, 2 and 4 ranks: the same `outputs` and last
/// checkpoint as the run through.
/// mpirun and the 2 ranks' output folder, as they stopped (None where the runs cannot be made:
/// said why).
fn resumed_on_ranks(
    tag: &str,
    text_: &str,
    (stop, every): (&str, Option<&str>),
    outputs: fn(&Path) -> Files,
) -> Option<(PathBuf, PathBuf)> {
    let Some(mpirun) = mpirun() else {
        eprintln!("skipped: mpirun is not installed (apt-get install openmpi-bin libopenmpi-dev)");
        return None;
    };
    let dir = temp_dir(tag);
    let scene_file = write_scene(&dir, text_);
    let interval = every.map_or(vec![], |n| vec!["--checkpoint-interval", n]);
    let stopped = [&interval[..], &["--steps", stop]].concat();
    let part = dir.join("part");
    let mut cmd = mpirun_run(&mpirun, 2);
    cmd.arg(&scene_file).arg("--out").arg(&part).args(&stopped);
    let o = cmd.output().unwrap();
    if text(&o).contains("built without MPI") {
        eprintln!("skipped: lbm-server is built without MPI (cargo build -p lbm-server --features mpi)");
        return None;
    }
    assert_eq!(o.status.code(), Some(0), "2 ranks to step {stop}: {}", text(&o));
    let (through, one_stop) = (dir.join("through"), dir.join("one-stop"));
    ok(&mut server(&scene_file, &through, &interval), "one process");
    ok(
        &mut server(&scene_file, &one_stop, &stopped),
        "one process to the stop",
    );
    let what = format!("the checkpoint at step {stop} written on 2 ranks");
    same(&checkpoint_files(&one_stop), &checkpoint_files(&part), &what);
    let (want, want_checkpoint) = (outputs(&through), checkpoint_files(&through));
    for ranks in [1, 2, 4] {
        let out = dir.join(format!("resumed-on-{ranks}"));
        ok(Command::new("cp").arg("-a").arg(&part).arg(&out), "cp");
        let o = ok(
            &mut resume(&mpirun, ranks, &out),
            &format!("resumed on {ranks} rank(s)"),
        );
        let said = text(&o);
        assert!(
            said.contains(&format!("from its checkpoint at step {stop} ")),
            "{said}"
        );
        let what = format!("written on 2 ranks, resumed on {ranks}");
        same(&want, &outputs(&out), &what);
        same(
            &want_checkpoint,
            &checkpoint_files(&out),
            &format!("{what}: the last checkpoint"),
        );
    }
    Some((mpirun, part))
}

/// A walled box with solid cells across the cuts, checkpoints every 4 steps (the scene's),
/// stopped after step 7 (odd: the AA pattern's odd phase).
#[test]
fn a_fluid_run_checkpointed_on_2_ranks_resumes_on_1_2_and_4_as_one_process_runs_through() {
    let text_ = scene("mpi-ckpt-fluid", WALLED, SOLID).replace(
        "fields_interval = 6",
        "fields_interval = 6\ncheckpoint_interval = 4",
    );
    assert!(text_.contains("checkpoint_interval = 4"));
    resumed_on_ranks("mpi-ckpt-fluid", &text_, ("7", None), fluid_outputs);
}

/// Two spheres, one across the cuts of 2 and 4 blocks, checkpoints every 8 steps
/// (`--checkpoint-interval`, kept by the resumed runs), stopped after step 10 (even); the DEM's
/// half of the checkpoint (dem.bin) too. Resumed on 2 ranks with a DEM that cannot checkpoint
/// (the Python example: no CHECKPOINT in its Hello), it is refused in the Welcome as on one
/// process: every rank ends, the DEM is told why (CANNOT_RESUME), OUT is left as it was.
#[test]
fn a_coupled_run_checkpointed_on_2_ranks_resumes_on_1_2_and_4_as_one_process_runs_through() {
    let text_ = coupled_scene("mpi-ckpt-coupled", false);
    let Some((mpirun, part)) =
        resumed_on_ranks("mpi-ckpt-coupled", &text_, ("10", Some("8")), coupled_outputs)
    else {
        return;
    };
    let Some(python) = python_with_iceoryx2() else {
        eprintln!("skipped the refusal: python3 has no iceoryx2 (pip install iceoryx2==0.10.0)");
        return;
    };
    let before = files_under(&part);
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/clients/python/example_dem.py");
    let line = format!("exec {python} {script} --particles 2");
    let o = resume(&mpirun, 2, &part)
        .args(["--dem-command", &line])
        .output()
        .unwrap();
    let said = text(&o);
    assert_ne!(o.status.code(), Some(0), "{said}");
    assert!(
        said.contains("does not declare the CHECKPOINT capability"),
        "{said}"
    );
    assert!(said.contains("CANNOT_RESUME"), "the DEM is told why: {said}");
    let after = files_under(&part);
    assert_eq!(
        before.keys().collect::<Vec<_>>(),
        after.keys().collect::<Vec<_>>()
    );
    for (path, bytes) in &before {
        assert!(&after[path] == bytes, "{} changed", path.display());
    }
}

/// The interpreter `python3` names here, where it has the iceoryx2 binding: named by its path,
/// since mpirun started by its own path puts its folder (/usr/bin) first on the ranks' PATH.
fn python_with_iceoryx2() -> Option<String> {
    let o = Command::new("python3")
        .args(["-c", "import sys, iceoryx2; print(sys.executable)"])
        .output()
        .ok()?;
    o.status
        .success()
        .then(|| String::from_utf8_lossy(&o.stdout).trim().to_string())
}
