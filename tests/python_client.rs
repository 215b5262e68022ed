//! An external DEM written in Python (PyPI `iceoryx2`), knowing only PROTOCOL.md, completes a run.

mod common;
use common::*;
use std::process::Command;
use std::time::Duration;

/// A run with the Python DEM; with `lubrication` the scene asks for it, and as the Python DEM does
/// not declare LUBRICATION the fluid applies its own correction.
fn python_run(tag: &str, particles: u64, steps: u64, lubrication: bool) {
    python_run_with(tag, particles, steps, lubrication, "");
}

/// Starts `lbm-server` on the scene `text` for an external DEM and runs the Python example DEM
/// against it with `args` after `--service RUN`; both must succeed. Returns the client's stdout
/// and stderr, the run's output folder and the run name.
fn with_python_dem(tag: &str, text: &str, args: &[&str]) -> (String, String, std::path::PathBuf, String) {
    let dir = temp_dir(tag);
    let scene = write_scene(&dir, text);
    let out = dir.join("out");
    let (mut server, run) = start_external(&scene, &out);
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/clients/python/example_dem.py");
    let client = Command::new("python3")
        .arg(script)
        .args(["--service", &run])
        .args(args)
        .output()
        .expect("python3 runs");
    let client_out = String::from_utf8_lossy(&client.stdout).into_owned();
    let client_err = String::from_utf8_lossy(&client.stderr).into_owned();
    assert!(
        client.status.success(),
        "python client failed ({args:?}):\n{client_out}\n{client_err}"
    );
    let (code, _) = server.wait_exit(Duration::from_secs(60));
    assert_eq!(code, Some(0), "{args:?}: {}", Proc::drain(&server.stderr));
    (client_out, client_err, out, run)
}

/// `python_run` with `faces` as the scene's `[lattice.faces]`; the client must say it learnt the
/// periodic ones from the Welcome.
fn python_run_with(tag: &str, particles: u64, steps: u64, lubrication: bool, faces: &str) {
    // The external DEM brings its own particles: the scene only sets the capacity.
    let text = scene_text(tag, [2, 2, 2], steps, 50, 10.0)
        .replace("timeout = 10", "timeout = 10\ncapacity = 4096")
        .replace("lubrication = false", &format!("lubrication = {lubrication}"))
        .replace("[output]", &format!("{faces}[output]"));
    let (client_out, client_err, out, run) =
        with_python_dem(tag, &text, &["--particles", &particles.to_string()]);
    let expected = format!(
        "python-dem: completed {steps} steps, {particles} particles, last step {}",
        steps - 1
    );
    assert!(client_out.contains(&expected), "{client_out}\n{client_err}");
    let along = if faces.contains("x_min = \"periodic\"") {
        "periodic along ['x', 'y']"
    } else {
        "periodic along []"
    };
    assert!(client_err.contains(along), "{client_err}");
    let s = summary(&out);
    assert_eq!(s["steps_completed"], steps);
    assert_eq!(s["particles_initial"], particles);
    assert!(
        s["peer"]["software"].as_str().unwrap().contains("example_dem.py"),
        "{s}"
    );
    let fluid = s["fluid_physics"].to_string();
    assert_eq!(fluid.contains("lubrication"), lubrication, "{fluid}");
    // Forces arrived for every particle of every output step.
    let rows = csv_steps(&out);
    assert!(rows.values().all(|ids| ids.len() as u64 == particles));
    assert!(leftover_files(&run).is_empty(), "{:?}", leftover_files(&run));
}

#[test]
fn python_client_completes_a_run() {
    python_run("python", 64, 150, true);
}

#[test]
fn python_client_with_2000_particles() {
    python_run("python2k", 2000, 60, false);
}

/// The Welcome names the periodic axes (PROTOCOL.md 4.4, 6.2): the Python DEM wraps its spheres
/// along x and y and reflects them at the floor and lid.
#[test]
fn python_client_learns_the_periodic_axes_from_the_welcome() {
    let faces = "[lattice.faces]\nx_min = \"periodic\"\nx_max = \"periodic\"\ny_min = \"periodic\"\n\
                 y_max = \"periodic\"\nz_min = \"wall\"\nz_max = \"wall\"\n";
    python_run_with("python-periodic", 64, 60, false, faces);
}

/// A DEM may speak any units (PROTOCOL.md 4.3): the fluid converts what it receives to SI and what
/// it sends back to the DEM's units. The Python DEM in mm, half-seconds and grams runs the same
/// physics as in SI: the same positions, velocities, spins, forces and torques in the fluid's
/// particles.csv (within round-off), and the forces are not zero. Fails when either conversion is
/// skipped or done twice.
#[test]
fn a_dem_in_other_units_runs_the_same_physics_as_in_si() {
    let steps = 40;
    let run_in = |tag: &str, units: &str| {
        let text = scene_text(tag, [2, 2, 2], steps, 10, 10.0)
            .replace("timeout = 10", "timeout = 10\ncapacity = 64");
        let (_, _, out, _) = with_python_dem(tag, &text, &["--particles", "27", "--units", units]);
        particle_rows(&out)
    };
    let si = run_in("units-si", "1,1,1");
    let other = run_in("units-other", "1e-3,0.5,2e-3");
    assert_eq!(si.len(), other.len());
    assert_eq!(si.len(), 27 * 5, "rows at steps 0, 10, 20, 30 and 39");
    let largest = |col: usize| si.iter().map(|r| r[col].abs()).fold(0.0, f64::max);
    assert!(largest(14) > 0.0, "the fluid pushes the spheres");
    for (a, b) in si.iter().zip(&other) {
        for col in 0..a.len() {
            let scale = largest(col).max(f64::MIN_POSITIVE);
            assert!(
                (a[col] - b[col]).abs() <= 1e-9 * scale,
                "step {} particle {} column {col}: {} in SI, {} in other units",
                a[0],
                a[2],
                a[col],
                b[col]
            );
        }
    }
}

/// `lbm-server run SCENE --dem-command CMD` starts any DEM itself: the Python example through
/// `sh -c`, the run name in $LBMDEM_RUN, the scene in $LBMDEM_SCENE and clients/python on
/// PYTHONPATH (the command imports lbmdem from another folder), runs to the last step and leaves
/// no shared-memory file.
#[test]
fn dem_command_starts_the_python_dem_and_runs_to_the_end() {
    let steps = 40;
    let text = scene_text("dem-command", [2, 2, 2], steps, 10, 10.0)
        .replace("timeout = 10", "timeout = 10\ncapacity = 64");
    let dir = temp_dir("dem-command");
    let scene = write_scene(&dir, &text);
    let out = dir.join("out");
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/clients/python/example_dem.py");
    let line = format!(
        "cd / && test -f \"$LBMDEM_SCENE\" && python3 -c 'import lbmdem, lbmdem_scene' && \
         exec python3 {script} --particles 27"
    );
    let mut fluid = start(server(&scene, &out, &["--dem-command", &line]));
    let (code, _) = fluid.wait_exit(Duration::from_secs(240));
    let said = Proc::drain(&fluid.stdout) + &Proc::drain(&fluid.stderr);
    assert_eq!(code, Some(0), "{said}");
    assert!(
        said.contains(&format!("python-dem: completed {steps} steps, 27 particles")),
        "{said}"
    );
    let s = summary(&out);
    assert_eq!(s["steps_completed"], steps);
    assert!(
        s["peer"]["software"].as_str().unwrap().contains("example_dem.py"),
        "{s}"
    );
    // The run's name is lbmdem_<pid of lbm-server>_<nonce>.
    let run = format!("lbmdem_{}_", fluid.child.id());
    assert!(leftover_files(&run).is_empty(), "{:?}", leftover_files(&run));
}

/// A `--dem-command` that dies before it joins ends the run with exit 1, naming it, as a
/// dem-client that dies does: without waiting for the connect timeout (here 600 s).
#[test]
fn dem_command_that_dies_ends_the_run() {
    let dir = temp_dir("dem-command-dies");
    let scene = write_scene(&dir, &scene_text("dem-command-dies", [1, 1, 1], 10, 10, 10.0));
    let started = std::time::Instant::now();
    let args = ["--dem-command", "exit 3", "--connect-timeout", "600"];
    let run = server(&scene, &dir.join("out"), &args)
        .output()
        .expect("lbm-server runs");
    let said = String::from_utf8_lossy(&run.stderr).into_owned();
    assert_eq!(run.status.code(), Some(1), "{said}");
    assert!(said.contains("died"), "{said}");
    assert!(started.elapsed() < Duration::from_secs(300), "{said}");
}
