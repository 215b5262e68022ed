//! Two real processes complete coupled runs (lattice + immersed boundary + DEM) in lockstep; every
//! step index is checked on both sides.

mod common;
use common::*;
use std::time::Duration;

/// Runs `steps` steps with a block of `count` particles and checks summary and output.
fn lockstep_run(tag: &str, count: [u64; 3], steps: u64, interval: u64) {
    let n: u64 = count.iter().product();
    let dir = temp_dir(tag);
    let scene = write_scene(&dir, &scene_text(tag, count, steps, interval, 10.0));
    let out = dir.join("out");
    let mut server = start(server(&scene, &out, &[]));
    let (code, _) = server.wait_exit(Duration::from_secs(300));
    let stderr = Proc::drain(&server.stderr);
    assert_eq!(code, Some(0), "lbm-server failed:\n{stderr}");
    assert!(
        stderr.contains(&format!("dem-client: finished after {steps} steps")),
        "{stderr}"
    );
    let s = summary(&out);
    assert_eq!(s["steps_completed"], steps);
    assert_eq!(s["last_completed_step"], steps - 1);
    assert_eq!(s["particles_initial"], n);
    assert_eq!(s["exit_reason"], "completed");
    let physics = s["fluid_physics"].to_string();
    assert!(
        physics.contains("lattice-boltzmann") && physics.contains("immersed-boundary"),
        "{physics}"
    );
    let rows = csv_steps(&out);
    let expected: Vec<u64> = (0..steps)
        .filter(|k| k % interval == 0 || *k == steps - 1)
        .collect();
    assert_eq!(rows.keys().copied().collect::<Vec<_>>(), expected);
    for (step, ids) in &rows {
        let mut sorted = ids.clone();
        sorted.sort();
        assert_eq!(sorted, (0..n).collect::<Vec<_>>(), "ids at step {step}");
    }
    let run = s["run"].as_str().unwrap();
    assert!(
        leftover_files(run).is_empty(),
        "clean run left {:?}",
        leftover_files(run)
    );
}

#[test]
fn one_particle_1000_steps() {
    lockstep_run("one", [1, 1, 1], 1000, 100);
}

/// 1000 sub-cell spheres on a 16^3 lattice: 300 steps (each covers 1000 spheres on the lattice).
#[test]
fn thousand_particles_300_steps() {
    lockstep_run("thousand", [10, 10, 10], 300, 100);
}

/// 20 000 sub-cell spheres on a 42 x 27 x 22 lattice: 20 steps, since each step covers 20 000
/// spheres on the lattice (about 0.1-0.25 s a step on a CPU Vulkan); the 1000-step run above
/// checks the long lockstep.
#[test]
fn twenty_thousand_particles_20_steps() {
    lockstep_run("twentyk", [40, 25, 20], 20, 5);
}

#[test]
fn particle_count_changes_between_steps() {
    let dir = temp_dir("churn");
    let scene = write_scene(&dir, &scene_text("churn", [3, 3, 3], 200, 1, 10.0));
    let out = dir.join("out");
    let (mut server, run) = start_external(&scene, &out);
    let client = std::process::Command::new(bin("dem-client"))
        .args(["connect", "--service", &run, "--churn", "--scene"])
        .arg(&scene)
        .output()
        .unwrap();
    assert!(
        client.status.success(),
        "{}",
        String::from_utf8_lossy(&client.stderr)
    );
    let (code, _) = server.wait_exit(Duration::from_secs(60));
    assert_eq!(code, Some(0), "{}", Proc::drain(&server.stderr));
    let rows = csv_steps(&out);
    assert_eq!(rows.len(), 200);
    let counts: Vec<usize> = rows.values().map(Vec::len).collect();
    assert_eq!(
        &counts[..4],
        &[27, 26, 27, 26],
        "one removed, one inserted, alternately"
    );
    assert!(rows[&2].contains(&27), "the inserted particle carries a fresh id");
}

#[test]
fn a_wrong_step_index_breaks_the_run_on_both_sides() {
    let dir = temp_dir("skip");
    let scene = write_scene(&dir, &scene_text("skip", [2, 2, 2], 100, 10, 10.0));
    let out = dir.join("out");
    let (mut server, run) = start_external(&scene, &out);
    let mut client = std::process::Command::new(bin("dem-client"));
    client
        .args(["connect", "--service", &run, "--skip-step", "37", "--scene"])
        .arg(&scene);
    let mut client = start(client);
    let (code, _) = server.wait_exit(Duration::from_secs(30));
    let stderr = Proc::drain(&server.stderr);
    assert_eq!(code, Some(1));
    assert!(stderr.contains("sent step 38 where step 37 was due"), "{stderr}");
    assert!(stderr.contains("last completed step: 36"), "{stderr}");
    let (client_code, waited) = client.wait_exit(Duration::from_secs(5));
    assert_eq!(client_code, Some(1));
    assert!(waited < 1.0, "the DEM noticed the server's exit after {waited} s");
    assert_eq!(summary(&out)["steps_completed"], 37);
}
