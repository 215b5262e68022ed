//! `lbm-server bench` on several ranks (under mpirun or srun, or `--thread-ranks N`: threads of
//! one process): the lattice cut into blocks, one per rank, stepped with the halo exchange; MLUPS
//! per rank and in total, the halo's bytes per step and the exchange's share of the step.

use super::{parse_faces, parse_grid, parse_operator, BenchArgs};
use crate::lbm::geometry::Setup;
use crate::lbm::gpu::{Gpu, Health};
use crate::parallel::{all, choose_blocks, BlockLattice, Communicator, Decomposition, ThreadRanks};
use std::sync::Arc;
use std::time::Instant;

/// One rank's measurement: its device, own cells, best round's time [s] and exchange time [s].
struct RankTime {
    device: String,
    cells: usize,
    seconds: f64,
    exchange: f64,
    halo_bytes: usize,
}

/// Times `args.steps` steps of the grid cut over the ranks of `comm`, best of `args.rounds`
/// rounds (each ended when every rank is done), and prints, at rank 0, each rank's and the total.
pub fn run(args: &BenchArgs, comm: &dyn Communicator) -> Result<(), String> {
    let n = parse_grid(&args.grid)?;
    let faces = parse_faces(&args.faces)?;
    let tau = 0.6;
    let setup = Setup::new(n, faces, tau, parse_operator(&args.operator, tau)?);
    let periodic: [bool; 3] = std::array::from_fn(|a| setup.periodic(a));
    let blocks = choose_blocks(n, periodic, comm.size())?;
    let started = start(&setup, blocks, comm);
    if !all(comm, started.is_ok()) {
        return Err(started
            .err()
            .unwrap_or_else(|| "another rank failed to start".into()));
    }
    let (gpu, mut lattice) = started.expect("started");
    lattice.step(20, comm);
    let _ = lattice.health(comm);
    let mut best = (f64::INFINITY, 0.0);
    for _ in 0..args.rounds.max(1) {
        comm.min(0);
        let (t0, x0) = (Instant::now(), lattice.halo_cost().1);
        lattice.step(args.steps, comm);
        // The health check reads the device's status: the steps are done.
        let _ = lattice.health(comm);
        let round = (t0.elapsed().as_secs_f64(), lattice.halo_cost().1 - x0);
        if round.0 < best.0 {
            best = round;
        }
    }
    let mine = RankTime {
        device: format!("{}: {}", comm.host(), gpu.adapter.name),
        cells: lattice.decomposition.size.iter().product(),
        seconds: best.0,
        exchange: best.1,
        halo_bytes: lattice.halo_cost().0,
    };
    let rows = gather(comm, &mine);
    if comm.rank() == 0 {
        print(args, n, blocks, &rows);
    }
    Ok(())
}

/// [`run`] on `--thread-ranks N` threads of this process, one rank each; the first rank's error.
pub fn on_threads(args: &BenchArgs) -> Result<(), String> {
    let n = args.thread_ranks.unwrap_or(1);
    if n == 0 {
        return Err("--thread-ranks = 0: must be at least 1".into());
    }
    let results: Vec<Result<(), String>> = std::thread::scope(|s| {
        let handles: Vec<_> = ThreadRanks::world(n)
            .into_iter()
            .map(|comm| s.spawn(move || run(args, &comm)))
            .collect();
        handles
            .into_iter()
            .map(|h| {
                h.join()
                    .unwrap_or_else(|_| Err("a rank's thread panicked".into()))
            })
            .collect()
    });
    results.into_iter().collect()
}

fn start(
    setup: &Setup,
    blocks: [usize; 3],
    comm: &dyn Communicator,
) -> Result<(Arc<Gpu>, BlockLattice), String> {
    let gpu = Arc::new(Gpu::for_local_rank(comm.local_rank())?);
    let periodic: [bool; 3] = std::array::from_fn(|a| setup.periodic(a));
    let d = Decomposition::new(setup.n, periodic, blocks, comm.rank());
    let lattice = BlockLattice::new(gpu.clone(), setup.clone(), Health::default(), d)?;
    Ok((gpu, lattice))
}

/// Every rank's measurement at rank 0, in rank order.
fn gather(comm: &dyn Communicator, mine: &RankTime) -> Vec<RankTime> {
    let line = format!(
        "{}\t{}\t{}\t{}\t{}",
        mine.device, mine.cells, mine.seconds, mine.exchange, mine.halo_bytes
    );
    comm.gather(line.as_bytes())
        .iter()
        .map(|r| {
            let text = String::from_utf8_lossy(r);
            let f: Vec<&str> = text.split('\t').collect();
            RankTime {
                device: f[0].to_string(),
                cells: f[1].parse().unwrap_or(0),
                seconds: f[2].parse().unwrap_or(f64::NAN),
                exchange: f[3].parse().unwrap_or(f64::NAN),
                halo_bytes: f[4].parse().unwrap_or(0),
            }
        })
        .collect()
}

fn print(args: &BenchArgs, n: [usize; 3], blocks: [usize; 3], rows: &[RankTime]) {
    let steps = args.steps as f64;
    println!(
        "grid {}x{}x{} ({}, {}) on {} ranks in {}x{}x{} blocks, {} steps, best of {} rounds",
        n[0],
        n[1],
        n[2],
        args.operator,
        args.faces,
        rows.len(),
        blocks[0],
        blocks[1],
        blocks[2],
        args.steps,
        args.rounds.max(1)
    );
    println!("rank  cells      MLUPS   halo bytes/step  exchange share  device");
    for (rank, r) in rows.iter().enumerate() {
        println!(
            "{rank:>4}  {:>9}  {:>7.2}  {:>15}  {:>13.1}%  {}",
            r.cells,
            r.cells as f64 * steps / r.seconds / 1e6,
            r.halo_bytes,
            100.0 * r.exchange / r.seconds,
            r.device
        );
    }
    let cells: usize = rows.iter().map(|r| r.cells).sum();
    let slowest = rows.iter().map(|r| r.seconds).fold(0.0, f64::max);
    let bytes: usize = rows.iter().map(|r| r.halo_bytes).sum();
    let share = rows.iter().map(|r| r.exchange / r.seconds).sum::<f64>() / rows.len() as f64;
    println!(
        "total {cells:>9}  {:>7.2} MLUPS, halo {bytes} bytes per step, exchange {:.1}% of the step (mean over ranks)",
        cells as f64 * steps / slowest / 1e6,
        100.0 * share
    );
}
