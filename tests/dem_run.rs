//! `dem-client run`: a granular scene alone writes its outputs; a bad DEM scene is refused by name.

mod common;
use common::*;
use std::process::Command;

const POUR: &str = r#"name = "small-pour"
[domain]
min = [0.0, 0.0, 0.0]
max = [0.03, 0.03, 0.06]
[fluid]
density = 1.2
dynamic_viscosity = 1.8e-5
[time]
dt = 2.0e-3
steps = 50
[output]
interval = 25
[particles]
density = 2500.0
[[dem.material]]
name = "glass"
restitution = 0.5
friction = 0.4
[[dem.insert]]
origin = [0.004, 0.004, 0.004]
count = [5, 5, 6]
spacing = 0.005
radius = [0.0017, 0.002]
jitter = 0.0004
"#;

#[test]
fn a_granular_scene_runs_alone_and_writes_csv_energy_and_vtk() {
    let dir = temp_dir("dem-run");
    let scene = write_scene(&dir, POUR);
    let out = dir.join("out");
    let run = Command::new(bin("dem-client"))
        .arg("run")
        .arg(&scene)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
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
