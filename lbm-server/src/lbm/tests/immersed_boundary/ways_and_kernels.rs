//! The ways of treating the covered cells and the fluid kernels changed between steps give the
//! same run bit for bit; a way the device refuses leaves the lattice as it was.

use super::*;

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
