//! Conservation: the mass of a closed box with a moving lid, and the momentum of fluid and a
//! free particle exchanging it through the immersed boundary.

use super::coupled_lattice;
use crate::lbm::geometry::{Face, Operator, Setup};
use crate::lbm::gpu::{equilibrium_field, total_mass, Gpu, GpuLattice, Health};
use crate::lbm::imb::{ImbOptions, SolidParticle};
use crate::lbm::storage::Storage;
use std::sync::Arc;

/// Mass in a closed box with a moving lid, before and after `steps` steps.
#[derive(Debug, Clone, Copy)]
pub struct Mass {
    pub before: f64,
    pub after: f64,
    pub relative_drift: f64,
}

pub fn closed_box_mass(gpu: &Arc<Gpu>, n: usize, steps: u64, operator: Operator) -> Mass {
    closed_box_mass_stored(gpu, n, &[steps], operator, Storage::Fp32)[0]
}

/// [`closed_box_mass`] with the populations in `storage`, the mass after each of `steps` (rising
/// step counts of one run).
pub fn closed_box_mass_stored(
    gpu: &Arc<Gpu>,
    n: usize,
    steps: &[u64],
    operator: Operator,
    storage: Storage,
) -> Vec<Mass> {
    let mut faces = [Face::Wall; 6];
    faces[5] = Face::MovingWall([0.05, 0.0, 0.0]);
    let mut setup = Setup::new([n, n, n], faces, 0.6, operator);
    setup.storage = storage;
    let mut lattice = GpuLattice::new(gpu.clone(), setup.clone(), Health::default(), None).expect("lattice");
    let start = crate::lbm::random::random_populations(&setup, 7);
    lattice.set_populations(&start);
    let before = total_mass(&setup, &lattice.populations());
    let mut done = 0;
    steps
        .iter()
        .map(|&s| {
            lattice.step(s - done);
            done = s;
            let after = total_mass(&setup, &lattice.populations());
            Mass {
                before,
                after,
                relative_drift: (after - before).abs() / before,
            }
        })
        .collect()
}

/// Total momentum (fluid + particle) in a closed periodic box with one free particle.
#[derive(Debug, Clone, Copy)]
pub struct Momentum {
    pub initial: [f64; 3],
    pub last: [f64; 3],
    pub relative_change: f64,
    pub particle_velocity: [f64; 3],
}

/// A fluid moving at u0 along x around a particle at rest (density ratio 2), periodic box: the
/// particle is dragged along; fluid + particle momentum must not change.
pub fn momentum_exchange(gpu: &Arc<Gpu>, n: usize, steps: u64) -> Momentum {
    let setup = Setup::new(
        [n, n, n],
        [Face::Periodic; 6],
        0.7,
        Operator::Trt { magic: 3.0 / 16.0 },
    );
    let mut lattice = coupled_lattice(gpu, &setup, ImbOptions::default());
    let u0 = 0.02;
    lattice.set_populations(&equilibrium_field(&setup, |_| (1.0, [u0, 0.0, 0.0])));
    let radius = n as f64 / 6.0;
    let mass = 2.0 * 4.0 / 3.0 * std::f64::consts::PI * radius.powi(3);
    let mut p = SolidParticle {
        position: [n as f64 / 2.0 + 0.3, n as f64 / 2.0 - 0.2, n as f64 / 2.0],
        radius,
        ..Default::default()
    };
    let fluid_momentum = |lattice: &GpuLattice| -> [f64; 3] {
        let f = lattice.populations();
        let mut j = [0.0; 3];
        for cell in &f {
            for (i, fi) in cell.iter().enumerate() {
                for (ja, c) in j.iter_mut().zip(crate::lbm::d3q19::C[i]) {
                    *ja += fi * c as f64;
                }
            }
        }
        j
    };
    let total = |lattice: &GpuLattice, p: &SolidParticle| -> [f64; 3] {
        let j = fluid_momentum(lattice);
        std::array::from_fn(|a| j[a] + mass * p.velocity[a])
    };
    let initial = total(&lattice, &p);
    for _ in 0..steps {
        let load = lattice.step_coupled(&[p]).expect("coupled step")[0];
        for a in 0..3 {
            p.velocity[a] += load.force[a] / mass;
            p.position[a] += p.velocity[a];
        }
    }
    let last = total(&lattice, &p);
    let norm = |v: [f64; 3]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let change = norm(std::array::from_fn(|a| last[a] - initial[a])) / norm(initial);
    Momentum {
        initial,
        last,
        relative_change: change,
        particle_velocity: p.velocity,
    }
}
