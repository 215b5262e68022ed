//! Taylor-Green vortex decay: the viscosity the lattice shows against the one tau sets.

use crate::lbm::geometry::{Face, Operator, Setup};
use crate::lbm::gpu::{equilibrium_field, Gpu, GpuLattice, Health};
use crate::lbm::storage::Storage;
use std::sync::Arc;

/// Taylor-Green vortex decay: the measured viscosity against the one set by tau.
#[derive(Debug, Clone, Copy)]
pub struct Decay {
    pub nu_expected: f64,
    pub nu_measured: f64,
    pub relative_error: f64,
}

/// A 2D Taylor-Green vortex in an n x n periodic box: kinetic energy decays as exp(-4 nu k^2 t).
pub fn taylor_green(gpu: &Arc<Gpu>, n: usize, tau: f64, operator: Operator, u0: f64, steps: u64) -> Decay {
    taylor_green_stored(gpu, n, tau, operator, u0, steps, Storage::Fp32)
}

/// [`taylor_green`] with the populations in `storage`.
pub fn taylor_green_stored(
    gpu: &Arc<Gpu>,
    n: usize,
    tau: f64,
    operator: Operator,
    u0: f64,
    steps: u64,
    storage: Storage,
) -> Decay {
    let mut setup = Setup::new([n, n, 1], [Face::Periodic; 6], tau, operator);
    setup.storage = storage;
    let k = 2.0 * std::f64::consts::PI / n as f64;
    let state = |p: [usize; 3]| {
        let (x, y) = (p[0] as f64 + 0.5, p[1] as f64 + 0.5);
        let u = [
            u0 * (k * x).sin() * (k * y).cos(),
            -u0 * (k * x).cos() * (k * y).sin(),
            0.0,
        ];
        let pressure = -u0 * u0 / 4.0 * ((2.0 * k * x).cos() + (2.0 * k * y).cos());
        (1.0 + 3.0 * pressure, u)
    };
    let mut lattice = GpuLattice::new(gpu.clone(), setup.clone(), Health::default(), None).expect("lattice");
    lattice.set_populations(&equilibrium_field(&setup, state));
    // Skip the first steps (initial pressure transients), then fit between two times.
    let energy = |lattice: &GpuLattice| -> f64 {
        let (fields, _) = lattice.fields();
        fields.iter().map(|f| (f[1] * f[1] + f[2] * f[2]) as f64).sum()
    };
    lattice.step(steps / 10);
    let e0 = energy(&lattice);
    lattice.step(steps);
    let e1 = energy(&lattice);
    let nu_measured = (e0 / e1).ln() / (4.0 * k * k * steps as f64);
    let nu_expected = setup.viscosity();
    Decay {
        nu_expected,
        nu_measured,
        relative_error: (nu_measured - nu_expected).abs() / nu_expected,
    }
}
