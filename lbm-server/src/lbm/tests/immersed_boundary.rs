//! The immersed moving boundary's kernels against the f64 reference on random populations, its
//! ways and kernels changed between steps, and its refusals.

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

/// Three spheres whose overlap holds cells covered by all three, so that a cell's slots cannot
/// hold them all: each run keeps the same particles (the largest solid fractions, as the f64
/// reference does) and gives the same loads bit for bit, whatever the order in which the GPU's
/// invocations reach a cell.
#[test]
fn crowded_cells_keep_the_same_particles_every_run() {
    let setup = Setup::new(
        [12, 11, 10],
        [Face::Periodic; 6],
        0.7,
        Operator::Trt { magic: 3.0 / 16.0 },
    );
    let crowd = |shift: f64| {
        let mut particles = two_particles(shift);
        particles.insert(
            0,
            SolidParticle {
                position: [6.0 - shift, 5.0, 4.2 + shift],
                radius: 2.2,
                velocity: [0.005, 0.01, -0.02],
                angular_velocity: [-0.002, 0.001, 0.0],
            },
        );
        particles
    };
    for slots in [1, 2] {
        let options = ImbOptions {
            slots,
            ..Default::default()
        };
        let runs: Vec<(Vec<Vec<Load>>, u32)> = (0..3)
            .map(|_| check_steps(setup.clone(), options, 23, &[0.0, 0.29, 0.74], crowd))
            .collect();
        assert!(runs[0].1 > 0, "{slots} slots: some covers are dropped");
        for run in &runs[1..] {
            assert_eq!(run, &runs[0], "{slots} slots: bitwise identical loads and drops");
        }
    }
}

/// A sphere across periodic faces (its box wraps along x and y) feels what it feels inside the
/// box over the same fluid moved with it: the loads and the populations (moved back) agree,
/// fused and redone, over an even and an odd step; so does the sphere given one period away
/// (as a DEM with a periodic domain may send it). Until 2026-12-01 its box was clipped at the
/// faces, and the cells beyond were not covered.
#[test]
fn a_sphere_across_periodic_faces_feels_what_it_feels_inside() {
    let n = [12, 11, 10];
    let setup = Setup::new(n, [Face::Periodic; 6], 0.7, Operator::Trt { magic: 3.0 / 16.0 });
    let shift = [5, 4, 0];
    // moved[c] = f[c - shift]: the fluid moved by `shift` (and `back` undoes it).
    let roll = |f: &[Cell], by: [usize; 3]| -> Vec<Cell> {
        (0..setup.cells())
            .map(|k| {
                let c = setup.coords(k);
                f[setup.index(std::array::from_fn(|a| (c[a] + n[a] - by[a]) % n[a]))]
            })
            .collect()
    };
    let back = std::array::from_fn(|a| n[a] - shift[a]);
    let f0 = random_populations(&setup, 31);
    let sphere = |x: [f64; 3]| {
        vec![SolidParticle {
            position: x,
            radius: 2.3,
            velocity: [0.02, -0.01, 0.005],
            angular_velocity: [0.001, 0.002, -0.003],
        }]
    };
    let across = [[0.7, 10.4, 4.9], [0.9, 10.1, 5.2]];
    let run = |mode: CoveredCells, f: &[Cell], at: &dyn Fn(usize) -> [f64; 3]| {
        let options = ImbOptions {
            covered_cells: mode,
            ..Default::default()
        };
        let mut lattice = GpuLattice::new(gpu(), setup.clone(), Health::default(), Some(options)).unwrap();
        lattice.set_populations(f);
        let loads: Vec<Vec<Load>> = (0..2)
            .map(|s| lattice.step_coupled(&sphere(at(s))).unwrap())
            .collect();
        (loads, lattice.populations())
    };
    for mode in CoveredCells::DEFINITE {
        let (edge, f_edge) = run(mode, &f0, &|s| across[s]);
        let moved = |s: usize| std::array::from_fn(|a| (across[s][a] + shift[a] as f64) % n[a] as f64);
        let (inside, f_inside) = run(mode, &roll(&f0, shift), &moved);
        let (away, _) = run(mode, &f0, &|s| {
            [across[s][0] - 12.0, across[s][1] + 11.0, across[s][2]]
        });
        let scale = edge[0][0].force.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(scale > 1e-2, "{mode:?}: the sphere feels a force: {edge:?}");
        for s in 0..2 {
            for (what, other) in [("inside", &inside), ("one period away", &away)] {
                let err = max_load_difference(&edge[s], &other[s]);
                assert!(
                    err < 1e-4 * scale,
                    "{mode:?}, step {s}: across the faces {:?}, {what} {:?}",
                    edge[s],
                    other[s]
                );
            }
        }
        let err = max_difference(&f_edge, &roll(&f_inside, back));
        assert!(err < TOLERANCE, "{mode:?}: populations differ by {err:e}");
    }
}

#[test]
fn a_sphere_wider_than_a_periodic_axis_is_refused() {
    let setup = Setup::new([12, 5, 10], [Face::Periodic; 6], 0.7, Operator::Bgk);
    let mut lattice = coupled(&setup);
    let sphere = SolidParticle {
        position: [6.0, 2.5, 5.0],
        radius: 2.3,
        ..Default::default()
    };
    let err = lattice.step_coupled(&[sphere]).unwrap_err();
    assert!(
        err.contains("particle 0") && err.contains("periodic y axis of 5 cells"),
        "{err}"
    );
}

#[test]
fn trt_periodic_quads_next_to_particles_match_reference() {
    let setup = Setup::new(
        [12, 10, 9],
        [Face::Periodic; 6],
        0.7,
        Operator::Trt { magic: 3.0 / 16.0 },
    );
    check_with_quads(setup, ImbOptions::default(), 21);
}

#[test]
fn bgk_walls_quads_next_to_particles_match_reference() {
    let faces = [
        Face::Periodic,
        Face::Periodic,
        Face::Wall,
        Face::MovingWall([0.01, 0.0, 0.0]),
        Face::Wall,
        Face::Wall,
    ];
    let setup = Setup::new([16, 9, 10], faces, 0.8, Operator::Bgk);
    check_with_quads(setup, ImbOptions::default(), 22);
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

#[test]
fn trt_noble_torczynski_matches_reference_over_moving_steps() {
    check(trt_under_a_moving_lid(), ImbOptions::default(), 11);
}

#[test]
fn bgk_seed_weighting_matches_reference() {
    let setup = Setup::new([11, 10, 9], [Face::Periodic; 6], 0.9, Operator::Bgk);
    check(
        setup,
        ImbOptions {
            slots: 2,
            seed_weighting: true,
            ..Default::default()
        },
        12,
    );
}

fn superposition() -> ImbOptions {
    ImbOptions {
        solid_collision: SolidCollision::Superposition,
        ..Default::default()
    }
}

/// The superposition term with a body force (its source kept out of Omega) and moving,
/// spinning particles, for each operator; walls and a moving lid with TRT.
#[test]
fn bgk_superposition_with_a_body_force_matches_reference() {
    let mut setup = Setup::new([11, 10, 9], [Face::Periodic; 6], 0.9, Operator::Bgk);
    setup.force = [2e-4, -1e-4, 5e-5];
    check(setup, superposition(), 31);
}

#[test]
fn trt_superposition_between_walls_matches_reference() {
    check(trt_under_a_moving_lid(), superposition(), 32);
}

#[test]
fn mrt_superposition_with_a_body_force_matches_reference() {
    let mut setup = Setup::new(
        [12, 10, 9],
        [Face::Periodic; 6],
        0.8,
        Operator::Mrt {
            rates: Rates::dhumieres(1.0 / 0.8),
        },
    );
    setup.force = [-1e-4, 2e-4, 1e-4];
    check_with_quads(setup, superposition(), 33);
}

/// The superposition term drives a fully covered cell (B = 1) to the solid's velocity: its
/// populations become post - S + f_eq(u_s) - f_eq(u), whose momentum with BGK is rho u_s
/// exactly without a body force, and rho u_s - (1 - 1/tau) F / 2 with one (what Guo's
/// half-force velocity leaves of F in the relaxed part).
#[test]
fn superposition_moves_a_covered_cell_to_the_solid_velocity() {
    for force in [[0.0; 3], [1e-4, -2e-4, 0.0]] {
        let mut setup = Setup::new([12, 12, 12], [Face::Periodic; 6], 0.8, Operator::Bgk);
        setup.force = force;
        let f0 = random_populations(&setup, 34);
        let sphere = SolidParticle {
            position: [6.0, 6.0, 6.0],
            radius: 3.0,
            velocity: [0.02, -0.01, 0.005],
            ..Default::default()
        };
        let (next, _) = reference::step_with_particles(&setup, &f0, &[sphere], superposition());
        // Cell (6, 6, 6) lies wholly inside; streaming moved its post-collision populations
        // one link on: gather them back.
        let post: Cell = std::array::from_fn(|i| {
            let c = super::super::d3q19::C[i];
            next[setup.index(std::array::from_fn(|a| (6 + c[a] as i64) as usize))][i]
        });
        let (rho, _) = reference::moments(&f0[setup.index([6, 6, 6])], force);
        for a in 0..3 {
            let j: f64 = (0..19)
                .map(|i| post[i] * super::super::d3q19::C[i][a] as f64)
                .sum();
            let want = rho * sphere.velocity[a] - (1.0 - 1.0 / setup.tau) * force[a] / 2.0;
            assert!(
                (j - want).abs() < 1e-12,
                "force {force:?}, axis {a}: momentum {j} against {want}"
            );
        }
    }
}

#[test]
fn mrt_with_one_slot_matches_reference() {
    let setup = Setup::new(
        [11, 10, 9],
        [Face::Wall; 6],
        0.8,
        Operator::Mrt {
            rates: Rates::dhumieres(1.0 / 0.8),
        },
    );
    let options = ImbOptions {
        slots: 1,
        ..Default::default()
    };
    let f0 = random_populations(&setup, 13);
    let mut lattice = GpuLattice::new(gpu(), setup.clone(), Health::default(), Some(options)).unwrap();
    lattice.set_populations(&f0);
    // Particles apart: one slot suffices, nothing is dropped.
    let particles = vec![
        two_particles(0.0)[0],
        SolidParticle {
            position: [8.5, 6.0, 5.0],
            radius: 1.2,
            ..Default::default()
        },
    ];
    let (next, want) = reference::step_with_particles(&setup, &f0, &particles, options);
    let got = lattice.step_coupled(&particles).unwrap();
    assert!(max_load_difference(&got, &want) < 1e-4);
    assert!(max_difference(&lattice.populations(), &next) < TOLERANCE);
    assert_eq!(lattice.lost_covers().dropped, 0);
}

#[test]
fn forces_are_identical_from_run_to_run() {
    let setup = Setup::new(
        [11, 10, 9],
        [Face::Periodic; 6],
        0.7,
        Operator::Trt { magic: 3.0 / 16.0 },
    );
    let f0 = random_populations(&setup, 14);
    let run = || {
        let mut lattice = coupled(&setup);
        lattice.set_populations(&f0);
        (0..5)
            .map(|k| lattice.step_coupled(&two_particles(0.1 * k as f64)).unwrap())
            .collect::<Vec<_>>()
    };
    let (a, b) = (run(), run());
    assert_eq!(a, b, "bitwise identical loads");
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

#[test]
fn particles_in_parallel_chunks_match_the_reference() {
    let setup = many_particles_setup();
    let (loads, dropped) = check_steps(setup, ImbOptions::default(), 22, &[0.0, 0.3], many_particles);
    assert_eq!(loads[0].len(), 2 * CHUNK + 321);
    assert!(dropped > 0, "crowded cells drop covers");
}

/// The redo's list of covered cells in each layout: joined with one atomic per subgroup (a
/// GPU's) or one per cell (a CPU driver's), kept by population (a GPU's) or cell by cell (a CPU
/// driver's): each against the reference, and the same populations and loads bit for bit (the
/// cells' order in the list differs).
#[test]
fn the_covered_cells_list_gives_the_same_run_in_every_layout() {
    let setup = many_particles_setup();
    let options = ImbOptions {
        covered_cells: CoveredCells::Redo,
        ..ImbOptions::default()
    };
    let device = gpu();
    let subgroups = device.device.features().contains(wgpu::Features::SUBGROUP);
    assert!(subgroups, "this device has subgroups: every layout is compared");
    let layouts = [(false, false), (true, false), (false, true), (true, true)];
    let runs = layouts.map(|(subgroups, by_population)| {
        let gpu = Arc::new(device.with_list(ListLayout {
            subgroups,
            by_population,
        }));
        check_steps_in(gpu, setup.clone(), options, 23, &[0.0, 0.3], &many_particles)
    });
    for (layout, run) in layouts.iter().zip(&runs).skip(1) {
        assert_eq!(run.0, runs[0].0, "{layout:?}: loads differ");
        assert!(run.1 == runs[0].1, "{layout:?}: populations differ");
        assert_eq!(run.2, runs[0].2, "{layout:?}: dropped covers differ");
    }
}

/// A lattice that changes its way of treating the covered cells between steps (each of the
/// six changes once, at either parity; started fused, so the redo's list grows the `fields`
/// buffer under ways already built) gives the loads and populations of a lattice that keeps
/// to one, bit for bit: what lets a run time the ways on its own steps (`WayTrials`). A way
/// built during the run must leave its state alone (its kernels' first dispatch, which
/// compiles them on a CPU driver, once covered the last step's particles again).
#[test]
fn changing_ways_between_steps_gives_the_same_run() {
    let setup = many_particles_setup();
    let shifts = [0.0, 0.3, 0.45, 0.7, 0.8, 1.1, 1.3];
    let ways = [
        CoveredCells::Fused,
        CoveredCells::Redo,
        CoveredCells::Skip,
        CoveredCells::Fused,
        CoveredCells::Skip,
        CoveredCells::Redo,
        CoveredCells::Fused,
    ];
    let f0 = random_populations(&setup, 24);
    let options = ImbOptions {
        covered_cells: ways[0],
        ..ImbOptions::default()
    };
    let run = |change: bool| {
        run_shifted(&setup, options, &f0, &shifts, &|lattice, step| {
            if change {
                lattice.set_covered_cells(ways[step]).unwrap();
                assert_eq!(lattice.covered_cells(), ways[step]);
            }
        })
    };
    let (kept, changed) = (run(false), run(true));
    assert!(kept.0.iter().all(|l| l.iter().any(|l| l.force != [0.0; 3])));
    for (step, (a, b)) in kept.0.iter().zip(&changed.0).enumerate() {
        assert_eq!(a, b, "step {step} ({:?}): loads differ", ways[step]);
    }
    assert!(kept.1 == changed.1, "populations differ");
}

/// A lattice that changes its fluid kernels (the quads' and the per-cell kernel) and its way
/// of treating the covered cells between steps gives the loads and populations of a lattice
/// that keeps the quads' kernels and the redo, bit for bit: what lets a run's start-up trial
/// time the kernels on its own steps (`trials::Trial`).
#[test]
fn changing_kernels_between_steps_gives_the_same_run() {
    let setup = many_particles_setup();
    let shifts = [0.0, 0.3, 0.45, 0.7, 0.8, 1.1, 1.3];
    let (quads, cells) = (Kernel::Quads, Kernel::Cells);
    let ways = [
        (cells, CoveredCells::Redo),
        (cells, CoveredCells::Fused),
        (quads, CoveredCells::Skip),
        (cells, CoveredCells::Skip),
        (quads, CoveredCells::Redo),
        (cells, CoveredCells::Fused),
        (quads, CoveredCells::Fused),
    ];
    let f0 = random_populations(&setup, 26);
    let run = |change: bool| {
        run_shifted(&setup, ImbOptions::default(), &f0, &shifts, &|lattice, step| {
            if change {
                let (kernel, way) = ways[step];
                lattice.set_way(kernel, way).unwrap();
                assert_eq!((lattice.kernel(), lattice.covered_cells()), (kernel, way));
            }
        })
    };
    let (kept, changed) = (run(false), run(true));
    assert!(kept.0.iter().all(|l| l.iter().any(|l| l.force != [0.0; 3])));
    for (step, (a, b)) in kept.0.iter().zip(&changed.0).enumerate() {
        assert_eq!(a, b, "step {step} ({:?}): loads differ", ways[step]);
    }
    assert!(kept.1 == changed.1, "populations differ");
}

/// The loads of each step and the last populations of a lattice of `setup` with `options`,
/// from `f0`, stepped with `many_particles(shift)` for each of `shifts`, `before(lattice,
/// step)` called before each step; no cover left after the last.
fn run_shifted(
    setup: &Setup,
    options: ImbOptions,
    f0: &[Cell],
    shifts: &[f64],
    before: &dyn Fn(&mut GpuLattice, usize),
) -> (Vec<Vec<Load>>, Vec<Cell>) {
    let mut lattice = GpuLattice::new(gpu(), setup.clone(), Health::default(), Some(options)).unwrap();
    lattice.set_populations(f0);
    let loads: Vec<Vec<Load>> = shifts
        .iter()
        .enumerate()
        .map(|(step, &shift)| {
            before(&mut lattice, step);
            lattice.step_coupled(&many_particles(shift)).unwrap()
        })
        .collect();
    assert_eq!(lattice.cover_words_left(), 0, "covers left after the last step");
    (loads, lattice.populations())
}

/// A way whose kernels the device refuses (here a constant they do not declare, as a driver's
/// compiler refusing one would) is an error naming it, and the lattice goes on with its way:
/// the next steps match a lattice that never tried.
#[test]
fn a_way_the_device_refuses_leaves_the_lattice_as_it_was() {
    let setup = many_particles_setup();
    let f0 = random_populations(&setup, 25);
    let run = |spoil: bool| {
        let mut lattice = GpuLattice::new(
            gpu(),
            setup.clone(),
            Health::default(),
            Some(ImbOptions::default()),
        )
        .unwrap();
        lattice.set_populations(&f0);
        let mut loads = vec![lattice.step_coupled(&many_particles(0.0)).unwrap()];
        if spoil {
            lattice.spoil_next_way = true;
            let err = lattice.set_covered_cells(CoveredCells::Skip).unwrap_err();
            assert!(err.contains("skip kernels could not be built"), "{err}");
            assert_eq!(lattice.covered_cells(), CoveredCells::Redo);
        }
        loads.push(lattice.step_coupled(&many_particles(0.3)).unwrap());
        (loads, lattice.populations())
    };
    let (tried, kept) = (run(true), run(false));
    assert_eq!(tried.0, kept.0, "loads");
    assert!(tried.1 == kept.1, "populations");
}

#[test]
fn a_particle_too_large_is_refused_by_id_in_any_chunk() {
    let setup = Setup::new([40, 36, 32], [Face::Periodic; 6], 0.7, Operator::Bgk);
    let mut lattice = coupled(&setup);
    let mut particles = many_particles(0.0);
    particles[2 * CHUNK + 7].radius = 17.0;
    let err = lattice.step_coupled(&particles).unwrap_err();
    let id = format!("particle {}:", 2 * CHUNK + 7);
    assert!(err.contains(&id) && err.contains("periodic z axis"), "{err}");
}

#[test]
fn solid_fraction_sums_to_the_sphere_volume() {
    // Worst of 2000, 500 and 100 random centres (docs/imb.md): 1.1%, 0.39%, 0.05%.
    for (r, tolerance) in [(2.0, 0.015), (4.0, 0.005), (8.0, 0.001)] {
        for k in 0..16 {
            let c = [0.37, 0.61, 0.83].map(|a: f64| 10.0 + (a * k as f64).fract());
            let volume = covered_volume(c, r);
            let exact = 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
            let err = (volume - exact).abs() / exact;
            assert!(
                err < tolerance,
                "r = {r}, centre {c:?}: covered volume {volume} vs {exact} ({err:.2e})"
            );
        }
    }
}

#[test]
fn a_particle_too_large_for_the_box_index_is_refused_by_id() {
    let setup = Setup::new([8; 3], [Face::Periodic; 6], 0.7, Operator::Bgk);
    let mut lattice = coupled(&setup);
    let mut particles = two_particles(0.0);
    particles[1].radius = 128.0;
    let err = lattice.step_coupled(&particles).unwrap_err();
    assert!(err.contains("particle 1"), "{err}");
}

/// Covered cells beyond the room of the list of covered cells are counted (the run stops on
/// them), none when the list has room.
#[test]
fn covered_cells_beyond_the_list_are_counted() {
    let setup = Setup::new([12; 3], [Face::Periodic; 6], 0.7, Operator::Bgk);
    for covered_cells in [CoveredCells::Redo, CoveredCells::Skip] {
        let unlisted = |cap: Option<u64>| {
            let options = ImbOptions {
                covered_cells,
                ..ImbOptions::default()
            };
            let mut lattice =
                GpuLattice::new(gpu(), setup.clone(), Health::default(), Some(options)).unwrap();
            if let Some(cells) = cap {
                lattice.cap_covered_cells(cells);
            }
            lattice.step_coupled(&two_particles(0.0)).unwrap();
            let left = lattice.cover_words_left();
            (
                lattice.lost_covers().unlisted,
                lattice.covered_cell_capacity(),
                left,
            )
        };
        assert_eq!(unlisted(None).0, 0);
        let (missing, room, left) = unlisted(Some(16));
        assert_eq!(room, 16);
        assert!(
            missing > 16,
            "{covered_cells:?}: {missing} covered cells beyond a list of 16"
        );
        // Skip: only listed cells are masked (and unmasked after the fluid kernels).
        assert_eq!(left, 0, "{covered_cells:?}: cover words left for the next step");
    }
}

#[test]
fn the_bounding_box_holds_every_cell_with_a_solid_fraction() {
    let setup = Setup::new([24; 3], [Face::Periodic; 6], 0.7, Operator::Bgk);
    for r in [0.3f64, 0.7, 1.3, 2.0, 2.5, 4.0, 7.3] {
        // Centres with x - r and x + r on cell faces included.
        for offset in [0.0, 0.25, 0.5, 0.999, 1.0 - r.fract()] {
            let p = SolidParticle {
                position: [11.0 + offset, 12.0 - offset, 11.5 + offset],
                radius: r,
                ..Default::default()
            };
            let in_box: f64 = reference::box_cells(&setup, &p)
                .map(|(_, x)| reference::solid_fraction(x, p.position, r))
                .sum();
            let everywhere: f64 = (0..setup.cells())
                .map(|k| setup.coords(k).map(|v| v as f64 + 0.5))
                .map(|x| reference::solid_fraction(x, p.position, r))
                .sum();
            assert!(
                (in_box - everywhere).abs() < 1e-9,
                "r = {r}, centre {:?}: {in_box} in the box, {everywhere} in the grid",
                p.position
            );
        }
    }
}

/// The sum of the solid fractions of a 21^3 grid around a sphere.
fn covered_volume(c: [f64; 3], r: f64) -> f64 {
    let mut volume = 0.0;
    for x in 0..21 {
        for y in 0..21 {
            for z in 0..21 {
                volume += reference::solid_fraction([x, y, z].map(|v| v as f64 + 0.5), c, r);
            }
        }
    }
    volume
}
