//! The tests of the start-up trial: which choice each step takes under made-up step costs.

use super::*;
use CoveredCells::{Fused, Redo, Skip};
use Kernel::{Cells, Quads};

fn ms(c: Choice, kernel: [f64; 2], way: [f64; 3]) -> f64 {
    let k = match c.kernel {
        Quads => kernel[0],
        Cells => kernel[1],
    };
    let w = match c.way {
        Redo => way[0],
        Skip => way[1],
        _ => way[2],
    };
    1e-3 * k * w
}

/// Runs `steps` steps of a trial, each step lasting `cost(step, choice)` seconds plus
/// `switch` seconds when its choice differs from the previous step's; the choices taken and
/// the trial's report lines.
fn run(
    mut trial: Trial,
    steps: u64,
    cost: impl Fn(u64, Choice) -> f64,
    switch: f64,
) -> (Vec<Choice>, Vec<String>) {
    let (mut now, mut taken, mut reports) = (0.0, Vec::<Choice>::new(), Vec::new());
    for step in 0..steps {
        let c = trial.choice_for(step, now);
        reports.extend(trial.take_report());
        if taken.last().is_some_and(|&last| last != c) {
            now += switch;
        }
        now += cost(step, c);
        taken.push(c);
    }
    (taken, reports)
}

fn open() -> Trial {
    Trial::new(vec![Quads, Cells], vec![Redo, Skip, Fused], 1000)
}

/// The first stage times the kernels with the starting way, BLOCK steps a choice a round in
/// turned order; the second the ways with the kernel kept; the fastest of each is kept from
/// the trial's end; the first step of each block, slowed by the change, does not decide.
#[test]
fn a_trial_keeps_the_fastest_kernel_and_way() {
    let cost = |_, c| ms(c, [1.0, 1.2], [2.0, 1.5, 2.2]);
    let (taken, reports) = run(open(), 1000, cost, 0.05);
    assert!(taken[..FIRST as usize].iter().all(|&c| c
        == Choice {
            kernel: Quads,
            way: Redo
        }));
    let block = |b: u64| taken[(FIRST + b * BLOCK) as usize];
    let kernels: Vec<Kernel> = (0..6).map(|b| block(b).kernel).collect();
    assert_eq!(kernels, [Quads, Cells, Cells, Quads, Quads, Cells]);
    assert!((0..6).all(|b| block(b).way == Redo));
    let ways: Vec<CoveredCells> = (6..15).map(|b| block(b).way).collect();
    assert_eq!(ways, [Redo, Skip, Fused, Skip, Fused, Redo, Fused, Redo, Skip]);
    assert!((6..15).all(|b| block(b).kernel == Quads));
    for b in 0..15 {
        let steps = &taken[(FIRST + b * BLOCK) as usize..(FIRST + (b + 1) * BLOCK) as usize];
        assert!(steps.iter().all(|&c| c == block(b)), "block {b}");
    }
    let after = (FIRST + 15 * BLOCK) as usize;
    assert!(taken[after..].iter().all(|&c| c
        == Choice {
            kernel: Quads,
            way: Skip
        }));
    assert_eq!(reports.len(), 2, "{reports:?}");
    assert!(
        reports[0].contains("quads 2.000 ms, cells 2.400 ms") && reports[0].ends_with("quads kept"),
        "{reports:?}"
    );
    assert!(
        reports[1].contains("redo 2.000 ms, skip 1.500 ms, fused 2.200 ms")
            && reports[1].ends_with("skip kept"),
        "{reports:?}"
    );
}

/// A kernel many times slower (the per-cell kernel on a CPU driver) is dropped after the
/// first round: it takes one block; the ways are then timed with the other.
#[test]
fn a_slow_choice_takes_one_block() {
    let cost = |_, c| ms(c, [1.0, 16.0], [1.0, 2.0, 3.0]);
    let (taken, reports) = run(open(), 1000, cost, 0.0);
    assert_eq!(taken.iter().filter(|c| c.kernel == Cells).count(), BLOCK as usize);
    assert!(
        reports[0].contains("cells 16.000 ms (dropped after a round)"),
        "{reports:?}"
    );
    assert_eq!(
        taken[999],
        Choice {
            kernel: Quads,
            way: Redo
        }
    );
}

/// The per-cell kernel faster (a GPU): kept, and the ways timed with it.
#[test]
fn the_ways_are_timed_with_the_kernel_kept() {
    let cost = |_, c| ms(c, [1.3, 1.0], [2.0, 1.5, 1.4]);
    let (taken, reports) = run(open(), 1000, cost, 0.0);
    assert_eq!(
        taken[999],
        Choice {
            kernel: Cells,
            way: Fused
        }
    );
    assert!(
        reports[1].starts_with("covered cells timed with the cells kernels"),
        "{reports:?}"
    );
}

/// A change of choice that costs more than the choices differ by does not decide either.
#[test]
fn the_cost_of_changing_is_left_out() {
    let cost = |_, c| ms(c, [1.0, 1.1], [1.0, 1.2, 1.1]);
    let (taken, _) = run(open(), 1000, cost, 10.0);
    assert_eq!(
        taken[999],
        Choice {
            kernel: Quads,
            way: Redo
        }
    );
}

/// A run too short for the trial and the room after it keeps its choice throughout and says
/// how long a run must be; a scene that pins both has nothing to time.
#[test]
fn a_short_run_keeps_its_choice() {
    let steps = FIRST + ROOM * open().longest() - 1;
    let trial = Trial::new(vec![Quads, Cells], vec![Fused, Redo, Skip], steps);
    assert!(trial.describe().contains("not timed"), "{}", trial.describe());
    let (taken, reports) = run(trial, steps, |_, c| ms(c, [2.0, 1.0], [1.0, 2.0, 3.0]), 0.0);
    assert!(
        taken.iter().all(|&c| c
            == Choice {
                kernel: Quads,
                way: Fused
            })
            && reports.is_empty()
    );
    let pinned = Trial::new(vec![Cells], vec![Skip], 100_000);
    assert!(!pinned.open());
    let (taken, reports) = run(pinned, 1000, |_, c| ms(c, [2.0, 1.0], [1.0, 2.0, 3.0]), 0.0);
    assert!(
        taken.iter().all(|&c| c
            == Choice {
                kernel: Cells,
                way: Skip
            })
            && reports.is_empty()
    );
}

/// A scene that pins the kernel has only the ways timed, from FIRST; one that pins the way
/// (or a run without particles) only the kernels.
#[test]
fn a_pinned_kernel_or_way_is_not_timed() {
    let trial = Trial::new(vec![Cells], vec![Redo, Skip, Fused], 1000);
    let (taken, reports) = run(trial, 1000, |_, c| ms(c, [1.0, 1.0], [2.0, 1.5, 3.0]), 0.0);
    assert_eq!(reports.len(), 1);
    assert_eq!(taken[FIRST as usize + BLOCK as usize].way, Skip);
    assert_eq!(
        taken[999],
        Choice {
            kernel: Cells,
            way: Skip
        }
    );
    let trial = Trial::new(vec![Quads, Cells], vec![Redo], 1000);
    let (taken, reports) = run(trial, 1000, |_, c| ms(c, [1.2, 1.0], [1.0, 1.0, 1.0]), 0.0);
    assert_eq!(reports.len(), 1);
    assert_eq!(
        taken[999],
        Choice {
            kernel: Cells,
            way: Redo
        }
    );
}

/// A trial with nothing to time (a pinned kernel, no particles; or pinned on a CPU driver)
/// is never under way, so the run steps its first steps in batches; an open one is until it
/// is done.
#[test]
fn a_trial_with_nothing_open_is_never_under_way() {
    let mut pinned = Trial::new(vec![Quads], Vec::new(), 1000);
    let mut timed = open();
    assert!(!pinned.under_way() && timed.under_way());
    for step in 0..1000 {
        pinned.choice_for(step, step as f64);
        timed.choice_for(step, step as f64);
        assert!(!pinned.under_way(), "step {step}");
    }
    assert!(!timed.under_way());
}

/// A slow step now and then (particles.csv written every 10 steps, 25 times a step's time)
/// does not decide: each choice's median step does.
#[test]
fn an_occasional_slow_step_does_not_decide() {
    let trial = Trial::new(vec![Quads], vec![Redo, Skip, Fused], 1000);
    let cost =
        |step: u64, c| ms(c, [1.0, 1.0], [2.0, 1.8, 3.0]) + if step.is_multiple_of(10) { 0.05 } else { 0.0 };
    let (taken, reports) = run(trial, 1000, cost, 0.0);
    assert_eq!(taken[999].way, Skip, "{reports:?}");
    assert!(
        reports[0].contains("redo 2.000 ms, skip 1.800 ms, fused 3.000 ms"),
        "{reports:?}"
    );
}

/// A choice the device does not build is refused at its first block: it is not asked for
/// again, the others decide, and the report says so.
#[test]
fn a_choice_not_built_is_left_out() {
    let mut trial = Trial::new(vec![Quads], vec![Redo, Skip, Fused], 1000);
    let (mut now, mut asked, mut reports) = (0.0, Vec::new(), Vec::new());
    let mut current = Redo;
    for step in 0..1000 {
        let c = trial.choice_for(step, now);
        reports.extend(trial.take_report());
        asked.push(c.way);
        if c.way == Fused {
            trial.refuse();
        } else {
            current = c.way;
        }
        now += ms(
            Choice {
                kernel: Quads,
                way: current,
            },
            [1.0, 1.0],
            [2.0, 1.5, 0.5],
        );
    }
    assert_eq!(asked.iter().filter(|&&w| w == Fused).count(), 1);
    assert_eq!(asked[999], Skip);
    assert!(
        reports.len() == 1 && reports[0].contains("skip 1.500 ms, fused not built"),
        "{reports:?}"
    );
}

/// On two ranks (threads), the trial of the kernels by rank 0's clock (rank 1's own running 7
/// times faster), where rank 1's device does not build the per-cell kernel: both ranks ask for
/// the same choices at every step, are under way at the same steps, and keep the same kernel;
/// rank 0's report says the per-cell kernel was not built.
#[test]
fn ranks_make_the_same_choices_by_rank_0s_clock_and_refusals() {
    use crate::lbm::geometry::{Face, Operator, Setup};
    use crate::lbm::gpu::{Gpu, Health};
    use crate::parallel::{rank0s, ThreadRanks};
    let gpu = std::sync::Arc::new(Gpu::new().expect("a wgpu adapter (lavapipe in CI)"));
    let setup = Setup::new([8, 8, 8], [Face::Periodic; 6], 0.8, Operator::Bgk);
    let steps = 120;
    let taken: Vec<(Vec<(bool, Choice)>, Kernel)> = std::thread::scope(|s| {
        let handles: Vec<_> = ThreadRanks::world(2)
            .into_iter()
            .map(|comm| {
                let (gpu, setup) = (gpu.clone(), setup.clone());
                s.spawn(move || {
                    let mut lattice = GpuLattice::new(gpu, setup, Health::default(), None).unwrap();
                    lattice.spoil_next_way = comm.rank() == 1;
                    let mut trial = Trial::new(vec![Quads, Cells], Vec::new(), steps);
                    let clock = [1e-3, 7e-3][comm.rank()];
                    let asked: Vec<(bool, Choice)> = (0..steps)
                        .map(|step| {
                            let now = rank0s(&comm, clock * step as f64);
                            trial.give_agreed_choice(&mut lattice, step, now, &comm);
                            (trial.under_way(), trial.kept())
                        })
                        .collect();
                    (asked, trial.kept().kernel)
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    assert_eq!(taken[0], taken[1], "the ranks' trials");
    assert!(taken[0].0.iter().any(|(under_way, _)| *under_way));
    assert!(!taken[0].0.last().unwrap().0, "the trial ended");
    assert_eq!(taken[0].1, Quads);
}
