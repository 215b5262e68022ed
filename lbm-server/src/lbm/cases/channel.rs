//! Steady channel flows against their analytic profiles: Poiseuille flow between plates and
//! through a square duct, half-way bounce-back walls.

use super::relaxation_steps;
use crate::lbm::geometry::{Face, Operator, Setup};
use crate::lbm::gpu::{equilibrium_field, Gpu, GpuLattice, Health};
use crate::lbm::storage::Storage;
use std::sync::Arc;

/// Result of a steady channel flow: L2 error of u_x against the analytic profile, relative to max.
#[derive(Debug, Clone, Copy)]
pub struct Channel {
    pub cells: usize,
    pub tau: f64,
    pub l2_error: f64,
    pub steps: u64,
    /// The mean u_x over the channel's cross-section (the flux over its area).
    pub mean_speed: f64,
}

/// A channel flow's lattice: cells across, tau, operator, centre-line speed, storage.
#[derive(Debug, Clone, Copy)]
pub struct Flow {
    pub n: usize,
    pub tau: f64,
    pub operator: Operator,
    pub u_max: f64,
    pub storage: Storage,
}

impl Flow {
    fn fp32(n: usize, tau: f64, operator: Operator, u_max: f64) -> Flow {
        Flow {
            n,
            tau,
            operator,
            u_max,
            storage: Storage::Fp32,
        }
    }

    /// The channel's lattice along x of `cells`, walls on y (and on z where `duct`).
    fn setup(&self, cells: [usize; 3], duct: bool) -> Setup {
        let z = if duct { Face::Wall } else { Face::Periodic };
        let faces = [Face::Periodic, Face::Periodic, Face::Wall, Face::Wall, z, z];
        let mut setup = Setup::new(cells, faces, self.tau, self.operator);
        setup.storage = self.storage;
        setup
    }
}

/// Poiseuille flow between plates at y = -1/2 and y = n - 1/2 (half-way bounce-back), driven by a
/// body force chosen for a centre-line speed `u_max`.
pub fn poiseuille_plates(gpu: &Arc<Gpu>, n: usize, tau: f64, operator: Operator, u_max: f64) -> Channel {
    poiseuille_plates_stored(gpu, Flow::fp32(n, tau, operator, u_max))
}

/// [`poiseuille_plates`] of `flow`, its populations in `flow.storage`.
pub fn poiseuille_plates_stored(gpu: &Arc<Gpu>, flow: Flow) -> Channel {
    let Flow { n, tau, u_max, .. } = flow;
    let mut setup = flow.setup([1, n, 1], false);
    let nu = setup.viscosity();
    let h = n as f64;
    setup.force = [8.0 * nu * u_max / (h * h), 0.0, 0.0];
    let exact = |y: usize| {
        let y = y as f64 + 0.5;
        4.0 * u_max * y * (h - y) / (h * h)
    };
    let steps = relaxation_steps(h, nu, 20.0);
    let (fields, _) = run_steady(gpu, &setup, |p| (1.0, [exact(p[1]), 0.0, 0.0]), steps);
    let error = l2_relative((0..n).map(|y| (fields[y][1] as f64, exact(y))));
    Channel {
        cells: n,
        tau,
        l2_error: error,
        steps,
        mean_speed: mean_speed(&fields),
    }
}

/// Flow through a square duct of n x n cells (walls on y and z), against the series solution.
pub fn poiseuille_duct(gpu: &Arc<Gpu>, n: usize, tau: f64, operator: Operator, u_max: f64) -> Channel {
    poiseuille_duct_stored(gpu, Flow::fp32(n, tau, operator, u_max))
}

/// [`poiseuille_duct`] of `flow`, its populations in `flow.storage`.
pub fn poiseuille_duct_stored(gpu: &Arc<Gpu>, flow: Flow) -> Channel {
    let Flow { n, tau, u_max, .. } = flow;
    let mut setup = flow.setup([1, n, n], true);
    let nu = setup.viscosity();
    let a = n as f64;
    // Series solution for unit forcing, scaled so that the centre speed is u_max.
    let unit = |y: f64, z: f64| duct_series(y / a, z / a) * a * a / nu;
    let g = u_max / unit(a / 2.0, a / 2.0);
    setup.force = [g, 0.0, 0.0];
    let exact = |p: [usize; 3]| g * unit(p[1] as f64 + 0.5, p[2] as f64 + 0.5);
    let steps = relaxation_steps(a, nu, 12.0);
    let (fields, _) = run_steady(gpu, &setup, |p| (1.0, [exact(p), 0.0, 0.0]), steps);
    let error = l2_relative((0..setup.cells()).map(|k| (fields[k][1] as f64, exact(setup.coords(k)))));
    Channel {
        cells: n,
        tau,
        l2_error: error,
        steps,
        mean_speed: mean_speed(&fields),
    }
}

/// u(y, z) of unit force, unit viscosity in the unit square with no-slip walls (Fourier series).
fn duct_series(y: f64, z: f64) -> f64 {
    let pi = std::f64::consts::PI;
    let mut sum = 0.0;
    for i in (1..80).step_by(2) {
        for j in (1..80).step_by(2) {
            let (a, b) = (i as f64 * pi, j as f64 * pi);
            sum += 16.0 / (a * b * (a * a + b * b)) * (a * y).sin() * (b * z).sin();
        }
    }
    sum
}

fn run_steady(
    gpu: &Arc<Gpu>,
    setup: &Setup,
    initial: impl Fn([usize; 3]) -> (f64, [f64; 3]),
    steps: u64,
) -> (Vec<[f32; 4]>, u64) {
    let mut lattice = GpuLattice::new(gpu.clone(), setup.clone(), Health::default(), None).expect("lattice");
    lattice.set_populations(&equilibrium_field(setup, initial));
    lattice.step(steps);
    let (fields, bad) = lattice.fields();
    assert!(bad.is_none(), "unhealthy: {bad:?}");
    (fields, steps)
}

/// The mean u_x of `fields`.
fn mean_speed(fields: &[[f32; 4]]) -> f64 {
    fields.iter().map(|f| f[1] as f64).sum::<f64>() / fields.len() as f64
}

fn l2_relative(pairs: impl Iterator<Item = (f64, f64)>) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (got, want) in pairs {
        num += (got - want).powi(2);
        den += want * want;
    }
    (num / den).sqrt()
}

/// Observed order of convergence between two (resolution, error) points.
pub fn order(a: &Channel, b: &Channel) -> f64 {
    (a.l2_error / b.l2_error).ln() / (b.cells as f64 / a.cells as f64).ln()
}
