//! Every mistake in a scene file is refused before anything runs, naming the file, the field and
//! the bad value.

mod common;
use common::*;

/// (what is wrong, text to replace, replacement, words the error must contain)
const MISTAKES: &[(&str, &str, &str, &[&str])] = &[
    ("unknown key", "density = 1000.0", "densty = 1000.0", &["unknown field `densty`", "line"]),
    ("negative radius", "radius = 0.0012", "radius = -0.0012", &["particles.block[0].radius = -0.0012 m"]),
    (
        "particles without a lattice",
        "steps = 100\n[lattice]\ndx = 0.001\ntau = 0.8\nvelocity_scale = 0.01\n",
        "steps = 100\ndt = 1.0e-4\n",
        &["lattice = missing", "add a [lattice] section", "dem-client run"],
    ),
    (
        "no lattice and no time step",
        "[lattice]\ndx = 0.001\ntau = 0.8\nvelocity_scale = 0.01\n",
        "",
        &["time.dt = missing", "add a [lattice] section"],
    ),
    ("relaxation time too low", "tau = 0.8", "tau = 0.5001", &["lattice.tau = 0.50010", "unstable", "raise lattice.tau"]),
    ("negative ramp time", "tau = 0.8", "tau = 0.8\nramp_time = -0.1", &["lattice.ramp_time = -0.1 s", ">= 0"]),
    ("zero steps", "steps = 100", "steps = 0", &["time.steps = 0"]),
    (
        "steps and duration",
        "steps = 100",
        "steps = 100\nduration = 0.1",
        &["time.duration = 0.1 s", "time.steps is given too"],
    ),
    ("negative viscosity", "dynamic_viscosity = 1.0", "dynamic_viscosity = -1.0", &["fluid.dynamic_viscosity = -1 Pa s"]),
    (
        "inverted domain",
        "max = [0.016, 0.016, 0.016]",
        "max = [0.016, -0.016, 0.016]",
        &["domain.max[1] = -0.016 m", "greater than domain.min[1]"],
    ),
    (
        "unknown periodic axis",
        "max = [0.016, 0.016, 0.016]",
        "max = [0.016, 0.016, 0.016]\nperiodic = [\"w\"]",
        &["domain.periodic[0] = \"w\"", "\"x\", \"y\" or \"z\""],
    ),
    (
        "periodic axis the lattice's faces do not have",
        "max = [0.016, 0.016, 0.016]",
        "max = [0.016, 0.016, 0.016]\nperiodic = [\"x\"]",
        &["domain.periodic = [\"x\"]", "lattice.faces", "are along []"],
    ),
    ("overlapping block", "spacing = 0.004", "spacing = 0.002", &["particles.block[0].spacing = 0.002 m", "overlap"]),
    ("wrong type", "steps = 100", "steps = \"many\"", &["steps", "invalid type"]),
    ("missing section", "[fluid]\ndensity = 1000.0\ndynamic_viscosity = 1.0\n", "", &["missing field `fluid`"]),
    ("zero output interval", "interval = 10", "interval = 0", &["output.interval = 0"]),
    ("negative timeout", "timeout = 10", "timeout = -1", &["coupling.timeout = -1 s"]),
    ("bad name", "name = \"bad\"", "name = \"my scene/1\"", &["name = \"my scene/1\""]),
    ("name of the parent folder", "name = \"bad\"", "name = \"..\"", &["name = \"..\"", "names output folders"]),
    (
        "non-finite body acceleration",
        "tau = 0.8",
        "tau = 0.8\nbody_acceleration = [nan, 0.0, 0.0]",
        &["lattice.body_acceleration = [NaN, 0, 0] m/s^2", "finite"],
    ),
    (
        "non-finite moving wall",
        "tau = 0.8",
        "tau = 0.8\nfaces.z_max = { type = \"moving_wall\", velocity = [nan, 0.0, 0.0] }",
        &["lattice.faces.z_max.velocity = [NaN, 0, 0] m/s", "finite"],
    ),
    (
        "non-finite MRT rate",
        "tau = 0.8",
        "tau = 0.8\noperator = \"mrt\"\nmrt = { e = 1.19, epsilon = 1.4, q = nan, pi = 1.4, m = 1.98 }",
        &["lattice.mrt.q = NaN", "(0, 2)"],
    ),
    (
        "solid box with a NaN corner",
        "tau = 0.8",
        "tau = 0.8\nsolid_box = [{ min = [nan, 0.0, 0.0], max = [0.004, 0.004, 0.004] }]",
        &["lattice.solid_box[0].min = [NaN, 0, 0] m", "finite"],
    ),
    ("non-finite gravity", "[domain]", "gravity = [0.0, 0.0, nan]\n[domain]", &["gravity = [0, 0, NaN] m/s^2"]),
    ("zero particle density", "density = 2500.0", "density = 0.0", &["particles.density = 0 kg/m^3"]),
    (
        "sphere outside the domain",
        "[[particles.block]]",
        "[[particles.sphere]]\nposition = [0.02, 0.008, 0.008]\nradius = 0.001\n[[particles.block]]",
        &["particles.sphere[0].position = [0.02, 0.008, 0.008] m", "leaves the domain"],
    ),
    (
        "overlapping spheres",
        "[[particles.block]]",
        "[[particles.sphere]]\nposition = [0.013, 0.013, 0.013]\nradius = 0.001\n[[particles.sphere]]\nposition = [0.0135, 0.013, 0.013]\nradius = 0.001\n[[particles.block]]",
        &["particles (ids 0 and 1)", "overlap"],
    ),
    ("capacity below count", "timeout = 10", "timeout = 10\ncapacity = 3", &["coupling.capacity = 3", "below the 8 particles"]),
    (
        "unknown covered-cell mode",
        "timeout = 10",
        "timeout = 10\ncovered_cells = \"gpu\"",
        &["coupling.covered_cells = \"gpu\"", "\"redo\" or \"skip\""],
    ),
    (
        "unknown solid collision",
        "timeout = 10",
        "timeout = 10\nsolid_collision = \"bounce-back\"",
        &["coupling.solid_collision = \"bounce-back\"", "\"noble-torczynski\" or \"superposition\""],
    ),
    (
        "calibrated radius correction with the superposition term",
        "velocity_scale = 0.01\n[output]\ninterval = 10\n[coupling]\ntimeout = 10",
        "velocity_scale = 0.01\n[output]\ninterval = 10\n[coupling]\ntimeout = 10\nsolid_collision = \"superposition\"\nradius_correction = \"calibrated\"",
        &["coupling.radius_correction = \"calibrated\"", "solid_collision = \"noble-torczynski\""],
    ),
    (
        "calibrated radius correction with another TRT magic",
        "velocity_scale = 0.01\n[output]\ninterval = 10\n[coupling]\ntimeout = 10",
        "velocity_scale = 0.01\nmagic = 0.01\n[output]\ninterval = 10\n[coupling]\ntimeout = 10\nradius_correction = \"calibrated\"",
        &["lattice.magic = 0.01", "magic 3/16"],
    ),
    (
        "calibrated radius correction with a bounded TRT tau-",
        "velocity_scale = 0.01\n[output]\ninterval = 10\n[coupling]\ntimeout = 10",
        "velocity_scale = 0.01\nmax_tau_minus = 1.0\n[output]\ninterval = 10\n[coupling]\ntimeout = 10\nradius_correction = \"calibrated\"",
        &["lattice.max_tau_minus = 1", "magic 3/16"],
    ),
    (
        "calibrated radius correction with other MRT rates",
        "velocity_scale = 0.01\n[output]\ninterval = 10\n[coupling]\ntimeout = 10",
        "velocity_scale = 0.01\noperator = \"mrt\"\nmrt = { e = 1.0, epsilon = 1.4, q = 1.2, pi = 1.4, m = 1.98 }\n[output]\ninterval = 10\n[coupling]\ntimeout = 10\nradius_correction = \"calibrated\"",
        &["lattice.mrt = MrtRates { e: 1.0", "d'Humieres' rates"],
    ),
];

#[test]
fn each_mistake_is_rejected_naming_file_field_and_value() {
    let base = scene_text("bad", [2, 2, 2], 100, 10, 10.0);
    assert!(MISTAKES.len() >= 10);
    for (what, from, to, words) in MISTAKES {
        assert!(base.contains(from), "{what}: the base scene lacks {from:?}");
        let dir = temp_dir("bad");
        let scene = write_scene(&dir, &base.replacen(from, to, 1));
        let out = dir.join("out");
        let result = server(&scene, &out, &[]).output().unwrap();
        let err = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(2), "{what}: exit code; stderr:\n{err}");
        assert!(
            err.contains(&scene.display().to_string()),
            "{what}: file not named:\n{err}"
        );
        for w in *words {
            assert!(err.contains(w), "{what}: {w:?} missing from:\n{err}");
        }
        assert!(!out.exists(), "{what}: the run started (output folder made)");
    }
}

#[test]
fn the_base_scene_itself_is_valid() {
    let dir = temp_dir("good");
    let scene = write_scene(&dir, &scene_text("good", [2, 2, 2], 3, 1, 10.0));
    let result = server(&scene, &dir.join("out"), &[]).output().unwrap();
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
}

/// A solid box wholly outside the domain makes no cell solid: the run goes on and warns, naming it.
#[test]
fn a_solid_box_outside_the_domain_warns() {
    let dir = temp_dir("box-outside");
    let text = scene_text("box", [2, 2, 2], 1, 1, 10.0).replacen(
        "tau = 0.8",
        "tau = 0.8\nsolid_box = [{ min = [0.1, 0.0, 0.0], max = [0.2, 0.016, 0.016] }]",
        1,
    );
    let scene = write_scene(&dir, &text);
    let result = server(&scene, &dir.join("out"), &[]).output().unwrap();
    let err = String::from_utf8_lossy(&result.stderr);
    assert!(result.status.success(), "{err}");
    let named = format!(
        "{}: lattice.solid_box[0] = min [0.1, 0, 0] m, max [0.2, 0.016, 0.016] m",
        scene.display()
    );
    assert!(
        err.contains(&named) && err.contains("wholly outside the domain"),
        "{err}"
    );
    // Said once, by lbm-server: the dem-client it starts loads the same scene and says nothing.
    assert_eq!(err.matches(&named).count(), 1, "{err}");
    assert!(err.contains(&format!("lbm-server: warning: {named}")), "{err}");
}

#[test]
fn a_missing_scene_file_is_named() {
    let result = server(
        std::path::Path::new("/nonexistent/scene.toml"),
        std::path::Path::new("/tmp/x"),
        &[],
    )
    .output()
    .unwrap();
    let err = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(2));
    assert!(
        err.contains("/nonexistent/scene.toml: cannot read the scene file"),
        "{err}"
    );
}
