//! A coupled lattice cut into blocks against the same lattice on one rank: the particles' loads
//! (at rank 0) and the fields bit for bit, with spheres across the cuts, the periodic wraps and
//! an edge and a corner of the blocks, and spheres within one block each (their loads reduced by
//! that block's rank); ranks as threads (`tests.rs`), without MPI.

use super::coupled_block::block_options;
use super::tests::{periodic, put_together, walled};
use super::ThreadRanks;
use super::{BlockLattice, Decomposition};
use crate::lbm::geometry::Setup;
use crate::lbm::gpu::{Gpu, GpuLattice, Health};
use crate::lbm::imb::{box_edge, BoxRanks, CoveredCells, ImbOptions, Load, SolidParticle, StepBoxes};
use std::sync::Arc;

/// The particles at step `t` (on the 8 x 6 x 8 lattices of `tests.rs`): one on the edge where the
/// cuts at x = 4 and z = 4 meet, one across the periodic x faces, moving and turning.
pub(super) fn particles(t: u64) -> Vec<SolidParticle> {
    let t = t as f64;
    vec![
        SolidParticle {
            position: [4.0 + 0.05 * t, 4.02, 3.97 - 0.03 * t],
            radius: 1.8,
            velocity: [0.05, 0.0, -0.03],
            angular_velocity: [0.0, 0.01, 0.02],
        },
        SolidParticle {
            position: [0.3 - 0.04 * t, 2.0, 5.8],
            radius: 1.5,
            velocity: [-0.04, 0.01, 0.0],
            angular_velocity: [0.03, 0.0, 0.0],
        },
    ]
}

/// The loads of `steps` coupled steps (covered cells redone) and the fields after them, on one
/// lattice and cut into `blocks` on threads: the same bits.
fn check(setup: Setup, blocks: [usize; 3], steps: u64) {
    check_with(particles, setup, blocks, steps);
}

/// [`check`] with the particles of `particles` at each step; the bytes each rank sent rank 0 per
/// step for the loads (rank order).
fn check_with(
    particles: fn(u64) -> Vec<SolidParticle>,
    setup: Setup,
    blocks: [usize; 3],
    steps: u64,
) -> Vec<usize> {
    let gpu = Arc::new(Gpu::new().expect("a wgpu adapter (lavapipe in CI)"));
    let want = single(&gpu, particles, &setup, steps, CoveredCells::Redo);
    let have = on_blocks(&gpu, particles, &setup, blocks, steps, (CoveredCells::Redo, true));
    same_bits(&want, &have, &format!("blocks {blocks:?}"));
    have.sent
}

/// What `steps` coupled steps of `setup` from rest with the particles of `particles` at each
/// step give: rank 0's loads and the whole lattice's fields after each step, and the bytes each
/// rank sent rank 0 per step for the loads (rank order; none on one lattice).
pub(super) struct CoupledRun {
    pub loads: Vec<Vec<Load>>,
    pub fields: Vec<Vec<[f32; 4]>>,
    pub sent: Vec<usize>,
}

/// [`CoupledRun`] on one lattice, the covered cells taking their solid term the way `mode` says.
pub(super) fn single(
    gpu: &Arc<Gpu>,
    particles: fn(u64) -> Vec<SolidParticle>,
    setup: &Setup,
    steps: u64,
    mode: CoveredCells,
) -> CoupledRun {
    let options = Some(ImbOptions {
        covered_cells: mode,
        ..ImbOptions::default()
    });
    let mut one = GpuLattice::new(gpu.clone(), setup.clone(), Health::default(), options).unwrap();
    let (loads, fields) = (0..steps)
        .map(|t| (one.step_coupled(&particles(t)).unwrap(), one.fields().0))
        .unzip();
    CoupledRun {
        loads,
        fields,
        sent: Vec::new(),
    }
}

/// [`CoupledRun`] cut into `blocks` on threads, the covered cells taking their solid term the way
/// `mode` says, the halo exchange overlapped with the interior's update where `overlap` asks
/// (`block.overlaps()` checked against what the step does).
pub(super) fn on_blocks(
    gpu: &Arc<Gpu>,
    particles: fn(u64) -> Vec<SolidParticle>,
    setup: &Setup,
    blocks: [usize; 3],
    steps: u64,
    (mode, overlap): (CoveredCells, bool),
) -> CoupledRun {
    let options = Some(ImbOptions {
        covered_cells: mode,
        ..ImbOptions::default()
    });
    let periodic: [bool; 3] = std::array::from_fn(|a| setup.periodic(a));
    let all: Vec<_> = std::thread::scope(|s| {
        let handles: Vec<_> = ThreadRanks::world(blocks.iter().product())
            .into_iter()
            .enumerate()
            .map(|(rank, comm)| {
                let (gpu, setup) = (gpu.clone(), setup.clone());
                s.spawn(move || {
                    let d = Decomposition::new(setup.n, periodic, blocks, rank);
                    let mut block =
                        BlockLattice::with_coupling(gpu, setup, Health::default(), d, options).unwrap();
                    block.set_overlap(overlap);
                    assert_eq!(block.overlaps(), overlap, "{mode:?}: the exchange that runs");
                    let steps: Vec<(Vec<Load>, Vec<[f32; 4]>)> = (0..steps)
                        .map(|t| {
                            let mut out = Vec::new();
                            block
                                .step_coupled_with(&particles(t)[..], &mut out, |_, l| l, &comm)
                                .unwrap();
                            (out, block.own_fields(&comm).0)
                        })
                        .collect();
                    (steps, block.shares_per_step())
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let fields = (0..steps as usize)
        .map(|t| {
            let own: Vec<&[[f32; 4]]> = all.iter().map(|(s, _)| &s[t].1[..]).collect();
            put_together(setup, blocks, &own)
        })
        .collect();
    CoupledRun {
        loads: all[0].0.iter().map(|(l, _)| l.clone()).collect(),
        fields,
        sent: all.iter().map(|(_, s)| *s).collect(),
    }
}

/// The loads of every step, and the fields after each, are the same bits in `have` as in `want`
/// (the particles feel the fluid); `what` names the run.
pub(super) fn same_bits(want: &CoupledRun, have: &CoupledRun, what: &str) {
    assert!(
        want.loads.iter().flatten().any(|l| l.force != [0.0; 3]),
        "the particles feel the fluid"
    );
    for (t, (w, h)) in want.loads.iter().zip(&have.loads).enumerate() {
        assert_eq!(w, h, "{what}, step {t}: the loads differ");
    }
    for (t, (w, h)) in want.fields.iter().zip(&have.fields).enumerate() {
        let differ = (0..w.len()).filter(|&k| w[k] != h[k]).count();
        assert_eq!(differ, 0, "{what}, step {t}: {differ} cells' fields differ");
    }
}

/// Two and four blocks (an edge of the cuts, the periodic x faces between ranks); few, since
/// each block builds its kernels (seconds on lavapipe).
#[test]
fn a_coupled_lattice_cut_into_blocks_gives_the_single_lattices_loads_bit_for_bit() {
    check(walled(), [1, 1, 2], 4);
    check(periodic(), [2, 1, 2], 3);
}

/// The particles at step `t` on the 8 x 6 x 8 lattice cut into [2, 1, 2] blocks (x and z cut at
/// 4): three within one block each (ranks 3, 1 and 0), one across the x cut, one across the
/// periodic x faces and the z cut, one within rank 2's block; all barely moving.
fn alone_and_across(t: u64) -> Vec<SolidParticle> {
    let t = t as f64;
    let sphere = |position: [f64; 3], radius: f64| SolidParticle {
        position,
        radius,
        velocity: [0.01, -0.01, 0.005],
        angular_velocity: [0.0, 0.01, 0.02],
    };
    vec![
        sphere([6.0 + 0.01 * t, 3.0, 6.0], 1.2),
        sphere([5.9, 2.5 + 0.01 * t, 2.1], 1.2),
        sphere([2.0, 3.0, 2.0 - 0.01 * t], 1.2),
        sphere([4.0 + 0.02 * t, 3.0, 6.0], 1.5),
        sphere([0.2, 2.0, 4.0 - 0.02 * t], 1.5),
        sphere([2.1, 2.9, 6.0], 1.2),
    ]
}

/// Particles whose box one rank other than 0 holds alone (their loads reduced there and sent)
/// beside particles across the cuts (their covered cells gathered): rank 0's loads are the single
/// lattice's bit for bit, and each rank sends less than the 16 bytes per cell of every box it
/// sent before.
#[test]
fn particles_within_one_block_and_across_the_cuts_give_the_single_lattices_loads_bit_for_bit() {
    let setup = periodic();
    let blocks = [2, 1, 2];
    let options = ImbOptions {
        covered_cells: CoveredCells::Redo,
        ..ImbOptions::default()
    };
    let d = Decomposition::new(setup.n, [true; 3], blocks, 0);
    let block = block_options(options, &d, &setup).block.unwrap();
    let ranks: Vec<BoxRanks> = StepBoxes::of(&alone_and_across(0)[..], block).ranks().collect();
    use BoxRanks::{One, Several};
    assert_eq!(ranks, [One(3), One(1), One(0), Several, Several, One(2)]);
    let sent = check_with(alone_and_across, setup, blocks, 4);
    let every_box: usize = alone_and_across(0)
        .iter()
        .map(|p| 16 * (box_edge(p.radius) as usize).pow(3))
        .sum();
    assert_eq!(sent[0], 0, "rank 0 sends nothing");
    for (rank, &bytes) in sent.iter().enumerate().skip(1) {
        assert!(
            bytes > 0 && bytes < every_box / 4,
            "rank {rank}: {bytes} bytes per step"
        );
    }
}
