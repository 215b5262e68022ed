//! A decomposed lattice against the same lattice on one rank, bit for bit: ranks as threads of
//! one process ([`ThreadRanks`]), on one device, so that these run without MPI.

use super::{BlockLattice, Communicator, Decomposition, ThreadRanks};
use crate::lbm::geometry::{Cell, Face, Operator, Setup};
use crate::lbm::gpu::{Gpu, GpuLattice, Health};
use crate::lbm::kernel::Kernel;
use crate::lbm::mrt::Rates;
use crate::lbm::storage::Storage;
use std::sync::Arc;

/// Runs `steps` steps of `setup` from rest on one lattice, and cut into `blocks` on threads;
/// checks the fields after each of the last two steps (both AA parities) bit for bit, the
/// blocks' own fields put together into the whole lattice.
fn check(setup: Setup, blocks: [usize; 3], steps: u64) {
    let gpu = Arc::new(Gpu::new().expect("a wgpu adapter (lavapipe in CI)"));
    let mut one = GpuLattice::new(gpu.clone(), setup.clone(), Health::default(), None).unwrap();
    let mut expected = Vec::new();
    one.step(steps - 1);
    expected.push(one.fields().0);
    one.step(1);
    expected.push(one.fields().0);
    let got = on_ranks(&gpu, &setup, blocks, |block, comm| {
        block.step(steps - 1, comm);
        let first = block.own_fields(comm).0;
        block.step(1, comm);
        vec![first, block.own_fields(comm).0]
    });
    let whole = |parity: usize| {
        let pieces: Vec<&[[f32; 4]]> = got.iter().map(|p| &p[parity][..]).collect();
        put_together(&setup, blocks, &pieces)
    };
    let got = [whole(0), whole(1)];
    for (parity, (want, have)) in expected.iter().zip(&got).enumerate() {
        let differ: Vec<usize> = (0..want.len()).filter(|&k| want[k] != have[k]).collect();
        assert!(
            differ.is_empty(),
            "blocks {blocks:?}, step {}: {} cells differ, first {:?}: {:?} vs {:?}",
            steps - 1 + parity as u64,
            differ.len(),
            setup.coords(differ[0]),
            want[differ[0]],
            have[differ[0]]
        );
    }
}

/// The whole lattice `setup` from every rank's own fields (`pieces`, rank order) of the
/// decomposition into `blocks` (NaN where none gave a cell).
pub(super) fn put_together(setup: &Setup, blocks: [usize; 3], pieces: &[&[[f32; 4]]]) -> Vec<[f32; 4]> {
    let periodic: [bool; 3] = std::array::from_fn(|a| setup.periodic(a));
    let mut whole = vec![[f32::NAN; 4]; setup.cells()];
    for (rank, piece) in pieces.iter().enumerate() {
        let d = Decomposition::new(setup.n, periodic, blocks, rank);
        for (&(_, g), v) in d.own_cells().iter().zip(piece.iter()) {
            whole[g] = *v;
        }
    }
    whole
}

/// Walls, a moving wall, solid cells (some on the cuts), a body force, TRT.
pub(super) fn walled() -> Setup {
    crate::lbm::tests::trt_walls_and_solids([8, 6, 8])
}

/// Periodic, a body force, MRT.
pub(super) fn periodic() -> Setup {
    periodic_of([8, 6, 8])
}

/// Periodic, a body force, MRT, `n` cells.
pub(super) fn periodic_of(n: [usize; 3]) -> Setup {
    let rates = Rates::dhumieres(1.0 / 0.8);
    let mut setup = Setup::new(n, [Face::Periodic; 6], 0.8, Operator::Mrt { rates });
    setup.force = [2e-4, 1e-4, -1e-4];
    setup
}

#[test]
fn a_walled_lattice_cut_along_one_axis_is_the_single_lattice_bit_for_bit() {
    check(walled(), [1, 1, 2], 6);
    check(walled(), [2, 1, 1], 6);
}

#[test]
fn a_periodic_lattice_cut_along_one_axis_is_the_single_lattice_bit_for_bit() {
    check(periodic(), [1, 2, 1], 6);
}

#[test]
fn lattices_cut_along_two_and_three_axes_are_the_single_lattice_bit_for_bit() {
    check(walled(), [2, 3, 1], 6);
    check(periodic(), [2, 2, 2], 5);
}

/// 16-bit storage: the halo's messages carry the stored 16 bits, two populations to a word (the
/// last word of an odd layer half used): the same bits as one lattice, in half the bytes.
#[test]
fn sixteen_bit_storages_cut_are_the_single_lattice_bit_for_bit_in_half_the_bytes() {
    let fp16 = |storage: Storage, setup: Setup| Setup { storage, ..setup };
    check(fp16(Storage::Fp16c, walled()), [2, 1, 1], 6);
    check(fp16(Storage::Fp16s, periodic_of([7, 6, 6])), [1, 2, 2], 5);
    let setup = periodic_of([7, 6, 6]);
    let bytes = |storage: Storage| {
        let gpu = Arc::new(Gpu::new().expect("a wgpu adapter (lavapipe in CI)"));
        on_ranks(&gpu, &fp16(storage, setup.clone()), [1, 2, 2], |block, _| {
            block.halo_cost().0
        })
    };
    let (words16, words32) = (bytes(Storage::Fp16s), bytes(Storage::Fp32));
    for (rank, (b16, b32)) in words16.iter().zip(&words32).enumerate() {
        // Four cut faces, each layer's last word perhaps half used.
        assert!(
            2 * b16 >= *b32 && 2 * b16 <= b32 + 4 * 8,
            "rank {rank}: {b16} bytes per step in FP16, {b32} in FP32"
        );
    }
}

/// Every rank's populations (its block's lattice, ghost layers included) after `steps` steps of
/// `setup` from rest cut into `blocks` on threads, the halo exchange overlapped with the
/// interior's update (`overlap`) or after each whole step.
fn block_populations(setup: &Setup, blocks: [usize; 3], steps: u64, overlap: bool) -> Vec<Vec<Cell>> {
    let gpu = Arc::new(Gpu::new().expect("a wgpu adapter (lavapipe in CI)"));
    on_ranks(&gpu, setup, blocks, |block, comm| {
        block.set_overlap(overlap);
        assert_eq!(block.overlaps(), overlap, "the exchange asked for");
        block.step(steps, comm);
        block.lattice.populations()
    })
}

/// `run(block, rank)` on each rank of `setup` from rest cut into `blocks`, the ranks threads on
/// `gpu`; the results in rank order.
fn on_ranks<T: Send>(
    gpu: &Arc<Gpu>,
    setup: &Setup,
    blocks: [usize; 3],
    run: impl Fn(&mut BlockLattice, &ThreadRanks) -> T + Sync,
) -> Vec<T> {
    let periodic: [bool; 3] = std::array::from_fn(|a| setup.periodic(a));
    let run = &run;
    std::thread::scope(|s| {
        let handles: Vec<_> = ThreadRanks::world(blocks.iter().product())
            .into_iter()
            .map(|comm| {
                let (gpu, setup) = (gpu.clone(), setup.clone());
                s.spawn(move || {
                    let d = Decomposition::new(setup.n, periodic, blocks, comm.rank());
                    let mut block = BlockLattice::new(gpu, setup, Health::default(), d).unwrap();
                    run(&mut block, &comm)
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    })
}

/// The overlapped exchange (the step split into the shell and the interior's parts) leaves every
/// population of every block, ghost layers included, as the exposed exchange after the whole
/// step does: walls, a moving wall during the faces' ramp, solid cells, a body force, cuts along
/// one, two and three axes, the quads' kernels, the per-cell kernel and 16-bit storage, after
/// an even and an odd number of steps.
#[test]
fn the_overlapped_exchange_gives_the_exposed_exchanges_bits() {
    let mut walled = crate::lbm::tests::trt_walls_and_solids([16, 12, 12]);
    walled.ramp_steps = 4.0;
    let setups = [
        (walled.clone(), [2, 1, 1], 5),
        (walled.clone(), [2, 2, 1], 6),
        (
            Setup {
                kernel: Kernel::Cells,
                ..walled.clone()
            },
            [1, 2, 2],
            5,
        ),
        (
            Setup {
                storage: Storage::Fp16s,
                ..periodic_of([16, 12, 12])
            },
            [2, 2, 2],
            6,
        ),
    ];
    for (setup, blocks, steps) in setups {
        let overlapped = block_populations(&setup, blocks, steps, true);
        let exposed = block_populations(&setup, blocks, steps, false);
        for (rank, (a, b)) in overlapped.iter().zip(&exposed).enumerate() {
            let differ = a.iter().zip(b).filter(|(p, q)| p != q).count();
            assert!(
                differ == 0,
                "{:?} {:?} blocks {blocks:?}, rank {rank}: {differ} cells differ",
                setup.kernel,
                setup.storage
            );
        }
    }
}
