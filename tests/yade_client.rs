//! YADE as the DEM of a coupled run (clients/yade): it settles the Ten Cate E1 sphere as the
//! built-in DEM does, and a YADE script that does not fit the scene ends the run with exit 2.
//! Where yade or iceoryx2 for Debian's python is missing, the YADE tests say they were skipped
//! and why, and pass (CI installs both: .ci/run). The scene reader the Python DEMs use
//! (clients/python/lbmdem_scene.py) needs only Python 3.11 and is checked everywhere.

mod common;
use common::*;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::Duration;

const TEN_CATE: &str = include_str!("../validation/scenes/ten-cate-e1.toml");
const CLIENT_DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/clients/yade");
/// lbmdem (the package lbmdem/) and lbmdem_scene.py, which the YADE module imports from PYTHONPATH.
const PYTHON_CLIENTS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/clients/python");

/// The Debian python YADE runs on.
const SYSTEM_PYTHON: &str = "/usr/bin/python3";

/// YADE with iceoryx2 for its python: `yade` on PATH, and iceoryx2 in $LBMDEM_YADE_PYTHONPATH or
/// target/yade-py (where .ci/run installs it). One test of this file holds it at a time: each
/// starts lbm-server on the CPU's Vulkan driver.
struct Yade {
    pythonpath: String,
    _one_run_at_a_time: std::sync::MutexGuard<'static, ()>,
}

impl Yade {
    /// None (and a line saying why the test is skipped) where YADE cannot run here.
    fn find(test: &str) -> Option<Yade> {
        static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());
        let on_path = std::env::var_os("PATH")
            .map(|p| std::env::split_paths(&p).any(|d| d.join("yade").is_file()))
            .unwrap_or(false);
        if !on_path {
            skipped(&format!(
                "{test}: skipped: yade is not installed (apt-get install yade python3-yade, or \
                 sh validation/dem/install.sh)"
            ));
            return None;
        }
        let iox = std::env::var("LBMDEM_YADE_PYTHONPATH")
            .unwrap_or_else(|_| concat!(env!("CARGO_MANIFEST_DIR"), "/target/yade-py").to_string());
        let found = Command::new(SYSTEM_PYTHON)
            .args(["-c", "import iceoryx2"])
            .env("PYTHONPATH", &iox)
            .output()
            .is_ok_and(|o| o.status.success());
        if !found {
            skipped(&format!(
                "{test}: skipped: iceoryx2 for Debian's python is not in {iox} \
                 ({SYSTEM_PYTHON} -m pip install --target {iox} iceoryx2==0.10.0)"
            ));
            return None;
        }
        Some(Yade {
            pythonpath: format!("{iox}:{PYTHON_CLIENTS}:{CLIENT_DIR}"),
            _one_run_at_a_time: SERIAL.lock().unwrap_or_else(|e| e.into_inner()),
        })
    }

    /// `yade -n -x SCRIPT ARGS`, to completion.
    fn run(&self, script: &Path, args: &[&str]) -> Output {
        Command::new("yade")
            .arg("-n")
            .arg("-x")
            .arg(script)
            .args(args)
            .env("PYTHONPATH", &self.pythonpath)
            .output()
            .expect("yade runs")
    }
}

/// Says why a test is skipped, on stderr itself: the test harness captures `eprintln!`.
fn skipped(why: &str) {
    use std::io::Write;
    let _ = writeln!(std::io::stderr(), "{why}");
}

/// Ten Cate E1 cut to `steps` steps, written into a fresh folder.
fn ten_cate_scene(tag: &str, steps: u64) -> (PathBuf, PathBuf) {
    let dir = temp_dir(tag);
    let text = TEN_CATE.replace("steps = 400", &format!("steps = {steps}"));
    let scene = write_scene(&dir, &text);
    (dir, scene)
}

/// Starts `lbm-server run SCENE --dem external`, runs the YADE script against it with `args`
/// after the run name and the scene, waits for both. Returns YADE's output, the server's exit
/// code and stderr, and the run name.
fn coupled_with_yade(
    yade: &Yade,
    scene: &Path,
    out: &Path,
    script: &Path,
    args: &[&str],
) -> (Output, Option<i32>, String, String) {
    let (server, run) = start_external(scene, out);
    let mut fluid = Fluid(server);
    let scene = scene.to_str().unwrap();
    let mut all = vec!["--service", &run, "--scene", scene];
    all.extend_from_slice(args);
    let client = yade.run(script, &all);
    let (code, _) = fluid.0.wait_exit(Duration::from_secs(60));
    (client, code, Proc::drain(&fluid.0.stderr), run)
}

/// The fluid server of a test, killed when the test leaves early (a failed assertion): with
/// `--dem external` it would otherwise wait for a DEM without end.
struct Fluid(Proc);

impl Drop for Fluid {
    fn drop(&mut self) {
        if matches!(self.0.child.try_wait(), Ok(None)) {
            let _ = self.0.child.kill();
            let _ = self.0.child.wait();
        }
    }
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// The largest downward speed in a run's particles.csv [m/s].
fn peak_settling_speed(out: &Path) -> f64 {
    particle_rows(out).iter().map(|r| -r[8]).fold(f64::MIN, f64::max)
}

/// Ten Cate E1 at 6 cells per diameter, 150 steps (0.57 s, near the terminal speed), the sphere
/// released spinning at 5 rad/s about y (the torque path: the fluid's torque slows it), once with
/// the built-in DEM and once with YADE building the sphere from the scene
/// (clients/yade/ten_cate_e1.py, ~70 YADE steps per fluid step): the same peak settling speed
/// within 0.5%, the same spin at every output step within 0.5% (1e-5 of the initial spin once it
/// has decayed), every step exchanged, no shared-memory file left.
#[test]
fn yade_settles_the_ten_cate_sphere_as_the_builtin_dem_does() {
    let Some(yade) = Yade::find("yade_settles_the_ten_cate_sphere_as_the_builtin_dem_does") else {
        return;
    };
    let (dir, scene) = spinning_ten_cate_scene("yade-tencate", 150);
    let builtin = dir.join("builtin");
    let run = server(&scene, &builtin, &[]).output().expect("lbm-server runs");
    assert!(run.status.success(), "built-in DEM run: {}", text(&run.stderr));

    let out = dir.join("yade");
    let script = Path::new(CLIENT_DIR).join("ten_cate_e1.py");
    let (client, code, server_err, run) = coupled_with_yade(&yade, &scene, &out, &script, &[]);
    let (client_out, client_err) = (text(&client.stdout), text(&client.stderr));
    assert!(
        client.status.success(),
        "yade failed:\n{client_out}\n{client_err}"
    );
    assert!(
        client_out.contains("yade-dem: completed 150 steps, 1 particles, last step 149"),
        "{client_out}\n{client_err}"
    );
    assert_eq!(code, Some(0), "{server_err}");
    let s = summary(&out);
    assert_eq!(s["steps_completed"], 150);
    let software = s["peer"]["software"].as_str().unwrap();
    assert!(
        software.contains("YADE") && software.contains("lbmdem_yade"),
        "{s}"
    );

    let (with_builtin, with_yade) = (peak_settling_speed(&builtin), peak_settling_speed(&out));
    eprintln!("peak settling speed: built-in DEM {with_builtin} m/s, YADE {with_yade} m/s");
    assert!(with_builtin > 0.03, "the sphere settles: {with_builtin} m/s");
    assert!(
        (with_yade - with_builtin).abs() <= 0.005 * with_builtin,
        "peak settling speed with YADE {with_yade} m/s, with the built-in DEM {with_builtin} m/s"
    );
    same_spin(&builtin, &out);
    assert!(leftover_files(&run).is_empty(), "{:?}", leftover_files(&run));
}

/// [`ten_cate_scene`] with the sphere released spinning at 5 rad/s about y.
fn spinning_ten_cate_scene(tag: &str, steps: u64) -> (PathBuf, PathBuf) {
    let (dir, scene) = ten_cate_scene(tag, steps);
    let spinning = std::fs::read_to_string(&scene).unwrap().replace(
        "radius = 0.0075                      # m",
        "radius = 0.0075                      # m\nangular_velocity = [0.0, 5.0, 0.0]",
    );
    assert!(spinning.contains("angular_velocity"));
    std::fs::write(&scene, spinning).unwrap();
    (dir, scene)
}

/// The sphere's spin about y in the runs into `builtin` and `yade` at every output step: the same
/// within 0.5%, and 1e-5 of the initial spin where it has decayed to the flow's own (1e-3 rad/s
/// at 0.5 s); the fluid slows it.
fn same_spin(builtin: &Path, yade: &Path) {
    // particles.csv: step, time, id, x, y, z, vx, vy, vz, wx, wy, wz, ... Within 0.5%, and 1e-5
    // of the initial spin where it has decayed to the flow's own (1e-3 rad/s at 0.5 s).
    let (spin_builtin, spin_yade) = (particle_rows(builtin), particle_rows(yade));
    assert_eq!(spin_builtin.len(), spin_yade.len());
    assert!(
        spin_builtin[8][10] < 1.0,
        "the fluid slows the spin: {:?}",
        spin_builtin[8]
    );
    for (b, y) in spin_builtin.iter().zip(&spin_yade) {
        assert!(
            (y[10] - b[10]).abs() <= 0.005 * b[10].abs() + 1e-5 * 5.0,
            "step {}: spin {} rad/s with YADE, {} rad/s with the built-in DEM",
            b[0],
            y[10],
            b[10]
        );
    }
}

/// A YADE script for the one-sphere Ten Cate scene: `count` builds two spheres, `ids` maps the
/// sphere to scene particle 3, `dt` sets an O.dt that does not divide the fluid step.
const MISFIT: &str = r#"
import sys
import lbmdem_yade
case = sys.argv[-1]
O.materials.append(FrictMat(young=5e6, density=1120))
O.bodies.append(sphere((0.05, 0.05, 0.1275), 0.0075))
if case == "count":
    O.bodies.append(sphere((0.05, 0.05, 0.05), 0.0075))
O.engines = [ForceResetter(), NewtonIntegrator(damping=0.0, gravity=(0, 0, -9.81))]
O.dt = 1e-4
lbmdem_yade.couple(sys.argv[2], scene=sys.argv[4], ids={3: 0} if case == "ids" else None,
                   max_dt=None if case == "dt" else 1e-3, timeout_s=2.0 if case == "ids" else 10.0)
"#;

/// Bad input (issue 39, item 7): a YADE sphere count that differs from the scene's particle
/// count (found before joining), an O.dt that does not divide the fluid step (found from the
/// Welcome): a message naming it, exit 2, the run ended with STOP at step 0 (the server exits 130
/// after one step: stopped before its last step, it did not complete), no process waiting and no shared-memory file left. An id the scene does not
/// have, with no server to tell: the message and exit 2 all the same.
#[test]
fn a_yade_script_that_does_not_fit_the_scene_ends_the_run_with_exit_2() {
    let Some(yade) = Yade::find("a_yade_script_that_does_not_fit_the_scene_ends_the_run_with_exit_2") else {
        return;
    };
    let (dir, scene) = ten_cate_scene("yade-misfit", 20);
    let script = dir.join("misfit.py");
    std::fs::write(&script, MISFIT).unwrap();
    let cases = [
        ("count", "YADE couples 2 spheres, the scene"),
        ("dt", "is not a whole number of YADE steps O.dt = 0.0001 s"),
    ];
    for (case, message) in cases {
        let out = dir.join(case);
        let (client, code, server_err, run) = coupled_with_yade(&yade, &scene, &out, &script, &[case]);
        let client_err = text(&client.stderr);
        assert_eq!(client.status.code(), Some(2), "{case}: {client_err}");
        assert!(
            client_err.contains("yade-dem: error: ") && client_err.contains(message),
            "{case}: expected {message:?} in\n{client_err}"
        );
        assert!(client_err.contains("with STOP at step 0"), "{case}: {client_err}");
        assert_eq!(code, Some(130), "{case}: {server_err}");
        assert_eq!(summary(&out)["steps_completed"], 1, "{case}");
        assert_eq!(
            summary(&out)["exit_reason"],
            "stopped by the DEM client",
            "{case}"
        );
        assert!(
            leftover_files(&run).is_empty(),
            "{case}: {:?}",
            leftover_files(&run)
        );
    }
    let scene = scene.to_str().unwrap();
    let no_run = format!("lbmdem_{}_0", std::process::id());
    let client = yade.run(&script, &["--service", &no_run, "--scene", scene, "ids"]);
    let client_err = text(&client.stderr);
    assert_eq!(client.status.code(), Some(2), "{client_err}");
    let message = "YADE body 0 is mapped to scene particle 3, which the scene";
    assert!(
        client_err.contains(message),
        "expected {message:?} in\n{client_err}"
    );
    assert!(client_err.contains("could not end the run"), "{client_err}");
    assert!(
        leftover_files(&no_run).is_empty(),
        "{:?}",
        leftover_files(&no_run)
    );
}

/// A scene with every way of making particles: spheres (one spinning), a block, two jittered
/// lattice insertions (one polydisperse, another seed) and a CSV file.
const MIXED_SCENE: &str = r#"name = "mixed"
[domain]
min = [0.0, 0.0, 0.0]
max = [0.04, 0.04, 0.04]
[fluid]
density = 1000.0
dynamic_viscosity = 0.001
[time]
dt = 0.001
steps = 1
[particles]
density = 2500.0
[[particles.sphere]]
position = [0.02, 0.02, 0.035]
radius = 0.001
velocity = [0.0, 0.0, -0.1]
angular_velocity = [0.0, 3.0, 0.0]
[[particles.block]]
origin = [0.005, 0.005, 0.025]
count = [2, 3, 1]
spacing = 0.003
radius = 0.001
[[dem.insert]]
origin = [0.005, 0.005, 0.005]
count = [3, 2, 2]
spacing = 0.004
radius = [0.001, 0.0015]
jitter = 0.0005
seed = 7
[[dem.insert]]
origin = [0.025, 0.005, 0.005]
count = [2, 2, 2]
spacing = 0.004
radius = 0.0012
jitter = 0.0007
[[dem.csv]]
file = "extra.csv"
"#;

/// Prints every particle of the scene as lbmdem_scene.py reads it: id, position, velocity,
/// angular velocity, radius (repr: the shortest text that reads back to the same double).
const READ_SCENE: &str = r#"
import sys
sys.path.insert(0, sys.argv[1])
import lbmdem_scene
for p in lbmdem_scene.Scene.load(sys.argv[2]).particles:
    print(" ".join(repr(float(v)) for v in (p.id, *p.position, *p.velocity, *p.angular_velocity, p.radius)))
"#;

/// The particles a DEM builds from the scene file (clients/python/lbmdem_scene.py) are the scene
/// crate's to the bit: ids, positions (jittered insertion included), velocities, spins and radii
/// of dem-client's step 0 (particles.csv and the step-0 VTK polydata).
#[test]
fn the_python_scene_reader_makes_the_scenes_particles() {
    let python = if Path::new(SYSTEM_PYTHON).is_file() {
        SYSTEM_PYTHON
    } else {
        "python3"
    };
    let has_tomllib = Command::new(python)
        .args(["-c", "import tomllib"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !has_tomllib {
        skipped(&format!(
            "the_python_scene_reader_makes_the_scenes_particles: skipped: {python} has no tomllib (Python 3.11+)"
        ));
        return;
    }
    let dir = temp_dir("scene-reader");
    std::fs::write(
        dir.join("extra.csv"),
        "x,y,z,r,vx,wz\n0.03,0.03,0.03,0.001,0.1,2.0\n0.033,0.03,0.03,0.0012,0,0\n",
    )
    .unwrap();
    let scene = write_scene(&dir, MIXED_SCENE);
    let out = dir.join("out");
    let run = Command::new(bin("dem-client"))
        .arg("run")
        .arg(&scene)
        .arg("--out")
        .arg(&out)
        .output()
        .expect("dem-client runs");
    assert!(run.status.success(), "{}", text(&run.stderr));
    let read = Command::new(python)
        .args(["-c", READ_SCENE, PYTHON_CLIENTS])
        .arg(&scene)
        .output()
        .expect("python runs");
    assert!(read.status.success(), "{}", text(&read.stderr));
    let python_rows: Vec<Vec<f64>> = text(&read.stdout)
        .lines()
        .map(|l| l.split(' ').map(|v| v.parse().unwrap()).collect())
        .collect();

    let step0: Vec<Vec<f64>> = particle_rows(&out).into_iter().filter(|r| r[0] == 0.0).collect();
    let radii = vtp_radii(&out.join("particles_000000.vtp"));
    assert_eq!(step0.len(), 29);
    assert_eq!(python_rows.len(), step0.len());
    for ((py, rust), r) in python_rows.iter().zip(&step0).zip(&radii) {
        // particles.csv: step, time, id, x, y, z, vx, vy, vz, wx, wy, wz, ... Within 0.5%, and 1e-5
        // of the initial spin where it has decayed to the flow's own (1e-3 rad/s at 0.5 s).
        let expected: Vec<f64> = rust[2..12].iter().copied().chain([*r]).collect();
        assert_eq!(py, &expected, "particle {}", rust[2]);
    }
}

/// The `radius` array of a VTK polydata file written by the DEM.
fn vtp_radii(path: &Path) -> Vec<f64> {
    let xml = std::fs::read_to_string(path).expect("VTK polydata of step 0");
    let after = xml.split("Name=\"radius\"").nth(1).expect("a radius array");
    let values = after.split('>').nth(1).unwrap().split('<').next().unwrap();
    values.split_whitespace().map(|v| v.parse().unwrap()).collect()
}

/// `lbm-server run SCENE --dem yade` in one command: the YADE script written from the scene
/// (OUT/dem.yade.py: the sphere from the scene reader, the domain's faces as walls,
/// Hertz-Mindlin) settles the Ten Cate sphere as the built-in DEM does, peak speeds within 0.5%.
#[test]
fn dem_yade_in_one_command_settles_the_ten_cate_sphere_as_the_builtin_dem_does() {
    let test = "dem_yade_in_one_command_settles_the_ten_cate_sphere_as_the_builtin_dem_does";
    let Some(yade) = Yade::find(test) else {
        return;
    };
    let (dir, scene) = ten_cate_scene("dem-yade", 60);
    let builtin = dir.join("builtin");
    let run = server(&scene, &builtin, &[]).output().expect("lbm-server runs");
    assert!(run.status.success(), "built-in DEM run: {}", text(&run.stderr));
    let out = dir.join("yade");
    let mut command = server(&scene, &out, &["--dem", "yade"]);
    command.env("PYTHONPATH", &yade.pythonpath);
    let mut fluid = Fluid(start(command));
    let (code, _) = fluid.0.wait_exit(Duration::from_secs(300));
    let said = Proc::drain(&fluid.0.stdout) + &Proc::drain(&fluid.0.stderr);
    assert_eq!(code, Some(0), "{said}");
    let script = std::fs::read_to_string(out.join("dem.yade.py")).expect("the script is in OUT");
    assert!(script.contains("Law2_ScGeom_MindlinPhys_Mindlin"), "{script}");
    let s = summary(&out);
    assert_eq!(s["steps_completed"], 60);
    assert!(s["peer"]["software"].as_str().unwrap().contains("YADE"), "{s}");
    let (with_builtin, with_yade) = (peak_settling_speed(&builtin), peak_settling_speed(&out));
    eprintln!("peak settling speed: built-in DEM {with_builtin} m/s, --dem yade {with_yade} m/s");
    assert!(
        (with_yade - with_builtin).abs() <= 0.005 * with_builtin,
        "peak settling speed with --dem yade {with_yade} m/s, with the built-in DEM {with_builtin} m/s"
    );
    let run = format!("lbmdem_{}_", fluid.0.child.id());
    assert!(leftover_files(&run).is_empty(), "{:?}", leftover_files(&run));
}
