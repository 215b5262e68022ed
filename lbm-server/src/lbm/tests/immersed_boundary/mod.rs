//! The immersed moving boundary's kernels against the f64 reference on random populations, its
//! ways and kernels changed between steps, and its refusals: the particles and lattices the
//! tests share, and the checks against the reference, here; the tests by concern:
//! `against_reference.rs` (the kernels and their options against the f64 reference),
//! `ways_and_kernels.rs` (ways and kernels changed between steps, or refused), `limits.rs`
//! (particles refused, covered cells beyond the list), `solid_fraction.rs` (the solid fraction's
//! sums and bounding box).

mod against_reference;
mod limits;
mod solid_fraction;
mod ways_and_kernels;

use super::super::imb::{CoveredCells, ImbOptions, Load, SolidCollision, SolidParticle, CHUNK};
use super::super::kernel::Kernel;
use super::*;

/// Two overlapping moving, spinning spheres, moved by `shift` cells between steps.
pub(in crate::lbm) fn two_particles(shift: f64) -> Vec<SolidParticle> {
    vec![
        SolidParticle {
            position: [4.3 + shift, 4.6, 3.9],
            radius: 2.4,
            velocity: [0.02, -0.01, 0.005],
            angular_velocity: [0.001, 0.002, -0.003],
        },
        SolidParticle {
            position: [7.4, 5.1 - shift, 4.4],
            radius: 1.7,
            velocity: [-0.01, 0.015, 0.0],
            angular_velocity: [0.0, -0.002, 0.004],
        },
    ]
}

/// A lattice coupled with the default settings.
fn coupled(setup: &Setup) -> GpuLattice {
    GpuLattice::new(
        gpu(),
        setup.clone(),
        Health::default(),
        Some(ImbOptions::default()),
    )
    .unwrap()
}

fn max_load_difference(a: &[Load], b: &[Load]) -> f64 {
    worst_load(a, b).1
}

/// The particle whose load differs most between `a` and `b`, and by how much.
fn worst_load(a: &[Load], b: &[Load]) -> (usize, f64) {
    assert_eq!(a.len(), b.len(), "loads of as many particles");
    let difference = |x: &Load, y: &Load| {
        (0..3)
            .flat_map(|k| [x.force[k] - y.force[k], x.torque[k] - y.torque[k]])
            .fold(0.0, |m: f64, d| m.max(d.abs()))
    };
    a.iter()
        .zip(b)
        .map(|(x, y)| difference(x, y))
        .enumerate()
        .fold((0, 0.0), |worst, (j, d)| if d > worst.1 { (j, d) } else { worst })
}

fn check(setup: Setup, options: ImbOptions, seed: u64) {
    let (_, dropped) = check_steps(setup, options, seed, &[0.0, 0.37, 0.81], two_particles);
    assert_eq!(dropped, 0);
}

/// One coupled step per shift on the GPU and in f64 (the particles moved between steps), each
/// compared, with the covered cells both fused in the fluid kernels and redone after them,
/// which must agree bit for bit; the GPU's loads of every step and the covers it dropped.
fn check_steps(
    setup: Setup,
    options: ImbOptions,
    seed: u64,
    shifts: &[f64],
    particles_at: impl Fn(f64) -> Vec<SolidParticle>,
) -> (Vec<Vec<Load>>, u32) {
    let modes = CoveredCells::DEFINITE;
    let runs = modes.map(|covered_cells| {
        let options = ImbOptions {
            covered_cells,
            ..options
        };
        check_steps_in(gpu(), setup.clone(), options, seed, shifts, &particles_at)
    });
    let (redo, redo_f, redo_dropped) = &runs[0];
    for (mode, (loads, f, dropped)) in modes.iter().zip(&runs).skip(1) {
        assert_eq!(loads, redo, "loads: redo and {mode:?} differ");
        assert_eq!(dropped, redo_dropped, "dropped covers: redo and {mode:?} differ");
        assert!(f == redo_f, "populations: redo and {mode:?} differ");
    }
    (redo.clone(), *redo_dropped)
}

/// `check_steps` with one way of treating the covered cells; also the final populations.
fn check_steps_in(
    gpu: Arc<Gpu>,
    setup: Setup,
    options: ImbOptions,
    seed: u64,
    shifts: &[f64],
    particles_at: &impl Fn(f64) -> Vec<SolidParticle>,
) -> (Vec<Vec<Load>>, Vec<Cell>, u32) {
    let f0 = random_populations(&setup, seed);
    let mut lattice = GpuLattice::new(gpu, setup.clone(), Health::default(), Some(options)).unwrap();
    assert_eq!(lattice.covered_cells(), options.covered_cells);
    lattice.set_populations(&f0);
    let mut f = f0;
    let mut loads = Vec::new();
    for (step, &shift) in shifts.iter().enumerate() {
        let particles = particles_at(shift);
        let (next, want) = reference::step_with_particles(&setup, &f, &particles, options);
        let got = lattice.step_coupled(&particles).unwrap();
        let scale = want
            .iter()
            .flat_map(|l| l.force)
            .fold(0.0, |m: f64, v| m.max(v.abs()));
        let (j, err) = worst_load(&got, &want);
        let mode = options.covered_cells;
        assert!(scale > 1e-3, "the particles feel a force: {want:?}");
        assert!(
            err < 1e-4 * scale.max(1.0),
            "{mode:?}, step {step}: loads differ by {err:e} at particle {j} of {}: {:?} vs {:?}",
            got.len(),
            got[j],
            want[j]
        );
        let pop_err = max_difference(&lattice.populations(), &next);
        assert!(
            pop_err < TOLERANCE,
            "{mode:?}, step {step}: populations differ by {pop_err:e}"
        );
        assert_eq!(
            lattice.cover_words_left(),
            0,
            "{mode:?}, step {step}: covers left for the next step"
        );
        f = next;
        loads.push(got);
    }
    (loads, lattice.populations(), lattice.lost_covers().dropped)
}

/// The grids below have interior quads (nx a multiple of 4), so the fast fluid kernels (quads,
/// their odd step, wrapping and boundary cells) run next to covered cells; a third sphere
/// crosses the face x = 0 (wrapping or boundary cells covered).
fn check_with_quads(setup: Setup, options: ImbOptions, seed: u64) {
    let classes = super::super::gpu::CellList::new(&setup, true);
    assert!(classes.interior_quads > 0, "the grid has interior quads");
    let three = |shift: f64| {
        let mut particles = two_particles(shift);
        particles.push(SolidParticle {
            position: [0.6, 2.2 + shift, 6.5],
            radius: 1.9,
            velocity: [0.0, 0.01, -0.01],
            angular_velocity: [0.003, 0.0, 0.001],
        });
        particles
    };
    let (_, dropped) = check_steps(setup, options, seed, &[0.0, 0.37, 0.81, 1.3], three);
    assert_eq!(dropped, 0);
}

/// TRT between walls in y and z, under a lid moving along x, periodic in x.
pub(in crate::lbm) fn trt_under_a_moving_lid() -> Setup {
    let faces = [
        Face::Periodic,
        Face::Periodic,
        Face::Wall,
        Face::Wall,
        Face::Wall,
        Face::MovingWall([0.01, 0.0, 0.0]),
    ];
    Setup::new([11, 10, 9], faces, 0.7, Operator::Trt { magic: 3.0 / 16.0 })
}

/// The periodic TRT lattice of `many_particles`.
fn many_particles_setup() -> Setup {
    Setup::new(
        [40, 36, 32],
        [Face::Periodic; 6],
        0.7,
        Operator::Trt { magic: 3.0 / 16.0 },
    )
}

/// Particles enough for three chunks of the host's passes (run in parallel, each writing its
/// own records and pair ranges, and converting its own loads), of different radii (box edges
/// 2 to 5), crowded and across the periodic faces: the f64 reference's loads and populations,
/// fused and redone.
fn many_particles(shift: f64) -> Vec<SolidParticle> {
    let mut r = Random::new(21);
    let n = [40.0, 36.0, 32.0];
    (0..2 * CHUNK + 321)
        .map(|_| SolidParticle {
            position: n.map(|n| (0.5 + 0.55 * r.next()) * n + shift),
            radius: 1.05 + 0.55 * r.next(),
            velocity: [0.02 * r.next(), 0.02 * r.next(), 0.02 * r.next()],
            angular_velocity: [0.002 * r.next(), 0.002 * r.next(), 0.002 * r.next()],
        })
        .collect()
}
