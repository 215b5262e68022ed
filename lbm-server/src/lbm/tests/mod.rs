//! Every GPU kernel against the f64 reference step, on random populations.

use super::geometry::{Cell, Face, Operator, Setup};
use super::gpu::{fits_device, furthest_out_of_bounds, Gpu, GpuLattice, Health, ListLayout};
use super::mrt::Rates;
use super::random::{random_populations, Random};
use super::reference;
use std::sync::Arc;

pub fn gpu() -> Arc<Gpu> {
    Arc::new(Gpu::new().expect("a wgpu adapter (lavapipe in CI)"))
}

/// Largest |a - b| over all populations.
fn max_difference(a: &[Cell], b: &[Cell]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(x, y)| x.iter().zip(y).map(|(p, q)| (p - q).abs()))
        .fold(0.0, f64::max)
}

/// Single-precision round-off bound for populations of magnitude ~0.35 after one step.
const TOLERANCE: f64 = 64.0 * f32::EPSILON as f64 * 0.35;

/// Runs 1 and 2 steps on the GPU and in f64 and compares (odd and even AA phases).
fn check_against_reference(setup: Setup, seed: u64) {
    let f0 = random_populations(&setup, seed);
    let mut lattice = GpuLattice::new(gpu(), setup.clone(), Health::default(), None).unwrap();
    lattice.set_populations(&f0);
    let f1 = reference::step(&setup, &f0);
    let f2 = reference::step(&setup, &f1);
    assert!(
        max_difference(&f0, &f1) > 1e-3,
        "the step must change the populations"
    );
    lattice.step(1);
    let err1 = max_difference(&lattice.populations(), &f1);
    lattice.step(1);
    let err2 = max_difference(&lattice.populations(), &f2);
    let op = setup.operator.name();
    assert!(
        err1 < TOLERANCE,
        "{op}: step 1 differs by {err1:e} (tolerance {TOLERANCE:e})"
    );
    assert!(
        err2 < TOLERANCE,
        "{op}: step 2 differs by {err2:e} (tolerance {TOLERANCE:e})"
    );
}

fn sprinkle_solids(setup: &mut Setup, seed: u64) {
    let mut r = Random::new(seed);
    for s in setup.solid.iter_mut() {
        *s = r.next() > 0.8;
    }
}

/// A grid whose fields buffer would exceed the device's storage binding limit is refused with the
/// numbers before anything is allocated (it used to panic in wgpu's bind-group validation: Ten Cate
/// E4 at 16 cells per diameter, 224 x 224 x 256, on lavapipe's 128 MiB).
#[test]
fn a_grid_beyond_the_binding_limit_is_refused_clearly() {
    let lavapipe = wgpu::Limits {
        max_storage_buffer_binding_size: 128 << 20,
        ..wgpu::Limits::default()
    };
    assert_eq!(fits_device(&lavapipe, [64, 64, 2048]), Ok(()));
    let err = fits_device(&lavapipe, [64, 64, 2049]).unwrap_err();
    for part in [
        "64x64x2049",
        "8392704 cells",
        "134283264 bytes",
        "134217728 bytes",
        "8388608 cells here",
    ] {
        assert!(err.contains(part), "{part} missing: {err}");
    }
    assert!(fits_device(&lavapipe, [224, 224, 256]).is_err());
}

/// BGK, periodic, with a body force, on `n` cells.
pub(super) fn bgk_periodic_with_force(n: [usize; 3]) -> Setup {
    let mut setup = Setup::new(n, [Face::Periodic; 6], 0.8, Operator::Bgk);
    setup.force = [1e-4, -2e-4, 3e-5];
    setup
}

/// TRT between walls in y and z (one moving), periodic in x, a body force, solid cells.
pub(crate) fn trt_walls_and_solids(n: [usize; 3]) -> Setup {
    let faces = [
        Face::Periodic,
        Face::Periodic,
        Face::Wall,
        Face::MovingWall([0.02, 0.0, 0.01]),
        Face::Wall,
        Face::Wall,
    ];
    let mut setup = Setup::new(n, faces, 0.62, Operator::Trt { magic: 3.0 / 16.0 });
    setup.force = [2e-5, 0.0, -1e-5];
    sprinkle_solids(&mut setup, 2);
    setup
}

/// MRT from a velocity inlet to a pressure outlet along x, walls in y, solid cells.
pub(super) fn mrt_inlet_outlet_and_solids() -> Setup {
    let faces = [
        Face::VelocityInlet([0.03, 0.0, 0.0]),
        Face::PressureOutlet(1.01),
        Face::Wall,
        Face::Wall,
        Face::Periodic,
        Face::Periodic,
    ];
    let mut setup = Setup::new(
        [6, 4, 5],
        faces,
        0.7,
        Operator::Mrt {
            rates: Rates::dhumieres(1.0 / 0.7),
        },
    );
    sprinkle_solids(&mut setup, 4);
    setup
}

#[test]
fn bgk_periodic_with_body_force_matches_reference() {
    check_against_reference(bgk_periodic_with_force([6, 5, 4]), 1);
}

#[test]
fn trt_walls_moving_wall_and_solids_match_reference() {
    check_against_reference(trt_walls_and_solids([7, 5, 4]), 3);
}

#[test]
fn mrt_inlet_outlet_and_solids_match_reference() {
    check_against_reference(mrt_inlet_outlet_and_solids(), 5);
}

#[test]
fn bgk_inlet_outlet_on_every_axis_matches_reference() {
    let faces = [
        Face::Wall,
        Face::MovingWall([0.0, 0.03, -0.01]),
        Face::VelocityInlet([0.0, 0.02, 0.0]),
        Face::PressureOutlet(0.99),
        Face::PressureOutlet(1.02),
        Face::VelocityInlet([0.01, 0.0, -0.02]),
    ];
    let setup = Setup::new([5, 6, 4], faces, 1.3, Operator::Bgk);
    check_against_reference(setup, 6);
}

/// A velocity inlet and a moving wall at `scale` times their velocity (`set_face_scale`) step as
/// the faces given that velocity do, bit for bit, and back at 1 as the faces given.
#[test]
fn scaled_face_velocities_are_the_faces_with_those_velocities() {
    let faces = |s: f64| {
        [
            Face::VelocityInlet([0.04 * s, 0.0, 0.01 * s]),
            Face::PressureOutlet(1.0),
            Face::MovingWall([0.0, 0.02 * s, 0.0]),
            Face::Wall,
            Face::Periodic,
            Face::Periodic,
        ]
    };
    let setup = |s: f64| Setup::new([6, 5, 4], faces(s), 0.7, Operator::Trt { magic: 3.0 / 16.0 });
    let f0 = random_populations(&setup(1.0), 7);
    let run = |setup: Setup, scales: &[f64]| {
        let mut lattice = GpuLattice::new(gpu(), setup, Health::default(), None).unwrap();
        lattice.set_populations(&f0);
        for &scale in scales {
            lattice.set_face_scale(scale);
            lattice.step(1);
        }
        lattice.populations()
    };
    let scaled = run(setup(1.0), &[0.25, 0.25, 1.0]);
    let given = {
        let mut lattice = GpuLattice::new(gpu(), setup(0.25), Health::default(), None).unwrap();
        lattice.set_populations(&f0);
        lattice.step(2);
        let mid = lattice.populations();
        let mut full = GpuLattice::new(gpu(), setup(1.0), Health::default(), None).unwrap();
        full.set_populations(&mid);
        full.time = 2;
        full.step(1);
        full.populations()
    };
    assert_eq!(max_difference(&scaled, &given), 0.0);
    assert!(
        max_difference(&scaled, &run(setup(1.0), &[1.0; 3])) > 1e-4,
        "the scale must act"
    );
}

/// The faces rise from rest as (1 - cos(pi t / T)) / 2 over the setup's ramp of T steps, and
/// are whole from the first step without one.
#[test]
fn the_faces_rise_from_rest_over_the_ramp() {
    let mut setup = Setup::new([2, 2, 2], [Face::Periodic; 6], 0.6, Operator::Bgk);
    assert_eq!(setup.face_ramp(0), 1.0, "no ramp: whole from the first step");
    setup.ramp_steps = 869.5;
    assert!(setup.face_ramp(0) < 1e-4, "{}", setup.face_ramp(0));
    let half = setup.face_ramp(433);
    let expected = 0.5 * (1.0 - (std::f64::consts::PI * 434.0 / 869.5).cos());
    assert!((half - expected).abs() < 1e-12, "{half}");
    assert!(setup.face_ramp(868) < 1.0);
    assert_eq!(setup.face_ramp(869), 1.0);
    assert_eq!(setup.face_ramp(8690), 1.0);
}

/// A start from rest keeps the pressure wave of a velocity inlet small: a duct between an inlet
/// and a pressure outlet, MRT at tau 0.51, started at full speed or ramped over 1000 steps (the
/// duct rings with a period of 4 L / c_s = 440 steps, hardly damped). Measured over steps
/// 1000-1500: the mid-plane flow swings up to 0.020 off the inlet's 0.05 after the sudden start,
/// 0.0025 after the ramp.
#[test]
fn a_ramped_inlet_sends_a_weaker_pressure_wave_than_a_sudden_one() {
    let faces = [
        Face::Periodic,
        Face::Periodic,
        Face::Wall,
        Face::Wall,
        Face::VelocityInlet([0.0, 0.0, 0.05]),
        Face::PressureOutlet(1.0),
    ];
    let tau = 0.51;
    let setup = Setup::new(
        [8, 8, 64],
        faces,
        tau,
        Operator::Mrt {
            rates: Rates::dhumieres(1.0 / tau),
        },
    );
    let largest_wave = |ramp_steps: f64| {
        let setup = Setup {
            ramp_steps,
            ..setup.clone()
        };
        let mut lattice = GpuLattice::new(gpu(), setup, Health::default(), None).unwrap();
        lattice.step(1000);
        let mut largest: f64 = 0.0;
        for _ in 0..100 {
            lattice.step(5);
            let (fields, _) = lattice.fields();
            let plane = &fields[32 * 64..33 * 64];
            let flow = plane.iter().map(|c| c[3] as f64).sum::<f64>() / 64.0;
            largest = largest.max((flow - 0.05).abs());
        }
        largest
    };
    let (sudden, ramped) = (largest_wave(0.0), largest_wave(1000.0));
    assert!(
        sudden > 0.01,
        "a sudden start at 0.05 leaves the duct ringing: {sudden}"
    );
    assert!(ramped < 0.3 * sudden, "ramped {ramped}, sudden {sudden}");
}

/// The fields kept on the device at a check that passed come back as they were then, after the
/// lattice has changed and failed a check (a run's last good snapshot).
#[test]
fn kept_fields_are_those_of_the_last_good_check() {
    let setup = Setup::new(
        [8, 6, 5],
        [Face::Periodic; 6],
        0.7,
        Operator::Trt { magic: 3.0 / 16.0 },
    );
    let mut f = random_populations(&setup, 12);
    let mut lattice = GpuLattice::new(gpu(), setup.clone(), Health::default(), None).unwrap();
    assert!(lattice.kept_fields().is_none());
    lattice.set_populations(&f);
    lattice.step(3);
    let (good, bad) = lattice.fields();
    assert!(bad.is_none());
    assert!(lattice.health().is_none());
    lattice.keep_fields();
    f[100] = std::array::from_fn(|i| super::d3q19::equilibrium_shifted(i, 1.0, [0.6, 0.0, 0.0]));
    lattice.set_populations(&f);
    assert!(lattice.health().is_some());
    assert_eq!(lattice.kept_fields().expect("kept"), good);
}

/// The run's health check reads back one cell, not the field: it finds the cell the full
/// readback finds (the lowest index among the unhealthy ones), with its density and velocity,
/// and nothing in a healthy lattice.
#[test]
fn the_health_check_finds_the_cell_the_full_readback_finds() {
    let setup = Setup::new([8, 6, 5], [Face::Wall; 6], 0.7, Operator::Bgk);
    let mut f = random_populations(&setup, 11);
    let mut lattice = GpuLattice::new(gpu(), setup.clone(), Health::default(), None).unwrap();
    lattice.set_populations(&f);
    assert!(lattice.health().is_none());
    assert!(lattice.fields().1.is_none());
    // Two cells too fast (|u| 0.5 > 0.4); the lower index is the one reported.
    for k in [141, 77] {
        f[k] = std::array::from_fn(|i| super::d3q19::equilibrium_shifted(i, 1.02, [0.3, -0.4, 0.0]));
    }
    lattice.set_populations(&f);
    let (fields, full) = lattice.fields();
    let (one, full) = (lattice.health().expect("unhealthy"), full.expect("unhealthy"));
    assert_eq!((one.cell, one.coords), (77, setup.coords(77)));
    assert_eq!((full.cell, full.coords), (one.cell, one.coords));
    assert_eq!([one.rho, one.u[0], one.u[1], one.u[2]], fields[77]);
    assert!((one.u[1] + 0.4).abs() < 1e-5, "{one:?}");
}

/// A blow-up is named where it is furthest out of bounds, not at the first cell in memory order
/// that the check finds: of a cell a little too fast and one far too fast, the far one; a negative
/// density is further out than a speed just above the limit; a non-finite value furthest of all.
#[test]
fn a_blow_up_is_named_at_the_cell_furthest_out_of_bounds() {
    let setup = Setup::new([8, 6, 5], [Face::Wall; 6], 0.7, Operator::Bgk);
    let mut f = random_populations(&setup, 11);
    let lattice_health = Health::default();
    let mut lattice = GpuLattice::new(gpu(), setup.clone(), lattice_health, None).unwrap();
    lattice.set_populations(&f);
    assert!(lattice.health().is_none());
    assert!(lattice.furthest_unhealthy().is_none());
    f[77] = std::array::from_fn(|i| super::d3q19::equilibrium_shifted(i, 1.0, [0.42, 0.0, 0.0]));
    f[141] = std::array::from_fn(|i| super::d3q19::equilibrium_shifted(i, 1.0, [0.0, 0.0, -0.6]));
    lattice.set_populations(&f);
    assert_eq!(
        lattice.health().expect("unhealthy").cell,
        77,
        "the check finds the first"
    );
    let furthest = lattice.furthest_unhealthy().expect("unhealthy");
    assert_eq!((furthest.cell, furthest.coords), (141, setup.coords(141)));
    let centre = |origin: f64, n: usize| origin + (n as f64 + 0.5) * 0.01;
    let said = furthest.describe(&lattice_health, |[i, j, k]| {
        [centre(0.5, i), centre(0.0, j), centre(-1.0, k)]
    });
    let [i, j, k] = setup.coords(141);
    let at = format!(
        "cell 141 at ({i}, {j}, {k}), centre ({:.4e}, {:.4e}, {:.4e}) m: lattice speed 0.600",
        centre(0.5, i),
        centre(0.0, j),
        centre(-1.0, k)
    );
    assert!(said.starts_with(&at), "{said}");
    let health = Health::default();
    let fields = [
        [1.0, 0.0, 0.0, 0.0],
        [1.0, 0.41, 0.0, 0.0],
        [-0.2, 0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0, 0.5],
    ];
    assert_eq!(
        furthest_out_of_bounds(&fields, &health),
        Some(2),
        "rho -0.2 is 2.4 x the bound"
    );
    let nan = [f32::NAN, 0.0, 0.0, 0.0];
    let fields = [
        [1.0, 0.0, 0.0, 0.0],
        [-0.2, 0.0, 0.0, 0.0],
        nan,
        [f32::INFINITY; 4],
    ];
    assert_eq!(furthest_out_of_bounds(&fields, &health), Some(2));
}

mod validation_cases;

pub(in crate::lbm) mod immersed_boundary;

mod coupling_validation;
