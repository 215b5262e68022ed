//! A checkpoint of a lattice cut into blocks against one process's, to the byte: the state the
//! blocks give rank 0 is the single lattice's, in either phase of the AA pattern, and blocks put
//! in the single lattice's state (cut another way) go on to its state of a later step, alone and
//! coupled to particles across the cuts; ranks as threads (`tests.rs`), without MPI.

use super::checkpoint::restore_whole;
use super::coupled_tests::particles;
use super::tests::{periodic, walled};
use super::{BlockLattice, Communicator, Decomposition, ThreadRanks};
use crate::lbm::geometry::Setup;
use crate::lbm::gpu::{Gpu, Health, RawState};
use crate::lbm::imb::{CoveredCells, ImbOptions};
use std::sync::Arc;

/// A copy of `s`.
fn copy(s: &RawState) -> RawState {
    RawState {
        populations: s.populations.clone(),
        status: s.status.clone(),
        time: s.time,
        face_scale: s.face_scale,
    }
}

/// `setup` cut into `blocks` on threads, put in the state `from` where given (else at rest),
/// stepped from step `t0` to `t1` (coupled to [`particles`] where `coupled`): the whole
/// lattice's state then, at rank 0.
fn run(
    setup: &Setup,
    coupled: bool,
    blocks: [usize; 3],
    from: Option<&RawState>,
    (t0, t1): (u64, u64),
) -> RawState {
    let gpu = Arc::new(Gpu::new().expect("a wgpu adapter (lavapipe in CI)"));
    let options = coupled.then(|| ImbOptions {
        covered_cells: CoveredCells::Redo,
        ..ImbOptions::default()
    });
    let periodic: [bool; 3] = std::array::from_fn(|a| setup.periodic(a));
    let ranks: usize = blocks.iter().product();
    std::thread::scope(|s| {
        let handles: Vec<_> = ThreadRanks::world(ranks)
            .into_iter()
            .map(|comm| {
                let (gpu, setup) = (gpu.clone(), setup.clone());
                let from = from.filter(|_| comm.rank() == 0).map(|f| Ok(copy(f)));
                s.spawn(move || {
                    let d = Decomposition::new(setup.n, periodic, blocks, comm.rank());
                    let mut block =
                        BlockLattice::with_coupling(gpu, setup, Health::default(), d, options).unwrap();
                    restore_whole(&mut block, &comm, from).unwrap();
                    for t in t0..t1 {
                        match coupled {
                            true => block
                                .step_coupled_with(&particles(t)[..], &mut Vec::new(), |_, l| l, &comm)
                                .unwrap(),
                            false => block.step(1, &comm),
                        }
                    }
                    block.whole_state(&comm)
                })
            })
            .collect();
        let mut states: Vec<_> = handles.into_iter().map(|h| h.join().unwrap()).collect();
        states.swap_remove(0).expect("rank 0's state")
    })
}

fn same(want: &RawState, have: &RawState, what: &str) {
    assert_eq!(want.time, have.time, "{what}: the clock");
    assert_eq!(want.face_scale.to_bits(), have.face_scale.to_bits(), "{what}");
    for (i, (w, h)) in want.populations.iter().zip(&have.populations).enumerate() {
        assert!(w == h, "{what}: direction {i}'s populations differ");
    }
    assert_eq!(want.status, have.status, "{what}: the status words");
}

/// One lattice, stepped to `at` and on to `end`; the blocks `written` stepped to `at` give its
/// state there, the blocks `resumed` put in it give its state at `end`.
fn check(setup: Setup, coupled: bool, (written, resumed): ([usize; 3], [usize; 3]), (at, end): (u64, u64)) {
    let one_at = run(&setup, coupled, [1, 1, 1], None, (0, at));
    let one_end = run(&setup, coupled, [1, 1, 1], Some(&one_at), (at, end));
    let what = format!("written on {written:?} at step {at}");
    same(&one_at, &run(&setup, coupled, written, None, (0, at)), &what);
    let what = format!("resumed on {resumed:?} at step {at}, at step {end}");
    same(
        &one_end,
        &run(&setup, coupled, resumed, Some(&one_at), (at, end)),
        &what,
    );
    let through = run(&setup, coupled, [1, 1, 1], None, (0, end));
    same(
        &through,
        &one_end,
        "one lattice resumed against one that went through",
    );
}

#[test]
fn a_checkpoint_of_blocks_is_the_single_lattices_and_resumes_on_other_blocks() {
    // Stopped after an odd step and after an even one (the AA pattern's two phases).
    check(walled(), false, ([1, 1, 2], [2, 1, 1]), (3, 6));
    check(periodic(), false, ([2, 2, 1], [1, 2, 1]), (4, 6));
}

#[test]
fn a_coupled_checkpoint_of_blocks_is_the_single_lattices_and_resumes_on_other_blocks() {
    check(walled(), true, ([1, 1, 2], [2, 1, 2]), (3, 5));
}
