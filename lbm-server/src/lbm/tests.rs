//! Every GPU kernel against the f64 reference step, on random populations.

use super::geometry::{Cell, Face, Operator, Setup};
use super::gpu::{Gpu, Health, Lattice};
use super::random::{random_populations, Random};
use super::mrt::Rates;
use super::reference;
use std::sync::Arc;

pub fn gpu() -> Arc<Gpu> {
    Arc::new(Gpu::new().expect("a wgpu adapter (lavapipe in CI)"))
}

/// Largest |a - b| over all populations.
fn max_difference(a: &[Cell], b: &[Cell]) -> f64 {
    a.iter().zip(b).flat_map(|(x, y)| x.iter().zip(y).map(|(p, q)| (p - q).abs())).fold(0.0, f64::max)
}

/// Single-precision round-off bound for populations of magnitude ~0.35 after one step.
const TOLERANCE: f64 = 64.0 * f32::EPSILON as f64 * 0.35;

/// Runs 1 and 2 steps on the GPU and in f64 and compares (odd and even AA phases).
fn check_against_reference(setup: Setup, seed: u64) {
    let f0 = random_populations(&setup, seed);
    let mut lattice = Lattice::new(gpu(), setup.clone(), Health::default()).unwrap();
    lattice.set_populations(&f0);
    let f1 = reference::step(&setup, &f0);
    let f2 = reference::step(&setup, &f1);
    assert!(max_difference(&f0, &f1) > 1e-3, "the step must change the populations");
    lattice.step(1);
    let err1 = max_difference(&lattice.populations(), &f1);
    lattice.step(1);
    let err2 = max_difference(&lattice.populations(), &f2);
    let op = setup.operator.name();
    assert!(err1 < TOLERANCE, "{op}: step 1 differs by {err1:e} (tolerance {TOLERANCE:e})");
    assert!(err2 < TOLERANCE, "{op}: step 2 differs by {err2:e} (tolerance {TOLERANCE:e})");
}

fn sprinkle_solids(setup: &mut Setup, seed: u64) {
    let mut r = Random::new(seed);
    for s in setup.solid.iter_mut() {
        *s = r.next() > 0.8;
    }
}

#[test]
fn bgk_periodic_with_body_force_matches_reference() {
    let mut setup = Setup::new([6, 5, 4], [Face::Periodic; 6], 0.8, Operator::Bgk);
    setup.force = [1e-4, -2e-4, 3e-5];
    check_against_reference(setup, 1);
}

#[test]
fn trt_walls_moving_wall_and_solids_match_reference() {
    let faces = [
        Face::Periodic,
        Face::Periodic,
        Face::Wall,
        Face::MovingWall([0.02, 0.0, 0.01]),
        Face::Wall,
        Face::Wall,
    ];
    let mut setup = Setup::new([7, 5, 4], faces, 0.62, Operator::Trt { magic: 3.0 / 16.0 });
    setup.force = [2e-5, 0.0, -1e-5];
    sprinkle_solids(&mut setup, 2);
    check_against_reference(setup, 3);
}

#[test]
fn mrt_inlet_outlet_and_solids_match_reference() {
    let faces = [
        Face::VelocityInlet([0.03, 0.0, 0.0]),
        Face::PressureOutlet(1.01),
        Face::Wall,
        Face::Wall,
        Face::Periodic,
        Face::Periodic,
    ];
    let mut setup = Setup::new([6, 4, 5], faces, 0.7, Operator::Mrt { rates: Rates::dhumieres(1.0 / 0.7) });
    sprinkle_solids(&mut setup, 4);
    check_against_reference(setup, 5);
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

mod validation_cases {
    use super::super::validation::*;
    use super::*;

    const MAGIC: f64 = 3.0 / 16.0;

    #[test]
    fn poiseuille_plates_converge_at_second_order_with_bgk() {
        let g = gpu();
        let runs: Vec<Channel> =
            [8, 16, 32].iter().map(|&n| poiseuille_plates(&g, n, 0.6, Operator::Bgk, 0.02)).collect();
        for pair in runs.windows(2) {
            let p = order(&pair[0], &pair[1]);
            assert!((1.8..2.3).contains(&p), "order {p:.2} between {:?} and {:?}", pair[0], pair[1]);
        }
    }

    #[test]
    fn trt_wall_location_is_viscosity_independent_bgk_is_not() {
        let g = gpu();
        let trt = Operator::Trt { magic: MAGIC };
        let taus = [0.6, 1.0, 2.0];
        let trt_err: Vec<f64> = taus.iter().map(|&t| poiseuille_plates(&g, 16, t, trt, 0.02).l2_error).collect();
        let bgk_err: Vec<f64> =
            taus.iter().map(|&t| poiseuille_plates(&g, 16, t, Operator::Bgk, 0.02).l2_error).collect();
        // TRT with Lambda = 3/16 keeps the wall half-way at every tau: what remains is far below BGK.
        assert!(trt_err.iter().all(|e| *e < 2e-4), "TRT errors {trt_err:?}");
        // BGK's wall moves with tau: its error grows by far more than 10x from tau 0.6 to 2.
        assert!(bgk_err[2] > 10.0 * bgk_err[0], "BGK errors {bgk_err:?}");
        assert!(bgk_err[2] > 100.0 * trt_err[2], "BGK {bgk_err:?} vs TRT {trt_err:?}");
    }

    #[test]
    fn square_duct_converges_at_second_order() {
        let g = gpu();
        let runs: Vec<Channel> =
            [8, 16, 24].iter().map(|&n| poiseuille_duct(&g, n, 0.8, Operator::Bgk, 0.02)).collect();
        for pair in runs.windows(2) {
            let p = order(&pair[0], &pair[1]);
            assert!((1.7..2.4).contains(&p), "order {p:.2} between {:?} and {:?}", pair[0], pair[1]);
        }
    }

    #[test]
    fn taylor_green_decay_gives_the_viscosity_within_one_percent() {
        let g = gpu();
        for op in [Operator::Bgk, Operator::Trt { magic: MAGIC }, Operator::Mrt { rates: Rates::dhumieres(1.0 / 0.8) }] {
            let d = taylor_green(&g, 32, 0.8, op, 0.02, 1000);
            assert!(d.relative_error < 0.01, "{}: {d:?}", op.name());
        }
    }

    #[test]
    fn mass_is_conserved_to_round_off_over_10000_steps() {
        let m = closed_box_mass(&gpu(), 12, 10_000, Operator::Trt { magic: MAGIC });
        assert!(m.relative_drift < 1e-6, "{m:?}");
    }
}
