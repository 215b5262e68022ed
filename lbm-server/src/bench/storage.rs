//! `bench --storage fp32,fp16s,fp16c`: the same grid with each storage of the populations
//! (`lattice.storage`), timed in rounds alternating between them (with `--per-cell`, each with the
//! quads' and the per-cell kernel), with the bytes per cell each keeps on the device and moves
//! per step.

use super::{best, list, BenchArgs};
use crate::lbm::geometry::Setup;
use crate::lbm::gpu::{Gpu, GpuLattice, Health};
use crate::lbm::kernel::Kernel;
use crate::lbm::storage::Storage;
use std::sync::Arc;
use std::time::Instant;

/// Device bytes per cell besides the populations in a fluid run: flags (4), fields (16), the
/// health check's kept copy of the fields (16), a cell-list entry (4).
pub const OTHER_BYTES_PER_CELL: usize = 4 + 16 + 16 + 4;

/// Bytes per cell a lattice of `storage` keeps on the device in a fluid run.
pub fn device_bytes_per_cell(storage: Storage) -> usize {
    19 * storage.bytes() + OTHER_BYTES_PER_CELL
}

/// Bytes moved per cell per step: 19 populations read and written, a 4-byte cell-list entry.
pub fn step_bytes_per_cell(storage: Storage) -> usize {
    19 * storage.bytes() * 2 + 4
}

/// Parses `--storage` (names separated by commas).
pub fn parse_storages(names: &[String]) -> Result<Vec<Storage>, String> {
    names
        .iter()
        .map(|name| {
            Storage::named(name).ok_or_else(|| format!("--storage = {name:?}: expected fp32, fp16s or fp16c"))
        })
        .collect()
}

/// Times `setup` with each of `storages` (rounds alternating; with `--per-cell` each storage with
/// both kernels) and prints a line per storage and kernel: MLUPS, bytes per cell, the fraction of
/// the copy `bandwidth`'s roofline, the ratio to the first storage of its kernel and, for the
/// per-cell kernel, to the quads' of its storage.
pub fn print_storages(
    gpu: &Arc<Gpu>,
    setup: &Setup,
    storages: &[Storage],
    args: &BenchArgs,
    bandwidth: f64,
) -> Result<(), String> {
    let kernels: &[Kernel] = if args.per_cell {
        &Kernel::ALL
    } else {
        &[Kernel::Quads]
    };
    let cases: Vec<(Storage, Kernel)> = kernels
        .iter()
        .flat_map(|&kernel| storages.iter().map(move |&storage| (storage, kernel)))
        .collect();
    let rounds = time_cases(gpu, setup, &cases, args)?;
    let best_of = |case: (Storage, Kernel)| best(&rounds[cases.iter().position(|&c| c == case).unwrap()]);
    for (&(storage, kernel), times) in cases.iter().zip(&rounds) {
        let mlups = best(times);
        let moved = step_bytes_per_cell(storage);
        let roofline = bandwidth / moved as f64 / 1e6;
        let against_quads = match kernel {
            Kernel::Cells => format!(", {:.2}x quads", mlups / best_of((storage, Kernel::Quads))),
            Kernel::Quads => String::new(),
        };
        println!(
            "storage {:<6} {:<6}{mlups:.1} MLUPS (best round; rounds: {}), {:.2}x {}{against_quads}; {} bytes/cell on the \
             device ({} populations), {moved} bytes/cell/step, {:.1}% of its roofline",
            storage.name(),
            kernel.name(),
            list(times),
            mlups / best_of((storages[0], kernel)),
            storages[0].name(),
            device_bytes_per_cell(storage),
            19 * storage.bytes(),
            100.0 * mlups / roofline
        );
    }
    Ok(())
}

/// MLUPS of each round of each case (a storage and a kernel), the cases alternating in each round
/// after 20 warm-up steps each.
fn time_cases(
    gpu: &Arc<Gpu>,
    setup: &Setup,
    cases: &[(Storage, Kernel)],
    args: &BenchArgs,
) -> Result<Vec<Vec<f64>>, String> {
    let mut lattices = cases
        .iter()
        .map(|&(storage, kernel)| {
            let setup = Setup {
                storage,
                kernel,
                ..setup.clone()
            };
            GpuLattice::new(gpu.clone(), setup, Health::default(), None)
        })
        .collect::<Result<Vec<_>, _>>()?;
    for lattice in &mut lattices {
        lattice.step(20);
    }
    gpu.wait();
    let cells = setup.cells() as f64;
    let mut rounds = vec![Vec::new(); cases.len()];
    for _ in 0..args.rounds.max(1) {
        for (lattice, times) in lattices.iter_mut().zip(&mut rounds) {
            let start = Instant::now();
            lattice.step(args.steps);
            gpu.wait();
            times.push(cells * args.steps as f64 / start.elapsed().as_secs_f64() / 1e6);
        }
    }
    Ok(rounds)
}
