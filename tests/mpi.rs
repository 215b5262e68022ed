//! A run decomposed over MPI ranks (`mpirun -np N lbm-server run`), against the same run in one
//! process, walled and periodic, on 2 and 4 ranks: a fluid-only run's probe lines and every field
//! snapshot byte for byte; a coupled run's particles.csv and snapshots byte for byte, spheres
//! across the cuts, the covered cells redone (the exchange after the whole step), skipped and
//! fused (the exchange overlapped); and the refusals of blocks that cannot be. The runs need mpirun
//! and an lbm-server built with `--features mpi`; where either is missing they say so and pass.

mod common;
use common::mpi::{
    coupled_outputs, coupled_scene, fluid_outputs, mpirun, mpirun_command, scene, text, Files, PERIODIC,
    SOLID, WALLED,
};
use common::*;
use std::path::{Path, PathBuf};

/// The scene on one process, then on each of `runs`' ranks with its `[parallel]` section (or
/// none): the same `outputs` byte for byte, and the summary names the ranks and blocks. The runs'
/// folder (the run on N ranks in npN); none where the runs cannot be made (said why).
fn same_on_ranks(
    tag: &str,
    text_: &str,
    runs: &[(usize, &str)],
    outputs: fn(&Path) -> Files,
) -> Option<PathBuf> {
    let Some(mpirun) = mpirun() else {
        eprintln!("skipped: mpirun is not installed (apt-get install openmpi-bin libopenmpi-dev)");
        return None;
    };
    let dir = temp_dir(tag);
    let scene = write_scene(&dir, text_);
    let single = dir.join("one");
    let o = server(&scene, &single, &[]).output().unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let expected = outputs(&single);
    for &(n, parallel) in runs {
        let out = dir.join(format!("np{n}"));
        let scene = dir.join(format!("np{n}.toml"));
        std::fs::write(&scene, format!("{text_}\n{parallel}\n")).unwrap();
        let o = mpirun_command(&mpirun, n, &scene, &out).output().unwrap();
        if text(&o).contains("built without MPI") {
            eprintln!("skipped: lbm-server is built without MPI (cargo build -p lbm-server --features mpi)");
            return None;
        }
        assert_eq!(o.status.code(), Some(0), "{n} ranks: {}", text(&o));
        // The run's first line names the ranks and their blocks.
        assert!(text(&o).contains(&format!("{n} ranks in ")), "{}", text(&o));
        for ((file, want), (_, have)) in expected.iter().zip(outputs(&out)) {
            assert!(
                *want == have,
                "{n} ranks: {file} differs from the single process's"
            );
        }
        let s = summary(&out);
        assert_eq!(s["parallel"]["ranks"], n, "{s}");
        let blocks: u64 = (0..3)
            .map(|a| s["parallel"]["blocks"][a].as_u64().unwrap())
            .product();
        assert_eq!(blocks, n as u64, "{s}");
        assert_eq!(s["parallel"]["devices"].as_array().unwrap().len(), n, "{s}");
    }
    Some(dir)
}

/// `[parallel] overlap` unset: on a CPU driver the exchange follows the whole step (nothing
/// overlaps there), on a GPU it overlaps the interior's update.
#[test]
fn a_walled_run_on_2_and_4_ranks_is_the_single_process_run_byte_for_byte() {
    let Some(dir) = same_on_ranks(
        "mpi-walled",
        &scene("walled", WALLED, SOLID),
        &[(2, ""), (4, "")],
        fluid_outputs,
    ) else {
        return;
    };
    let s = summary(&dir.join("np2"));
    let on_cpu = s["parallel"]["devices"][0].as_str().unwrap().contains("llvmpipe");
    assert_eq!(s["parallel"]["halo_overlapped"], !on_cpu, "{s}");
}

#[test]
fn a_periodic_run_cut_along_two_axes_is_the_single_process_run_byte_for_byte() {
    let parallel = "[parallel]\nblocks = [2, 1, 2]\noverlap = true";
    let Some(dir) = same_on_ranks(
        "mpi-periodic",
        &scene("periodic", PERIODIC, ""),
        &[(4, parallel)],
        fluid_outputs,
    ) else {
        return;
    };
    assert_eq!(summary(&dir.join("np4"))["parallel"]["halo_overlapped"], true);
}

/// Blocks that cannot be are refused before anything runs, naming the field and value: on one
/// process, more blocks than ranks (or, built without MPI, more than one block).
#[test]
fn blocks_that_cannot_be_are_refused_before_the_run() {
    let dir = temp_dir("mpi-blocks");
    let scene_file = write_scene(&dir, &scene("blocks", WALLED, "[parallel]\nblocks = [1, 1, 2]"));
    let o = server(&scene_file, &dir.join("out"), &[]).output().unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    let err = text(&o);
    assert!(err.contains("parallel.blocks = [1, 1, 2]"), "{err}");
    assert!(
        err.contains("needs the MPI build") || err.contains("2 blocks, but the run has 1 rank"),
        "{err}"
    );
    assert!(!dir.join("out").join("summary.json").exists(), "nothing ran");
    let scene_file = write_scene(&dir, &scene("blocks", WALLED, "[parallel]\nblocks = [3, 1, 1]"));
    let o = server(&scene_file, &dir.join("out"), &[]).output().unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains("parallel.blocks[0] = 3: must divide the lattice's 8 cells along x"),
        "{}",
        text(&o)
    );
}

/// Started as one of several ranks (as mpirun starts it) by a build without MPI, the run is
/// refused: each rank would run the whole scene alone.
#[test]
fn a_build_without_mpi_refuses_to_run_as_one_of_several_ranks() {
    let dir = temp_dir("mpi-without");
    let scene_file = write_scene(&dir, &scene("without", PERIODIC, ""));
    let probe = server(&scene_file, &dir.join("probe"), &["--steps", "1"])
        .output()
        .unwrap();
    let blocks = write_scene(
        &dir,
        &scene("without", PERIODIC, "[parallel]\nblocks = [1, 1, 2]"),
    );
    let built = server(&blocks, &dir.join("probe2"), &[]).output().unwrap();
    assert_eq!(probe.status.code(), Some(0), "{}", text(&probe));
    if !text(&built).contains("needs the MPI build") {
        eprintln!("skipped: lbm-server is built with MPI");
        return;
    }
    let scene_file = write_scene(&dir, &scene("without", PERIODIC, ""));
    let o = server(&scene_file, &dir.join("out"), &[])
        .env("OMPI_COMM_WORLD_SIZE", "2")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("built without MPI"), "{}", text(&o));
}

#[test]
fn a_coupled_walled_run_on_2_and_4_ranks_writes_the_single_process_particles_byte_for_byte() {
    let scene = coupled_scene("coupled-walled", false);
    let runs = [(2, ""), (4, "[parallel]\noverlap = true")];
    let Some(dir) = same_on_ranks("mpi-coupled-walled", &scene, &runs, coupled_outputs) else {
        return;
    };
    // "auto" takes the redo on ranks; its exchange follows the whole step by a CPU driver's
    // default, and overlaps the interior's update where the scene asks.
    for (n, overlapped) in [(2, false), (4, true)] {
        let s = summary(&dir.join(format!("np{n}")));
        assert_eq!(s["parallel"]["halo_overlapped"], overlapped, "{s}");
        assert_eq!(s["covered_cells"], "redo", "{s}");
    }
}

#[test]
fn a_coupled_periodic_run_on_2_and_4_ranks_writes_the_single_process_particles_byte_for_byte() {
    let blocks = "[parallel]\nblocks = [2, 1, 2]";
    let scene = coupled_scene("coupled-periodic", true);
    same_on_ranks(
        "mpi-coupled-periodic",
        &scene,
        &[(2, ""), (4, blocks)],
        coupled_outputs,
    );
}

/// The covered cells skipped (on 2 ranks) and fused (on 4, cut along two axes): particles.csv
/// and the snapshots byte for byte, the halo exchange overlapped with the interior's update
/// (summary.json's `halo_overlapped`).
#[test]
fn a_coupled_run_on_ranks_with_the_covered_cells_skipped_or_fused_overlaps_the_exchange() {
    let blocks = "[parallel]\nblocks = [2, 1, 2]\noverlap = true";
    for (way, n, parallel) in [("skip", 2, "[parallel]\noverlap = true"), ("fused", 4, blocks)] {
        let text_ = coupled_scene(&format!("coupled-{way}"), true).replace(
            "timeout = 10.0",
            &format!("timeout = 10.0\ncovered_cells = \"{way}\""),
        );
        let tag = format!("mpi-coupled-{way}");
        let Some(dir) = same_on_ranks(&tag, &text_, &[(n, parallel)], coupled_outputs) else {
            return;
        };
        let s = summary(&dir.join(format!("np{n}")));
        assert_eq!(s["parallel"]["halo_overlapped"], true, "{way}: {s}");
    }
}

/// `coupling.covered_cells = "timed"` on 2 ranks: every rank times the three ways on the same
/// steps by rank 0's clock and keeps the same one; summary.json says what the trial timed and
/// kept; particles.csv and the snapshots byte for byte as the single process's (which times them
/// too: every way gives the same bits).
#[test]
fn a_coupled_run_on_ranks_times_the_ways_of_the_covered_cells_at_start_up() {
    let text_ = coupled_scene("coupled-timed", false)
        .replace("steps = 24", "steps = 150")
        .replace("\ninterval = 4", "\ninterval = 25")
        .replace("timeout = 10.0", "timeout = 10.0\ncovered_cells = \"timed\"")
        .replace("operator = \"trt\"", "operator = \"trt\"\nkernel = \"quads\"");
    let runs = [(2, "[parallel]\noverlap = true")];
    let Some(dir) = same_on_ranks("mpi-coupled-timed", &text_, &runs, coupled_outputs) else {
        return;
    };
    let s = summary(&dir.join("np2"));
    let trial = s["trial"].as_array().expect("the trial's lines").clone();
    assert!(
        trial
            .iter()
            .any(|l| l.as_str().is_some_and(|l| l.contains("kept"))),
        "{s}"
    );
    assert!(
        ["redo", "skip", "fused"].contains(&s["covered_cells"].as_str().unwrap()),
        "{s}"
    );
}
