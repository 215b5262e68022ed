//! The tests of `[lattice]`: the units derived from a scene and the fields refused.

use super::Kernel;
use crate::Scene;

/// lattice.ramp_time becomes the steps of the ramp (`Setup::face_ramp` in lbm-server draws
/// it); without it, none.
#[test]
fn the_ramp_time_becomes_steps() {
    let text = crate::DEFAULT_SCENE.replace("check_interval = 100", "check_interval = 100\nramp_time = 1.0");
    let units = Scene::parse(&text, "ramp.toml")
        .expect("scene")
        .lattice_units
        .expect("lattice");
    assert!(
        (units.ramp_steps - 1.0 / units.dt).abs() < 1e-9,
        "{}",
        units.ramp_steps
    );
    let plain = Scene::parse(crate::DEFAULT_SCENE, "d.toml")
        .expect("scene")
        .lattice_units
        .expect("lattice");
    assert_eq!(plain.ramp_steps, 0.0, "no ramp");
}

/// The default scene with `lines` added to its `[lattice]`; a `tau` among them replaces the
/// scene's.
fn with_lattice(lines: &str) -> Result<super::LatticeUnits, crate::SceneError> {
    let own_tau = "tau = 0.75 ";
    assert!(crate::DEFAULT_SCENE.contains(own_tau));
    let scene = if lines.lines().any(|l| l.starts_with("tau =")) {
        crate::DEFAULT_SCENE.replace(own_tau, "# tau = 0.75 ")
    } else {
        crate::DEFAULT_SCENE.to_string()
    };
    let text = scene.replace("check_interval = 100", &format!("check_interval = 100\n{lines}"));
    Scene::parse(&text, "tau_minus.toml").map(|s| s.lattice_units.expect("lattice"))
}

/// lattice.kernel takes auto (by default), quads and cells, and refuses another, naming the
/// field and the value.
#[test]
fn the_kernel_is_auto_quads_or_cells() {
    assert_eq!(with_lattice("").expect("scene").kernel, None);
    let named = [
        ("auto", None),
        ("quads", Some(Kernel::Quads)),
        ("cells", Some(Kernel::Cells)),
    ];
    for (name, kernel) in named {
        let units = with_lattice(&format!("kernel = {name:?}")).expect("scene");
        assert_eq!(units.kernel, kernel);
    }
    let err = with_lattice("kernel = \"quad\"").expect_err("quad").to_string();
    assert!(err.contains("lattice.kernel") && err.contains("quad"), "{err}");
}

/// lattice.storage takes the three storages (fp32 by default) and refuses another, naming
/// the field.
#[test]
fn the_storage_is_one_of_three() {
    assert_eq!(with_lattice("").expect("scene").storage.name(), "fp32");
    for name in super::Storage::ALL.map(super::Storage::name) {
        let units = with_lattice(&format!("storage = {name:?}")).expect("scene");
        assert_eq!(units.storage.name(), name);
    }
    let err = with_lattice("storage = \"fp8\"").expect_err("fp8").to_string();
    assert!(err.contains("lattice.storage") && err.contains("fp8"), "{err}");
}

/// lattice.max_tau_minus lowers TRT's magic where tau- = 1/2 + magic / (tau - 1/2) would
/// exceed it, and leaves it where it would not.
#[test]
fn max_tau_minus_bounds_trt_tau_minus() {
    let near = with_lattice("tau = 0.505\nmax_tau_minus = 1.0").expect("scene");
    assert!((near.magic - 0.0025).abs() < 1e-12, "{}", near.magic);
    assert!(
        (0.5 + near.magic / (near.tau - 0.5) - 1.0).abs() < 1e-9,
        "tau- = 1"
    );
    let far = with_lattice("tau = 1.0\nmax_tau_minus = 1.0").expect("scene");
    assert_eq!(far.magic, 3.0 / 16.0, "tau- 0.875 is below the bound");
    let plain = with_lattice("tau = 0.505").expect("scene");
    assert_eq!(plain.magic, 3.0 / 16.0, "no bound: the magic as given");
}

/// A bound of 1/2 or less, one on another operator and a magic that is not positive are
/// refused, naming the field and the value.
#[test]
fn a_bad_max_tau_minus_or_magic_is_refused() {
    let message = |lines: &str| with_lattice(lines).expect_err(lines).to_string();
    let half = message("max_tau_minus = 0.5");
    assert!(
        half.contains("lattice.max_tau_minus = 0.5") && half.contains("above 1/2"),
        "{half}"
    );
    assert!(with_lattice("max_tau_minus = 1.0").is_ok(), "TRT accepts it");
    let text = crate::DEFAULT_SCENE
        .replace("operator = \"trt\"", "operator = \"mrt\"")
        .replace(
            "check_interval = 100",
            "check_interval = 100\nmax_tau_minus = 1.0",
        );
    let mrt = Scene::parse(&text, "mrt.toml").expect_err("MRT").to_string();
    assert!(
        mrt.contains("lattice.max_tau_minus = 1") && mrt.contains("TRT only"),
        "{mrt}"
    );
    let magic = message("magic = -0.1");
    assert!(magic.contains("lattice.magic = -0.1"), "{magic}");
}
