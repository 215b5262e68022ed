//! Fluid-only scenes in SI units through `lbm-server run`: the units path end to end, refusals
//! of unstable parameters, the health check, and the VTK output.

mod common;
use common::*;
use std::path::Path;

const POISEUILLE: &str = include_str!("../validation/scenes/poiseuille.toml");
const CAVITY: &str = include_str!("../validation/scenes/cavity-unstable.toml");

/// Rows (s, ux) of the last step in a line probe.
fn last_profile(path: &Path) -> Vec<(f64, f64)> {
    let text = std::fs::read_to_string(path).unwrap();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    let last = rows.last().unwrap()[0];
    rows.iter()
        .filter(|r| r[0] == last)
        .map(|r| (r[2], r[4]))
        .collect()
}

#[test]
fn poiseuille_in_si_units_matches_the_analytic_profile() {
    let (code, err, out) = run_scene("pois", POISEUILLE);
    assert_eq!(code, Some(0), "{err}");
    let profile = last_profile(&out.join("line0.csv"));
    assert_eq!(profile.len(), 16);
    // u(y) = a / (2 nu) y (H - y) with nu = 1e-6 m^2/s, a = 6.25e-6 m/s^2, H = 16 mm.
    let (a, nu, h) = (6.25e-6, 1.0e-6, 0.016);
    let u_max = a * h * h / (8.0 * nu);
    for (y, u) in profile {
        let exact = a / (2.0 * nu) * y * (h - y);
        assert!((u - exact).abs() < 2e-3 * u_max, "u({y}) = {u}, analytic {exact}");
    }
    let pvd = std::fs::read_to_string(out.join("fields.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), 3, "{pvd}");
    let vti = std::fs::read(out.join("fields/step000003000.vti")).unwrap();
    let cells = 2 * 16 * 2;
    assert!(vti.len() > 16 * cells, "density and velocity payload present");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["steps_completed"], 3000);
    assert_eq!(summary["lattice"]["tau"], 0.8);
    assert_eq!(summary["lattice"]["magic"], 0.1875, "TRT's magic as used");
    let tau_minus = summary["lattice"]["tau_minus"].as_f64().expect("TRT's tau-");
    assert!((tau_minus - (0.5 + 0.1875 / 0.3)).abs() < 1e-12, "{tau_minus}");
    assert_eq!(summary["lattice"]["ramp_time_s"], 0.0);
}

#[test]
fn tau_below_the_limit_is_refused() {
    let text = POISEUILLE
        .replace("operator = \"trt\"", "operator = \"bgk\"")
        .replace("tau = 0.8", "tau = 0.5004");
    let (code, err, out) = run_scene("lowtau", &text);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("lattice.tau = 0.50040: is below 0.5 + 0.0005: unstable; raise lattice.tau"),
        "{err}"
    );
    assert!(!out.exists());
}

/// `--duration` runs the steps that cover it (Poiseuille's dt is 0.1 s: 0.45 s is 5 steps), and
/// is refused beside `--steps`.
#[test]
fn a_duration_on_the_command_line_runs_the_steps_that_cover_it() {
    let dir = temp_dir("duration");
    let scene = write_scene(&dir, POISEUILLE);
    let out = dir.join("out");
    let result = server(&scene, &out, &["--duration", "0.45"]).output().unwrap();
    let err = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(0), "{err}");
    assert_eq!(summary(&out)["steps_completed"], 5, "{err}");
    let both = server(&scene, &out, &["--duration", "0.45", "--steps", "3"])
        .output()
        .unwrap();
    assert_eq!(both.status.code(), Some(2));
}

#[test]
fn too_high_a_lattice_mach_number_is_refused() {
    let (code, err, _) = run_scene(
        "mach",
        &POISEUILLE.replace("velocity_scale = 2.0e-4", "velocity_scale = 0.01"),
    );
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("lattice.velocity_scale = 0.01 m/s: gives lattice Mach 1.732, above 0.35 for trt"),
        "{err}"
    );
}

#[test]
fn a_face_too_fast_for_the_lattice_is_refused() {
    let text = CAVITY.replace("velocity = [0.05, 0.0, 0.0]", "velocity = [0.3, 0.0, 0.0]");
    let (code, err, _) = run_scene("fastlid", &text);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("lattice.faces.z_max.velocity = [0.3, 0, 0] m/s: is lattice Mach 1.732"),
        "{err}"
    );
}

#[test]
fn a_blow_up_is_caught_with_step_cell_and_quantity() {
    let (code, err, out) = run_scene("blowup", CAVITY);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("the fluid became unstable between steps"), "{err}");
    assert!(err.contains("cell ") && err.contains(" at ("), "{err}");
    assert_last_good_kept(&err, &out);
}

/// A blow-up's run names its last good snapshot, has written it, and its summary gives the reason.
fn assert_last_good_kept(err: &str, out: &Path) {
    assert!(err.contains("last good snapshot (step"), "{err}");
    assert!(out.join("last_good.vti").is_file());
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert!(
        summary.contains("\"exit_reason\": \"error: the fluid became unstable"),
        "{summary}"
    );
}

/// The unstable cavity with a sphere of 4 cells at its centre, checked every `every` steps.
fn cavity_with_a_sphere(every: u64) -> String {
    let sphere = "\n[particles]\ndensity = 1100.0\n[[particles.sphere]]\nposition = [0.008, 0.008, 0.008]\nradius = 0.002\n";
    CAVITY.replace("check_interval = 50", &format!("check_interval = {every}")) + sphere
}

/// The unstable cavity with a sphere in it: the coupled run says the fluid blew up (not the DEM,
/// whose states go NaN from the fluid's forces when that comes between two checks), keeps the
/// fields of the last check that passed, writes no NaN to particles.csv and tells the DEM to stop
/// (STOP on its last reply: the DEM ends on its own); caught at a check (every 10 steps) and
/// between checks (every 50).
#[test]
fn a_coupled_blow_up_is_the_fluids_with_its_last_good_fields() {
    for every in [10, 50] {
        let (code, err, out) = run_scene(&format!("coupledblowup{every}"), &cavity_with_a_sphere(every));
        assert_eq!(code, Some(1), "{err}");
        assert!(err.contains("immersed moving boundary"), "{err}");
        assert!(err.contains("error: the fluid became unstable by step"), "{err}");
        assert_last_good_kept(&err, &out);
        assert!(
            err.contains("dem-client: finished after") && !err.contains("dem-client: error"),
            "{err}"
        );
        let rows = particle_rows(&out);
        assert!(
            rows.len() > 1 && rows.iter().flatten().all(|v| v.is_finite()),
            "{rows:?}"
        );
    }
}

/// The same blow-up with the DEM joined from outside (`--dem external`): the fluid's STOP
/// reaches it, so the DEM ends cleanly (exit 0) while the server reports the fluid's failure (a
/// server that failed without replying left the DEM to find it gone and fail too).
#[test]
fn an_external_dem_is_told_to_stop_when_the_fluid_blows_up() {
    let dir = temp_dir("externalblowup");
    let scene = write_scene(&dir, &cavity_with_a_sphere(10));
    let out = dir.join("out");
    let (mut server, run) = start_external(&scene, &out);
    let client = std::process::Command::new(bin("dem-client"))
        .args(["connect", "--service", &run, "--scene"])
        .arg(&scene)
        .output()
        .unwrap();
    let client_err = String::from_utf8_lossy(&client.stderr);
    assert!(client.status.success(), "{client_err}");
    assert!(
        client_err.contains("finished after")
            && client_err.contains("the fluid server stopped the run after"),
        "{client_err}"
    );
    let (code, _) = server.wait_exit(std::time::Duration::from_secs(60));
    let err = Proc::drain(&server.stderr);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("error: the fluid became unstable by step"), "{err}");
}

#[test]
fn lattice_scene_mistakes_name_the_field() {
    let cases = [
        (
            "dx = 0.001",
            "dx = 0.0015",
            "lattice.dx = 0.0015 m: the domain's extent along axis 0",
        ),
        (
            "operator = \"trt\"",
            "operator = \"lbgk\"",
            "lattice.operator = \"lbgk\"",
        ),
        (
            "[time]\nsteps = 3000",
            "[time]\nsteps = 3000\ndt = 0.1",
            "time.dt = 0.1 s: the [lattice] section derives",
        ),
        (
            "x_max = \"periodic\"",
            "x_max = \"wall\"",
            "periodic faces come in pairs",
        ),
        (
            "y_max = \"wall\"",
            "y_max = \"slip\"",
            "lattice.faces.y_max = \"slip\"",
        ),
        ("axis = \"y\"", "axis = \"w\"", "output.line[0].axis = \"w\""),
    ];
    for (from, to, expected) in cases {
        assert!(POISEUILLE.contains(from), "{from}");
        let (code, err, _) = run_scene("latticebad", &POISEUILLE.replacen(from, to, 1));
        assert_eq!(code, Some(2), "{to}: {err}");
        assert!(err.contains(expected), "{to}: expected {expected:?} in {err}");
    }
}
