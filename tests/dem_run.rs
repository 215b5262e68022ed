//! `dem-client run`: a granular scene alone writes its outputs; a bad DEM scene is refused by name.
//! `dem-client bench`: the DEM side of a coupled scene timed.

mod common;
use common::*;
use std::process::Command;

#[test]
fn a_granular_scene_runs_alone_and_writes_csv_energy_and_vtk() {
    let dir = temp_dir("dem-run");
    let scene = write_scene(&dir, POUR);
    let out = dir.join("out");
    let run = dem_run(&scene, &out);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(stderr.contains("particle-steps/s"), "{stderr}");
    let rows = csv_steps(&out);
    assert_eq!(rows.keys().copied().collect::<Vec<_>>(), vec![0, 25, 50]);
    assert!(rows.values().all(|ids| ids.len() == 150));
    let energy = std::fs::read_to_string(out.join("energy.csv")).unwrap();
    assert_eq!(energy.lines().next(), Some("step,time,kinetic_energy,contacts"));
    assert_eq!(energy.lines().count(), 52);
    let last: Vec<&str> = energy.lines().last().unwrap().split(',').collect();
    assert!(
        last[3].parse::<u64>().unwrap() > 150,
        "a packed bed has contacts: {last:?}"
    );
    let pvd = std::fs::read_to_string(out.join("particles.pvd")).unwrap();
    for frame in [
        "particles_000000.vtp",
        "particles_000025.vtp",
        "particles_000050.vtp",
    ] {
        assert!(pvd.contains(frame), "{pvd}");
        let vtp = std::fs::read_to_string(out.join(frame)).unwrap();
        assert!(vtp.contains("NumberOfPoints=\"150\"") && vtp.contains("Name=\"radius\""));
    }
}

#[test]
fn a_time_step_above_the_stability_limit_is_refused_by_name() {
    let dir = temp_dir("dem-run-bad");
    let scene = write_scene(&dir, &format!("{POUR}[dem]\ndt = 1.0e-3\n"));
    let run = Command::new(bin("dem-client"))
        .arg("run")
        .arg(&scene)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains(&format!(
            "{}: dem.dt = 0.001 s: is above the stability limit",
            scene.display()
        )),
        "{stderr}"
    );
}

/// A granular scene alone, periodic along x by `domain.periodic`: no gravity, one sphere thrown
/// along +x, one along -x, each starting a radius from a face.
fn thrown(periodic: &str) -> String {
    format!(
        r#"name = "thrown"
[domain]
min = [0.0, 0.0, 0.0]
max = [0.03, 0.02, 0.02]
{periodic}
[fluid]
density = 1.2
dynamic_viscosity = 1.8e-5
[time]
dt = 1.0e-4
steps = 100
[output]
interval = 100
[particles]
density = 2500.0
[[particles.sphere]]
position = [0.027, 0.006, 0.01]
radius = 0.002
velocity = [0.5, 0.0, 0.0]
[[particles.sphere]]
position = [0.003, 0.014, 0.01]
radius = 0.002
velocity = [-0.5, 0.0, 0.0]
"#
    )
}

/// (x, vx) of each particle at the last step of particles.csv.
fn last_x_vx(out: &std::path::Path) -> Vec<(f64, f64)> {
    let text = std::fs::read_to_string(out.join("particles.csv")).unwrap();
    let last_step = text
        .lines()
        .last()
        .unwrap()
        .split(',')
        .next()
        .unwrap()
        .to_string();
    text.lines()
        .skip(1)
        .filter(|l| l.split(',').next() == Some(last_step.as_str()))
        .map(|l| {
            let c: Vec<f64> = l.split(',').map(|v| v.parse().unwrap()).collect();
            (c[3], c[6])
        })
        .collect()
}

fn dem_run(scene: &std::path::Path, out: &std::path::Path) -> std::process::Output {
    Command::new(bin("dem-client"))
        .arg("run")
        .arg(scene)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

/// Through the faces of a periodic axis the spheres come back on the other side at the same
/// speed (gravity off, nothing in the way); with walls there they bounce.
#[test]
fn spheres_pass_through_the_faces_of_a_periodic_granular_scene() {
    let dir = temp_dir("dem-periodic");
    for (periodic, through) in [("periodic = [\"x\"]", true), ("", false)] {
        let scene = write_scene(&dir, &thrown(periodic));
        let out = dir.join(if through { "periodic" } else { "walls" });
        let run = dem_run(&scene, &out);
        assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
        // 100 steps of 0.1 ms at 0.5 m/s: 5 mm, through the face 2 mm ahead of each centre.
        let got = last_x_vx(&out);
        assert_eq!(got.len(), 2);
        let (forward, backward) = (got[0], got[1]);
        if through {
            assert!(
                (forward.0 - 0.002).abs() < 1e-9,
                "+x sphere wrapped to x = 2 mm: {got:?}"
            );
            assert!(
                (backward.0 - 0.028).abs() < 1e-9,
                "-x sphere wrapped to x = 28 mm: {got:?}"
            );
            assert_eq!((forward.1, backward.1), (0.5, -0.5), "speeds kept: {got:?}");
        } else {
            assert!(
                forward.1 < 0.0 && backward.1 > 0.0,
                "bounced off the walls: {got:?}"
            );
            assert!(forward.0 < 0.03 && backward.0 > 0.0, "{got:?}");
        }
    }
}

/// Two spheres at opposite faces of a periodic axis overlap across it, and a periodic axis
/// shorter than two pair reaches is refused, each naming the field.
#[test]
fn a_periodic_granular_scene_is_checked_across_its_faces() {
    let dir = temp_dir("dem-periodic-bad");
    let across = thrown("periodic = [\"x\"]").replace(
        "position = [0.003, 0.014, 0.01]",
        "position = [0.0005, 0.006, 0.01]",
    );
    let short =
        thrown("periodic = [\"x\", \"y\"]").replace("max = [0.03, 0.02, 0.02]", "max = [0.03, 0.007, 0.02]");
    let short = short.replace("0.014, 0.01]", "0.001, 0.01]");
    for (what, text, words) in [
        (
            "overlap across x",
            across,
            vec!["particles (ids 0 and 1)", "overlap 5.000e-4 m"],
        ),
        (
            "short periodic y",
            short,
            vec!["domain.periodic = [\"x\", \"y\"]", "y"],
        ),
    ] {
        let scene = write_scene(&dir, &text);
        let run = dem_run(&scene, &dir.join("out"));
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{what}: {stderr}");
        for w in words {
            assert!(stderr.contains(w), "{what}: {w:?} missing from {stderr}");
        }
    }
}

/// `dem-client bench` times the DEM side of a coupled scene (validation/scenes/bed.toml, 4 x 4 x 2
/// of its beads): with free flight the beads in their films are one island in every fluid step,
/// without it they take every DEM step with the whole lists; a scene without a lattice is refused.
#[test]
fn the_dem_bench_times_a_coupled_scene_with_free_flight_on_and_off() {
    let dir = temp_dir("dem-bench");
    let scene = write_scene(&dir, &small_bed());
    let run = Command::new(bin("dem-client"))
        .args(["bench", "--steps", "3"])
        .arg(&scene)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    let lines: Vec<&str> = stderr.lines().collect();
    let on = lines
        .iter()
        .position(|l| l.contains("free flight on"))
        .expect(&stderr);
    let off = lines
        .iter()
        .position(|l| l.contains("free flight off"))
        .expect(&stderr);
    let k = dem_steps_per_fluid_step(lines[on]).expect(&stderr);
    assert!(lines[on].contains("32 spheres, 3 fluid steps"), "{stderr}");
    // Every bead is in the island: its first fluid steps alternate the island's world and the
    // whole world's lists (their trial, dem/world/everyone.rs), two of three through the island.
    assert!(
        lines[on + 2].contains(&format!(
            "{} DEM steps, 0 fluid steps flown whole, 2 with an island (0 dropped)",
            3 * k
        )),
        "{stderr}"
    );
    assert!(
        lines[off + 2].contains(&format!(
            "{} DEM steps, 0 fluid steps flown whole, 0 with an island",
            3 * k
        )),
        "{stderr}"
    );
    assert!(lines[on + 1].contains(" ms per fluid step"), "{stderr}");

    let granular = write_scene(&dir, POUR);
    let refused = Command::new(bin("dem-client"))
        .arg("bench")
        .arg(&granular)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("the scene has no [lattice]"), "{stderr}");
}

/// validation/scenes/bed.toml with 4 x 4 x 2 of its beads.
fn small_bed() -> String {
    let bed =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/validation/scenes/bed.toml")).unwrap();
    let small = bed.replace("count = [32, 32, 32]", "count = [4, 4, 2]");
    assert_ne!(
        small, bed,
        "validation/scenes/bed.toml holds the count this test shrinks"
    );
    small
}

/// The DEM steps per fluid step that the bench's `line` names ("... K DEM steps of ...").
fn dem_steps_per_fluid_step(line: &str) -> Option<u64> {
    line.split(" DEM steps of ")
        .next()
        .and_then(|head| head.rsplit(' ').next())
        .and_then(|k| k.parse().ok())
}
