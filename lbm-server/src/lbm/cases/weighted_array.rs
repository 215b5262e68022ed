//! Arrays of spheres (simple cubic or at random, immersed or staircase) held in a periodic box
//! against a weight per sphere: the superficial velocity at which the array's drag carries it.

use super::{coupled_lattice, plane_flux};
use crate::lbm::geometry::{Face, Operator, Setup};
use crate::lbm::gpu::{equilibrium_field, Gpu, GpuLattice, Health, Unhealthy};
use crate::lbm::imb::SolidParticle;
use std::sync::Arc;

/// An array of spheres held in a periodic n^3 box ([`array_at_weight`]).
#[derive(Debug, Clone)]
pub struct Array {
    pub cells: usize,
    pub diameter: f64,
    pub centres: Vec<[f64; 3]>,
    /// The x planes whose mean velocity is the superficial velocity: one that no sphere cuts, or
    /// all of them (the mean over the box; the fluid inside a held sphere is at rest).
    pub planes: Vec<usize>,
}

impl Array {
    /// One sphere at the centre of the box: a simple cubic array of solid fraction phi,
    /// d = n (6 phi / pi)^(1/3). The plane x = 0 lies half a box from the centre: no sphere cuts it.
    pub fn simple_cubic(n: usize, phi: f64) -> Self {
        Self {
            cells: n,
            diameter: n as f64 * (6.0 * phi / std::f64::consts::PI).cbrt(),
            centres: vec![[n as f64 / 2.0; 3]],
            planes: vec![0],
        }
    }

    /// Per cell (x fastest): whether its centre lies within a sphere, periodically.
    pub fn staircase(&self) -> Vec<bool> {
        let (n, r) = (self.cells, self.diameter / 2.0);
        let side = n as f64;
        let gap = |a: f64, b: f64| {
            let d = (a - b).abs();
            d.min(side - d)
        };
        (0..n * n * n)
            .map(|k| {
                let x = [k % n, (k / n) % n, k / (n * n)].map(|q| q as f64 + 0.5);
                self.centres
                    .iter()
                    .any(|c| (0..3).map(|a| gap(x[a], c[a]).powi(2)).sum::<f64>() < r * r)
            })
            .collect()
    }

    /// `count` spheres of solid fraction phi placed at random, none overlapping another across
    /// the periodic box (random sequential addition from `seed`): a random array as Tenneti et
    /// al. (2011) simulated theirs. Panics if a sphere finds no place in 100,000 tries.
    pub fn random(n: usize, count: usize, phi: f64, seed: u64) -> Self {
        let side = n as f64;
        let diameter = side * (6.0 * phi / (std::f64::consts::PI * count as f64)).cbrt();
        let mut random = crate::lbm::random::Random::new(seed);
        let mut centres: Vec<[f64; 3]> = Vec::with_capacity(count);
        let apart = |a: &[f64; 3], b: &[f64; 3]| {
            let gap = |i: usize| {
                let d = (a[i] - b[i]).abs();
                d.min(side - d)
            };
            (gap(0).powi(2) + gap(1).powi(2) + gap(2).powi(2)).sqrt() >= diameter
        };
        for k in 0..count {
            let place = (0..100_000)
                .map(|_| std::array::from_fn(|_| side * 0.5 * (random.next() + 1.0)))
                .find(|c| centres.iter().all(|o| apart(c, o)))
                .unwrap_or_else(|| panic!("sphere {k} of {count} finds no place at solid fraction {phi}"));
            centres.push(place);
        }
        Self {
            cells: n,
            diameter,
            centres,
            planes: (0..n).collect(),
        }
    }
}

/// How the held spheres of an [`Array`] meet the fluid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Spheres {
    /// The immersed moving boundary (partially saturated cells).
    Immersed,
    /// Solid cells, those whose centre lies within a sphere, with half-way bounce-back: a
    /// staircase of the sphere, no solid fractions.
    Staircase,
}

/// An array held against a weight per sphere ([`array_at_weight`]).
#[derive(Debug, Clone, Copy)]
pub struct WeightedArray {
    /// The periodic box's side n and the spheres' diameter d (cells).
    pub cells: usize,
    pub diameter: f64,
    pub tau: f64,
    pub steps: u64,
    /// Particle Reynolds number U d / nu of the superficial velocity U (the mean velocity over the
    /// array's planes): mean, lowest and highest over the last [`WEIGHT_SAMPLES`] checks.
    pub reynolds: [f64; 3],
    /// The first cell that failed the health check, if one did.
    pub unhealthy: Option<Unhealthy>,
}

/// Checks of the flux (one per [`WEIGHT_CHECK`] steps) that [`array_at_weight`] averages over and
/// that must agree to 1e-3 for it to stop.
pub const WEIGHT_SAMPLES: usize = 20;
pub const WEIGHT_CHECK: u64 = 100;

/// The spheres of `array` held in their periodic box, the fluid driven by a mean pressure
/// gradient f whose force on the box, f n^3, is `weight` rho nu^2 per sphere: the force a grain's
/// weight puts on the liquid in a fluidized bed, weight = (rho_p / rho_f - 1) g V / nu^2 = Ar pi
/// / 6. At rho = 1 and viscosity nu the superficial velocity settles where the array's drag
/// carries that weight; the run starts from the fluid at `u_start` everywhere and stops when
/// the last [`WEIGHT_SAMPLES`] fluxes agree to 1e-3 (a steady flow), after `max_steps`, or at a
/// failed health check. `boundary`: how the spheres meet the fluid.
pub fn array_at_weight(
    gpu: &Arc<Gpu>,
    array: &Array,
    [nu, weight]: [f64; 2],
    (operator, boundary): (Operator, Spheres),
    u_start: f64,
    max_steps: u64,
) -> WeightedArray {
    let setup = weighted_array_setup(array, [nu, weight], operator, boundary);
    let mut lattice = match boundary {
        Spheres::Immersed => coupled_lattice(gpu, &setup, Default::default()),
        Spheres::Staircase => {
            GpuLattice::new(gpu.clone(), setup.clone(), Health::default(), None).expect("lattice")
        }
    };
    lattice.set_populations(&equilibrium_field(&setup, |_| (1.0, [u_start, 0.0, 0.0])));
    let spheres: Vec<SolidParticle> = array
        .centres
        .iter()
        .map(|&position| SolidParticle {
            position,
            radius: array.diameter / 2.0,
            ..Default::default()
        })
        .collect();
    let mut history: Vec<f64> = Vec::new();
    let mut steps = 0;
    let mut unhealthy = None;
    while steps < max_steps {
        match boundary {
            Spheres::Immersed => {
                for _ in 0..WEIGHT_CHECK {
                    lattice.step_coupled(&spheres).expect("coupled step");
                }
            }
            Spheres::Staircase => lattice.step(WEIGHT_CHECK),
        }
        steps += WEIGHT_CHECK;
        let (fields, bad) = lattice.fields();
        if bad.is_some() {
            unhealthy = bad;
            break;
        }
        history.push(array_reynolds(array, &fields, nu));
        if steady(&history) {
            break;
        }
    }
    let last = &history[history.len().saturating_sub(WEIGHT_SAMPLES)..];
    let mean = last.iter().sum::<f64>() / last.len().max(1) as f64;
    let (low, high) = range(last);
    WeightedArray {
        cells: array.cells,
        diameter: array.diameter,
        tau: setup.tau,
        steps,
        reynolds: [mean, low, high],
        unhealthy,
    }
}

/// The periodic box of `array` with viscosity `nu` and the body force that carries `weight`
/// (in nu^2, per sphere) on the fluid cells: the spheres' solid cells with `Spheres::Staircase`.
fn weighted_array_setup(
    array: &Array,
    [nu, weight]: [f64; 2],
    operator: Operator,
    boundary: Spheres,
) -> Setup {
    let n = array.cells;
    let tau = 0.5 + 3.0 * nu;
    let mut setup = Setup::new([n, n, n], [Face::Periodic; 6], tau, operator);
    if boundary == Spheres::Staircase {
        setup.solid = array.staircase();
    }
    // The force acts on the fluid cells (solid cells are not updated): f times their count is
    // the weight of every sphere.
    let fluid = setup.solid.iter().filter(|&&s| !s).count();
    setup.force = [
        weight * nu * nu * array.centres.len() as f64 / fluid as f64,
        0.0,
        0.0,
    ];
    setup
}

/// The superficial Reynolds number of `array`'s flow: the mean flux through its planes times the
/// diameter over `nu`.
fn array_reynolds(array: &Array, fields: &[[f32; 4]], nu: f64) -> f64 {
    let flux = array
        .planes
        .iter()
        .map(|&x| plane_flux(fields, array.cells, x))
        .sum::<f64>();
    flux / array.planes.len() as f64 * array.diameter / nu
}

/// Whether the last `WEIGHT_SAMPLES` Reynolds numbers of `history` agree within 0.1%.
fn steady(history: &[f64]) -> bool {
    let last = &history[history.len().saturating_sub(WEIGHT_SAMPLES)..];
    let (low, high) = range(last);
    last.len() == WEIGHT_SAMPLES && high - low < 1e-3 * high.abs()
}

/// The lowest and highest of `values`.
fn range(values: &[f64]) -> (f64, f64) {
    values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
            (l.min(v), h.max(v))
        })
}

#[cfg(test)]
mod tests {
    /// A random array: its spheres at the solid fraction asked for, none overlapping another across
    /// the periodic box, the same placement from the same seed and another from another.
    #[test]
    fn a_random_array_places_its_spheres_apart_at_the_solid_fraction() {
        let (n, count, phi) = (25, 32, 0.24);
        let array = super::Array::random(n, count, phi, 1);
        assert_eq!(array.centres.len(), count);
        let volume = count as f64 * std::f64::consts::PI / 6.0 * array.diameter.powi(3);
        assert!((volume / (n * n * n) as f64 - phi).abs() < 1e-12);
        let side = n as f64;
        for (i, a) in array.centres.iter().enumerate() {
            assert!(a.iter().all(|&x| (0.0..side).contains(&x)), "{a:?}");
            for b in &array.centres[i + 1..] {
                let d2: f64 = (0..3)
                    .map(|k| {
                        let d = (a[k] - b[k]).abs();
                        d.min(side - d).powi(2)
                    })
                    .sum();
                assert!(d2.sqrt() >= array.diameter, "{a:?} {b:?}");
            }
        }
        assert_eq!(super::Array::random(n, count, phi, 1).centres, array.centres);
        assert_ne!(super::Array::random(n, count, phi, 2).centres, array.centres);
        assert_eq!(array.planes.len(), n);
    }

    /// A staircase: the cells whose centre lies within a sphere, across the periodic faces too;
    /// over 32 spheres at random, near their volume.
    #[test]
    fn a_staircase_marks_the_cells_within_each_sphere_across_the_faces() {
        let (n, diameter) = (16, 7.0);
        let one = |centre: [f64; 3]| super::Array {
            cells: n,
            diameter,
            centres: vec![centre],
            planes: vec![0],
        };
        let middle = one([8.0; 3]).staircase();
        let corner = one([0.0; 3]).staircase();
        let count = |cells: &[bool]| cells.iter().filter(|&&s| s).count();
        assert_eq!(count(&middle), count(&corner));
        assert!(corner[0] && corner[n - 1] && corner[n * n * n - 1]);
        assert!(middle[8 + 8 * n + 8 * n * n] && !middle[0]);
        let random = super::Array::random(25, 32, 0.24, 1);
        let solid = count(&random.staircase()) as f64 / 25f64.powi(3);
        assert!((solid / 0.24 - 1.0).abs() < 0.03, "{solid}");
    }
}
