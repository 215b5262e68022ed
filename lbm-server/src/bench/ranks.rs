//! `lbm-server bench` on several ranks (under mpirun or srun, or `--thread-ranks N`: threads of
//! one process): the lattice cut into blocks, one per rank, stepped with the halo exchange; MLUPS
//! per rank and in total, the halo's bytes per step and the exchange's share of the step, and per
//! way of exchanging (`--exchange`: overlapped, exposed) the exposed exchange against the blocks
//! stepped without it; one storage of the populations (`--storage`, fp32 by default: the halo's
//! messages carry its bits). With `--particles N` the steps are coupled (`coupled_ranks.rs`).

use super::coupled_ranks::{coupling, Coupled};
use super::{parse_faces, parse_grid, parse_operator, BenchArgs};
use crate::lbm::geometry::Setup;
use crate::lbm::gpu::{Gpu, Health};
use crate::lbm::imb::ImbOptions;
use crate::lbm::storage::Storage;
use crate::parallel::{all, choose_blocks, BlockLattice, Communicator, Decomposition, ThreadRanks};
use std::sync::Arc;
use std::time::Instant;

/// One rank's measurement: its device, own cells, halo bytes per step, and for each way of
/// stepping timed (`Stepping`) its best round's time [s] and the host's exchange time in it [s].
struct RankTime {
    device: String,
    cells: usize,
    halo_bytes: usize,
    times: Vec<(f64, f64)>,
}

/// A way of stepping the blocks in the bench.
#[derive(Clone, Copy, PartialEq)]
pub(super) enum Stepping {
    /// The halo exchange overlapped with the interior's update.
    Overlapped,
    /// The halo exchange after the whole step.
    Exposed,
    /// No exchange, a submission per step: the compute alone (its results are not the run's;
    /// coupled, each block's loads read from its own pairs, none gathered).
    Alone,
}

impl Stepping {
    pub(super) fn name(self) -> &'static str {
        match self {
            Stepping::Overlapped => "overlapped",
            Stepping::Exposed => "exposed",
            Stepping::Alone => "without the exchange",
        }
    }
}

/// The ways of stepping `--exchange` asks to time, then the compute alone.
fn steppings(exchange: &str) -> Result<Vec<Stepping>, String> {
    let mut timed = match exchange {
        "overlapped" => vec![Stepping::Overlapped],
        "exposed" => vec![Stepping::Exposed],
        "both" => vec![Stepping::Overlapped, Stepping::Exposed],
        other => {
            return Err(format!(
                "--exchange = {other:?}: expected overlapped, exposed or both"
            ))
        }
    };
    timed.push(Stepping::Alone);
    Ok(timed)
}

/// Times `args.steps` steps of the grid cut over the ranks of `comm` each way `--exchange` asks
/// for and without the exchange, in alternating rounds (each ended when every rank is done), best
/// of `args.rounds` each, and prints, at rank 0, each rank's and the total.
pub fn run(args: &BenchArgs, comm: &dyn Communicator) -> Result<(), String> {
    let n = parse_grid(&args.grid)?;
    let faces = parse_faces(&args.faces)?;
    let modes = steppings(&args.exchange)?;
    let tau = 0.6;
    let setup = Setup {
        storage: one_storage(&args.storage)?,
        ..Setup::new(n, faces, tau, parse_operator(&args.operator, tau)?)
    };
    let periodic: [bool; 3] = std::array::from_fn(|a| setup.periodic(a));
    let blocks = choose_blocks(n, periodic, comm.size())?;
    let coupled = coupling(args, n)?;
    let started = start(&setup, blocks, comm, coupled.as_ref().map(|c| c.options));
    if !all(comm, started.is_ok()) {
        return Err(started
            .err()
            .unwrap_or_else(|| "another rank failed to start".into()));
    }
    let (gpu, mut lattice) = started.expect("started");
    step(&mut lattice, comm, (Stepping::Exposed, coupled.as_ref()), 20)?;
    let _ = lattice.health(comm);
    let mine = RankTime {
        device: format!("{}: {}", comm.host(), gpu.adapter.name),
        cells: lattice.decomposition.size.iter().product(),
        halo_bytes: lattice.halo_cost().0,
        times: time_rounds(args, &mut lattice, comm, (&modes, coupled.as_ref()))?,
    };
    let rows = gather(comm, &mine);
    if comm.rank() == 0 {
        print(args, &setup, blocks, &rows, &modes);
        if let Some(c) = &coupled {
            c.print();
        }
    }
    Ok(())
}

/// The storage `--storage` names (fp32 where it names none): one on ranks.
fn one_storage(names: &[String]) -> Result<Storage, String> {
    match super::storage::parse_storages(names)?[..] {
        [] => Ok(Storage::Fp32),
        [one] => Ok(one),
        _ => Err(format!(
            "--storage = {:?}: one storage on several ranks",
            names.join(",")
        )),
    }
}

/// Per way of stepping in `modes`, its best round of `args.rounds` (the ways alternating): time
/// [s] and the host's exchange time in it [s]; coupled steps where `coupled` says.
fn time_rounds(
    args: &BenchArgs,
    lattice: &mut BlockLattice,
    comm: &dyn Communicator,
    (modes, coupled): (&[Stepping], Option<&Coupled>),
) -> Result<Vec<(f64, f64)>, String> {
    let mut best = vec![(f64::INFINITY, 0.0); modes.len()];
    for _ in 0..args.rounds.max(1) {
        for (m, &mode) in modes.iter().enumerate() {
            comm.min(0);
            let (t0, x0) = (Instant::now(), lattice.halo_cost().1);
            step(lattice, comm, (mode, coupled), args.steps)?;
            // The health check reads the device's status: the steps are done.
            let _ = lattice.health(comm);
            let round = (t0.elapsed().as_secs_f64(), lattice.halo_cost().1 - x0);
            if round.0 < best[m].0 {
                best[m] = round;
            }
        }
    }
    Ok(best)
}

/// `steps` steps of `lattice` the way `mode` says, coupled where `coupled` says.
pub(super) fn step(
    lattice: &mut BlockLattice,
    comm: &dyn Communicator,
    (mode, coupled): (Stepping, Option<&Coupled>),
    steps: u64,
) -> Result<(), String> {
    lattice.set_overlap(mode == Stepping::Overlapped);
    if let Some(c) = coupled {
        return c.step(lattice, comm, mode == Stepping::Alone, steps);
    }
    if mode == Stepping::Alone {
        for _ in 0..steps {
            lattice.lattice.step(1);
        }
        return Ok(());
    }
    lattice.step(steps, comm);
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

/// This rank's device and block of `setup` cut into `blocks`, coupled with `options` where given.
fn start(
    setup: &Setup,
    blocks: [usize; 3],
    comm: &dyn Communicator,
    options: Option<ImbOptions>,
) -> Result<(Arc<Gpu>, BlockLattice), String> {
    let gpu = Arc::new(Gpu::for_local_rank(comm.local_rank())?);
    let periodic: [bool; 3] = std::array::from_fn(|a| setup.periodic(a));
    let d = Decomposition::new(setup.n, periodic, blocks, comm.rank());
    let lattice = BlockLattice::with_coupling(gpu.clone(), setup.clone(), Health::default(), d, options)?;
    Ok((gpu, lattice))
}

/// Every rank's measurement at rank 0, in rank order.
fn gather(comm: &dyn Communicator, mine: &RankTime) -> Vec<RankTime> {
    let times: Vec<String> = mine.times.iter().map(|(s, x)| format!("{s}\t{x}")).collect();
    let line = format!(
        "{}\t{}\t{}\t{}",
        mine.device,
        mine.cells,
        mine.halo_bytes,
        times.join("\t")
    );
    comm.gather(line.as_bytes())
        .iter()
        .map(|r| {
            let text = String::from_utf8_lossy(r);
            let f: Vec<&str> = text.split('\t').collect();
            let number = |v: &str| v.parse().unwrap_or(f64::NAN);
            RankTime {
                device: f[0].to_string(),
                cells: f[1].parse().unwrap_or(0),
                halo_bytes: f[2].parse().unwrap_or(0),
                times: f[3..].chunks(2).map(|t| (number(t[0]), number(t[1]))).collect(),
            }
        })
        .collect()
}

fn print(args: &BenchArgs, setup: &Setup, blocks: [usize; 3], rows: &[RankTime], modes: &[Stepping]) {
    let (steps, n) = (args.steps as f64, setup.n);
    println!(
        "grid {}x{}x{} ({}, {}, {}) on {} ranks in {}x{}x{} blocks, {} steps, best of {} rounds, exchange {}",
        n[0],
        n[1],
        n[2],
        args.operator,
        args.faces,
        setup.storage,
        rows.len(),
        blocks[0],
        blocks[1],
        blocks[2],
        args.steps,
        args.rounds.max(1),
        modes[0].name()
    );
    println!("rank  cells      MLUPS   halo bytes/step  exchange share  device");
    for (rank, r) in rows.iter().enumerate() {
        let (seconds, exchange) = r.times[0];
        println!(
            "{rank:>4}  {:>9}  {:>7.2}  {:>15}  {:>13.1}%  {}",
            r.cells,
            r.cells as f64 * steps / seconds / 1e6,
            r.halo_bytes,
            100.0 * exchange / seconds,
            r.device
        );
    }
    let cells: usize = rows.iter().map(|r| r.cells).sum();
    let bytes: usize = rows.iter().map(|r| r.halo_bytes).sum();
    let slowest = |m: usize| rows.iter().map(|r| r.times[m].0).fold(0.0, f64::max);
    let share = |m: usize| rows.iter().map(|r| r.times[m].1 / r.times[m].0).sum::<f64>() / rows.len() as f64;
    println!(
        "total {cells:>9}  {:>7.2} MLUPS, halo {bytes} bytes per step, exchange {:.1}% of the step (mean over ranks)",
        cells as f64 * steps / slowest(0) / 1e6,
        100.0 * share(0)
    );
    print_exchanges(steps, rows, modes);
}

/// Per way of exchanging timed, its time per step against the compute alone's (the last of
/// `modes`), the exposed exchange (their difference) and the host's share of the step in it.
fn print_exchanges(steps: f64, rows: &[RankTime], modes: &[Stepping]) {
    let slowest = |m: usize| rows.iter().map(|r| r.times[m].0).fold(0.0, f64::max);
    let share = |m: usize| rows.iter().map(|r| r.times[m].1 / r.times[m].0).sum::<f64>() / rows.len() as f64;
    let alone = slowest(modes.len() - 1) / steps;
    for (m, mode) in modes.iter().enumerate().take(modes.len() - 1) {
        let per_step = slowest(m) / steps;
        println!(
            "exchange {}: {:.3} ms per step against {:.3} ms without it: exposed {:.3} ms per step \
             ({:.1}%); the host in the exchange {:.1}% of the step",
            mode.name(),
            1e3 * per_step,
            1e3 * alone,
            1e3 * (per_step - alone),
            100.0 * (per_step - alone) / per_step,
            100.0 * share(m)
        );
    }
}
