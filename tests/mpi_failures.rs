//! A run on MPI ranks that fails or is stopped ends on every rank: a blow-up in rank 1's block
//! stops all ranks with the rank, steps, cell and quantity; Ctrl-C to mpirun stops every rank in
//! order (summary written, exit 130), a coupled run's DEM too, its shared memory removed; a rank
//! killed (kill -9) ends the others within seconds with mpirun's message naming it. The runs need mpirun and an lbm-server built with
//! `--features mpi`; where either is missing they say so and pass.

mod common;
use common::mpi::{mpirun, mpirun_command, scene, WALLED};
use common::*;
use std::path::PathBuf;
use std::time::Duration;

/// How long the ranks may take to end once stopped or once one is killed: mpirun ends the job
/// within about 2 s of a rank's death (measured 1.1-2.2 s on 2 busy cores), with room for load.
const ENDED_WITHIN_S: f64 = 8.0;

/// mpirun and a scene file (of 2 blocks) in a fresh folder, or None where the runs cannot be made (said why).
fn setup(tag: &str, text: &str) -> Option<(PathBuf, PathBuf, PathBuf)> {
    let Some(mpirun) = mpirun() else {
        eprintln!("skipped: mpirun is not installed (apt-get install openmpi-bin libopenmpi-dev)");
        return None;
    };
    let dir = temp_dir(tag);
    let scene_file = write_scene(&dir, text);
    // One process refuses the scene's 2 blocks, saying whether the build has MPI.
    let probe = server(&scene_file, &dir.join("probe"), &[]).output().unwrap();
    if output_text(&probe).contains("needs the MPI build") {
        eprintln!("skipped: lbm-server is built without MPI (cargo build -p lbm-server --features mpi)");
        return None;
    }
    Some((mpirun, scene_file, dir.join("out")))
}

/// The walled box run for (nearly) ever on 2 ranks in 1x1x2 blocks, started; the pids of its
/// ranks once they step.
fn started_long_run(tag: &str) -> Option<(Proc, Vec<u32>, PathBuf)> {
    let text = scene("long", WALLED, "[parallel]\nblocks = [1, 1, 2]")
        .replace("steps = 12", "steps = 100000000")
        .replace("interval = 6\n", "interval = 100000000\n");
    started_run_of(tag, &text)
}

/// The scene `text` (of 2 blocks) run on 2 ranks, started; the pids of its ranks once they step.
fn started_run_of(tag: &str, text: &str) -> Option<(Proc, Vec<u32>, PathBuf)> {
    let (mpirun, scene_file, out) = setup(tag, text)?;
    let run = start(mpirun_command(&mpirun, 2, &scene_file, &out));
    run.stderr_line("lbm-server: step ");
    let ranks = ranks_of(run.child.id());
    assert_eq!(ranks.len(), 2, "the ranks of mpirun {}", run.child.id());
    Some((run, ranks, out))
}

/// The lbm-server processes mpirun `pid` started, in rank order.
fn ranks_of(pid: u32) -> Vec<u32> {
    let children = std::fs::read_to_string(format!("/proc/{pid}/task/{pid}/children")).unwrap_or_default();
    let mut ranks: Vec<(usize, u32)> = children
        .split_whitespace()
        .filter_map(|c| {
            let c: u32 = c.parse().ok()?;
            let env = std::fs::read(format!("/proc/{c}/environ")).ok()?;
            let rank = env
                .split(|&b| b == 0)
                .find_map(|v| v.strip_prefix(b"OMPI_COMM_WORLD_RANK="))?;
            Some((String::from_utf8_lossy(rank).parse().ok()?, c))
        })
        .collect();
    ranks.sort();
    ranks.into_iter().map(|(_, pid)| pid).collect()
}

/// mpirun and every one of `processes` (the ranks, a DEM) have ended within [`ENDED_WITHIN_S`];
/// its exit code and the lines it and the ranks wrote.
fn ended(run: &mut Proc, processes: &[u32]) -> (Option<i32>, String) {
    let (code, waited) = run.wait_exit(Duration::from_secs(60));
    assert!(waited < ENDED_WITHIN_S, "mpirun ended {waited:.1} s after");
    // mpirun may end a moment before a rank it signalled has finished ending.
    let deadline = std::time::Instant::now() + Duration::from_secs_f64(ENDED_WITHIN_S - waited);
    for &pid in processes {
        while !is_gone(pid) && std::time::Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(50));
        }
        assert!(is_gone(pid), "pid {pid} left running {ENDED_WITHIN_S} s after");
    }
    (code, Proc::drain(&run.stderr) + &Proc::drain(&run.stdout))
}

#[test]
fn a_blow_up_in_rank_1s_block_stops_every_rank_naming_rank_steps_cell_and_quantity() {
    let text = include_str!("../validation/scenes/cavity-unstable.toml").to_string()
        + "\n[parallel]\nblocks = [1, 1, 2]\n";
    let Some((mpirun, scene_file, out)) = setup("mpi-blowup", &text) else {
        return;
    };
    let o = mpirun_command(&mpirun, 2, &scene_file, &out).output().unwrap();
    let err = output_text(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("the fluid became unstable between steps"), "{err}");
    assert!(err.contains("furthest out of bounds, rank 1, cell "), "{err}");
    assert!(err.contains("outside ["), "{err}");
    assert!(err.contains("last good snapshot (step"), "{err}");
    for file in ["last_good.pvti", "last_good/rank0.vti", "last_good/rank1.vti"] {
        assert!(out.join(file).is_file(), "{file}");
    }
    let s = summary(&out);
    assert_eq!(s["exit_code"], 1, "{s}");
    assert!(s["exit_reason"].as_str().unwrap().contains("rank 1, cell"), "{s}");
}

#[test]
fn ctrl_c_to_mpirun_stops_every_rank_in_order() {
    let Some((mut run, ranks, out)) = started_long_run("mpi-ctrl-c") else {
        return;
    };
    signal(run.child.id(), libc::SIGINT);
    let (_, text) = ended(&mut run, &ranks);
    assert!(text.contains("lbm-server: interrupted after "), "{text}");
    let s = summary(&out);
    assert_eq!(s["exit_reason"], "interrupted", "{s}");
    assert_eq!(s["exit_code"], 130, "{s}");
}

#[test]
fn a_rank_killed_ends_every_rank_within_seconds_naming_it() {
    let Some((mut run, ranks, _)) = started_long_run("mpi-kill") else {
        return;
    };
    signal(ranks[1], libc::SIGKILL);
    let (code, text) = ended(&mut run, &ranks);
    assert_ne!(code, Some(0), "{text}");
    assert!(
        text.contains("process rank 1") && text.contains("signal 9"),
        "mpirun names the rank killed: {text}"
    );
}

/// Ctrl-C to mpirun on a coupled run on 2 ranks: every process (the ranks and rank 0's DEM) ends
/// within seconds, summary.json says interrupted (130), and nothing of the run is left in shared
/// memory (the other ranks end only once rank 0 has removed it: `parallel::wait_for_rank_0`).
#[test]
fn ctrl_c_to_mpirun_ends_a_coupled_run_its_dem_and_its_shared_memory() {
    let text = scene_text("coupled-ctrl-c", [2, 2, 2], 100_000_000, 100_000_000, 10.0)
        + "[parallel]\nblocks = [1, 1, 2]\n";
    let Some((mut run, ranks, out)) = started_run_of("mpi-coupled-ctrl-c", &text) else {
        return;
    };
    let dem = child_pid(ranks[0]);
    let name = std::fs::read_to_string(format!("/proc/{dem}/comm")).unwrap_or_default();
    assert_eq!(name.trim(), "dem-client", "rank 0's child {dem}");
    let files = format!("lbmdem_{}_", ranks[0]);
    assert!(
        !leftover_files(&files).is_empty(),
        "the run's files in shared memory while it runs"
    );
    signal(run.child.id(), libc::SIGINT);
    let (_, text) = ended(&mut run, &[ranks[0], ranks[1], dem]);
    assert!(text.contains("lbm-server: interrupted after "), "{text}");
    let s = summary(&out);
    assert_eq!(s["exit_reason"], "interrupted", "{s}");
    assert_eq!(s["exit_code"], 130, "{s}");
    assert!(
        leftover_files(&files).is_empty(),
        "the run's files left: {:?}",
        leftover_files(&files)
    );
}
