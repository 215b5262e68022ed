//! No process outlives the one that started it: a test harness killed (its timeout, Ctrl-C of
//! `cargo test`) takes the lbm-server it started along, and that lbm-server its dem-client, as
//! does mpirun its ranks; an lbm-server killed while its dem-client joins the run takes the
//! dem-client along at once, not after the client's timeout (`die_with_test`,
//! `protocol::liveness::die_with_parent`).

mod common;
use common::mpi::{mpirun, mpirun_command, scene, WALLED};
use common::*;
use std::process::Command;
use std::time::{Duration, Instant};

/// How long the processes of a killed parent may take to end: a dem-client that steps notices
/// at its next wait (PROTOCOL.md 7), mpirun ends its ranks within about 2 s, with room for load.
const GONE_WITHIN: Duration = Duration::from_secs(15);

/// Waits until every process of `pids` is gone; those left after [`GONE_WITHIN`].
fn left_after_a_while(pids: &[u32]) -> Vec<u32> {
    let start = Instant::now();
    while pids.iter().any(|&p| !is_gone(p)) && start.elapsed() < GONE_WITHIN {
        std::thread::sleep(Duration::from_millis(20));
    }
    pids.iter().copied().filter(|&p| !is_gone(p)).collect()
}

/// What `ps` says of the processes `pids`, for a failure's message.
fn described(pids: &[u32]) -> String {
    let list: Vec<String> = pids.iter().map(u32::to_string).collect();
    let ps = Command::new("ps")
        .args(["-o", "pid,ppid,stat,etime,args", "-p", &list.join(",")])
        .output();
    ps.map(|o| output_text(&o)).unwrap_or_default()
}

/// A coupled run of many steps (a spawned dem-client with the coupling timeout `timeout_s`),
/// started, with the dem-client's pid once started.
fn long_coupled_run(tag: &str, timeout_s: f64) -> (Proc, u32) {
    let dir = temp_dir(tag);
    let scene = write_scene(&dir, &scene_text(tag, [2, 2, 2], 10_000_000, 1000, timeout_s));
    let mut server = start(server(&scene, &dir.join("out"), &[]));
    let dem = dem_of(&mut server);
    (server, dem)
}

/// A fluid run of many steps on 2 MPI ranks, stepping, with its ranks' pids; None where mpirun
/// or the MPI build is missing.
fn long_mpi_run() -> Option<(Proc, Vec<u32>)> {
    let mpirun = mpirun()?;
    let text = scene("long", WALLED, "[parallel]\nblocks = [1, 1, 2]")
        .replace("steps = 12", "steps = 100000000")
        .replace("interval = 6\n", "interval = 100000000\n");
    let dir = temp_dir("orphan-mpi");
    let scene_file = write_scene(&dir, &text);
    let probe = server(&scene_file, &dir.join("probe"), &[]).output().unwrap();
    if output_text(&probe).contains("needs the MPI build") {
        return None;
    }
    let run = start(mpirun_command(&mpirun, 2, &scene_file, &dir.join("out")));
    run.stderr_line("lbm-server: step ");
    let pid = run.child.id();
    let children = std::fs::read_to_string(format!("/proc/{pid}/task/{pid}/children")).unwrap();
    let ranks = children.split_whitespace().map(|c| c.parse().unwrap()).collect();
    Some((run, ranks))
}

/// The harness that `a_killed_harness_leaves_no_process` kills: starts a coupled run and (where
/// it can) a run on MPI ranks, prints `pids: ...` of all their processes, and waits to be killed.
#[test]
#[ignore = "run by a_killed_harness_leaves_no_process"]
fn harness_to_kill() {
    let (server, dem) = long_coupled_run("orphan-harness", 60.0);
    let mut pids = vec![server.child.id(), dem];
    let mpi = long_mpi_run();
    if let Some((run, ranks)) = &mpi {
        pids.push(run.child.id());
        pids.extend(ranks);
    }
    let list: Vec<String> = pids.iter().map(u32::to_string).collect();
    println!("pids: {}", list.join(" "));
    std::thread::sleep(Duration::from_secs(600));
}

#[test]
fn a_killed_harness_leaves_no_process() {
    let mut cmd = Command::new(std::env::current_exe().unwrap());
    cmd.args(["harness_to_kill", "--exact", "--ignored", "--nocapture"]);
    let harness = start(cmd);
    let line = harness.stdout_line("pids: ");
    let pids: Vec<u32> = line["pids: ".len()..]
        .split_whitespace()
        .map(|p| p.parse().unwrap())
        .collect();
    if pids.len() == 2 {
        eprintln!("the MPI part skipped: mpirun or lbm-server's MPI build missing");
    }
    signal(harness.child.id(), libc::SIGKILL);
    let left = left_after_a_while(&pids);
    assert!(left.is_empty(), "left running:\n{}", described(&left));
}

#[test]
fn a_dem_client_joining_dies_with_its_killed_lbm_server() {
    // Its timeout of 60 s is what a dem-client left behind would wait for the fluid.
    let (mut server, dem) = long_coupled_run("orphan-joining", 60.0);
    signal(server.child.id(), libc::SIGKILL);
    server.wait_exit(Duration::from_secs(10));
    let left = left_after_a_while(&[dem]);
    assert!(left.is_empty(), "left running:\n{}", described(&left));
}
