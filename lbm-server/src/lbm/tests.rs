//! Every GPU kernel against the f64 reference step, on random populations.

use super::geometry::{Cell, Face, Operator, Setup};
use super::gpu::{Gpu, Health, Lattice};
use super::lattice::equilibrium_shifted;
use super::mrt::Rates;
use super::reference;
use std::sync::Arc;

/// xorshift64*: reproducible random numbers without a dependency.
pub struct Random(u64);

impl Random {
    pub fn new(seed: u64) -> Self {
        Self(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }

    /// Uniform in [-1, 1).
    pub fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let v = self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11;
        v as f64 / (1u64 << 52) as f64 - 1.0
    }
}

/// Near-equilibrium random populations with a random non-equilibrium part.
pub fn random_populations(setup: &Setup, seed: u64) -> Vec<Cell> {
    let mut r = Random::new(seed);
    (0..setup.cells())
        .map(|_| {
            let rho = 1.0 + 0.05 * r.next();
            let u = [0.05 * r.next(), 0.05 * r.next(), 0.05 * r.next()];
            std::array::from_fn(|i| equilibrium_shifted(i, rho, u) + 1e-3 * r.next())
        })
        .collect()
}

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
