//! `lbm-server bench`: lattice updates per second against this device's memory bandwidth.

mod coupled;
mod coupled_ranks;
mod naive;
mod paired;
mod ranks;
mod storage;

use crate::lbm::geometry::{Face, Operator, Setup};
use crate::lbm::gpu::{Gpu, GpuLattice, Health};
use crate::lbm::kernel::Kernel;
use crate::lbm::mrt::Rates;
use coupled::Sweep;
use naive::Naive;
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Instant;

/// Bytes moved per cell per step: 19 populations read and written in f32, plus at most one 4-byte
/// cell-list entry (one per four cells for quads).
pub const BYTES_PER_CELL: f64 = 19.0 * 4.0 * 2.0 + 4.0;

#[derive(clap::Args)]
pub struct BenchArgs {
    /// Grid size NXxNYxNZ.
    #[arg(long, default_value = "64x64x64")]
    grid: String,
    /// Timed steps (after 20 warm-up steps).
    #[arg(long, default_value_t = 200)]
    steps: u64,
    /// Collision operator: bgk, trt or mrt.
    #[arg(long, default_value = "bgk")]
    operator: String,
    /// Also run coupled steps with these particle counts (e.g. 1,8,64,512,4096,32768): spheres of
    /// 4 cells diameter on a regular lattice, immersed moving boundary; MLUPS and ratio to LBM-only,
    /// and CPU time per step against as many LBM-only steps timed in alternating blocks beside them.
    /// On several ranks the steps are coupled, with the first count and the first way of
    /// --covered-cells (the loads gathered at rank 0 as in a run).
    #[arg(long, value_delimiter = ',')]
    particles: Vec<usize>,
    /// With --particles: also time each pass of the coupled step on its own (each submitted and
    /// waited for: the round trip is in every pass), mean over the timed steps; and, where the
    /// device has timestamps, each pass by the device's clock in steps not split.
    #[arg(long)]
    passes: bool,
    /// With --particles: where the covered cells get their solid term: auto (redo: the bench's
    /// spheres are sparse), fused, redo, skip, both (redo and fused) or all three.
    #[arg(long, default_value = "auto")]
    covered_cells: String,
    /// With --particles: the host waits this long (ms) after each coupled step's loads are back,
    /// as for a DEM process's step, before the next step (0: not at all). With the covered cells
    /// redone or skipped the fluid kernels run meanwhile; the LBM-only lockstep row waits as long.
    #[arg(long, default_value_t = 0.0)]
    dem_ms: f64,
    /// The grid's faces: periodic (every cell an interior or wrapping one) or walls (a closed box,
    /// as a settling sphere's or a bed's: the cells beside the walls take the general kernel).
    #[arg(long, default_value = "periodic")]
    faces: String,
    /// Also time the LBM-only step with the per-cell kernel (`lattice.kernel = "cells"`: a thread
    /// per cell, one dispatch, no cell list, as the naive kernel) against the quads' kernels of
    /// the same run; with --storage, each storage with both kernels.
    #[arg(long)]
    per_cell: bool,
    /// Also time the same grid with each of these storages of the populations (fp32, fp16s,
    /// fp16c: `lattice.storage`), in rounds alternating between them, with the bytes per cell
    /// (with --per-cell, each with the quads' and the per-cell kernel).
    #[arg(long, value_delimiter = ',')]
    storage: Vec<String>,
    /// Cut the grid over N ranks that are threads of this one process (no MPI), each with its own
    /// handle on the device of its rank number (one GPU: ranks sharing it), the halo exchanged
    /// through the host as between MPI ranks: MLUPS per rank and in total, halo bytes per step and
    /// the exchange's share, as under mpirun. 1 is the same code on one block (the baseline).
    #[arg(long)]
    thread_ranks: Option<usize>,
    /// On several ranks: the halo exchange timed, "overlapped" with the interior's update (the
    /// default, as `[parallel] overlap`), "exposed" (after the whole step) or "both", in
    /// alternating rounds; each round also steps the blocks without the exchange, the compute
    /// alone, so that the exposed exchange per step is the difference.
    #[arg(long, default_value = "overlapped")]
    exchange: String,
    /// Timed rounds, ours and the naive kernel alternating (best round reported).
    #[arg(long, default_value_t = 3)]
    rounds: u32,
    /// Whether to time the naive reference kernel: "both" (ours and it), "none" (ours alone) or
    /// "only" (it alone; for instruction counts under a profiler).
    #[arg(long, default_value = "both", hide = true)]
    reference: String,
}

/// Parses "NXxNYxNZ".
pub fn parse_grid(text: &str) -> Result<[usize; 3], String> {
    let parts: Vec<usize> = text
        .split('x')
        .map(|p| p.trim().parse::<usize>())
        .collect::<Result<_, _>>()
        .map_err(|_| {
            format!("--grid = {text:?}: expected NXxNYxNZ with positive integers, e.g. 128x128x128")
        })?;
    match parts[..] {
        [x, y, z] if x > 0 && y > 0 && z > 0 => Ok([x, y, z]),
        _ => Err(format!(
            "--grid = {text:?}: expected NXxNYxNZ with positive integers, e.g. 128x128x128"
        )),
    }
}

/// Parses an operator name; `tau` sets MRT's shear rate.
pub fn parse_operator(name: &str, tau: f64) -> Result<Operator, String> {
    match name {
        "bgk" => Ok(Operator::Bgk),
        "trt" => Ok(Operator::Trt { magic: 3.0 / 16.0 }),
        "mrt" => Ok(Operator::Mrt {
            rates: Rates::dhumieres(1.0 / tau),
        }),
        other => Err(format!("--operator = {other:?}: expected bgk, trt or mrt")),
    }
}

pub fn main(args: BenchArgs) -> ExitCode {
    // Under a launcher (mpirun, srun) the bench is the ranks', one rank included (the baseline of
    // a scaling series).
    let ranks = crate::parallel::start();
    let result = match &ranks {
        Ok(_) if args.thread_ranks.is_some() && crate::parallel::launched_ranks().is_some() => Err(
            "--thread-ranks under a launcher (mpirun, srun): ranks are either MPI's or threads, \
                 not both; drop --thread-ranks or the launcher"
                .into(),
        ),
        Ok(_) if args.thread_ranks.is_some() => ranks::on_threads(&args),
        Ok(comm) if crate::parallel::launched_ranks().is_some() => ranks::run(&args, &**comm),
        Ok(_) => run(&args),
        Err(e) => Err(e.clone()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            protocol::say!("lbm-server: error: {e}");
            ExitCode::from(2)
        }
    }
}

fn run(args: &BenchArgs) -> Result<(), String> {
    let n = parse_grid(&args.grid)?;
    let tau = 0.6;
    let operator = parse_operator(&args.operator, tau)?;
    if args.steps == 0 {
        return Err("--steps = 0: must be at least 1".into());
    }
    let timed = Timed::parse(&args.reference)?;
    let storages = storage::parse_storages(&args.storage)?;
    let faces = parse_faces(&args.faces)?;
    let gpu = Arc::new(Gpu::new()?);
    let bandwidth = copy_bandwidth(&gpu);
    let setup = Setup::new(n, faces, tau, operator);
    let sweep = match args.particles.is_empty() {
        true => None,
        false => Some(Sweep::new(&gpu, &setup, args)?),
    };
    let mut lattice = GpuLattice::new(gpu.clone(), setup.clone(), Health::default(), None)?;
    let naive = if timed.naive { Naive::new(&gpu, n) } else { None };
    let rounds = Rounds::time(&gpu, &mut lattice, naive.as_ref(), args, timed.ours);
    print_grid(&gpu, args, &setup);
    let mlups = best(&rounds.ours);
    if timed.ours {
        print_roofline(&rounds.ours, bandwidth);
        print_health_check(&gpu, &lattice);
        if args.per_cell && storages.is_empty() {
            print_per_cell(&gpu, &setup, args, &rounds.ours)?;
        }
        if !storages.is_empty() {
            storage::print_storages(&gpu, &setup, &storages, args, bandwidth)?;
        }
    }
    if let Some(sweep) = sweep {
        sweep.run(lattice, &args.particles, mlups)?;
    }
    if timed.naive {
        print_naive(naive.is_some(), &rounds, timed.ours);
    }
    Ok(())
}

/// Which of our kernels and the naive reference `--reference` times.
struct Timed {
    ours: bool,
    naive: bool,
}

impl Timed {
    fn parse(name: &str) -> Result<Timed, String> {
        let (ours, naive) = match name {
            "both" => (true, true),
            "none" => (true, false),
            "only" => (false, true),
            other => return Err(format!("--reference = {other:?}: expected both, none or only")),
        };
        Ok(Timed { ours, naive })
    }
}

/// MLUPS of each timed round of our kernels and of the naive kernel (empty where not timed).
struct Rounds {
    ours: Vec<f64>,
    theirs: Vec<f64>,
}

impl Rounds {
    /// Warm-up, then rounds alternating ours and the naive kernel, so that both see the same load.
    fn time(
        gpu: &Gpu,
        lattice: &mut GpuLattice,
        naive: Option<&Naive>,
        args: &BenchArgs,
        ours: bool,
    ) -> Rounds {
        lattice.step(20);
        gpu.wait();
        if let Some(naive) = naive {
            naive.run(gpu, 20);
        }
        let cells = lattice.setup.cells() as f64;
        let mlups = |seconds: f64| cells * args.steps as f64 / seconds / 1e6;
        let mut rounds = Rounds {
            ours: Vec::new(),
            theirs: Vec::new(),
        };
        for _ in 0..args.rounds.max(1) {
            if ours {
                let start = Instant::now();
                lattice.step(args.steps);
                gpu.wait();
                rounds.ours.push(mlups(start.elapsed().as_secs_f64()));
            }
            if let Some(naive) = naive {
                let start = Instant::now();
                naive.run(gpu, args.steps);
                rounds.theirs.push(mlups(start.elapsed().as_secs_f64()));
            }
        }
        rounds
    }
}

/// The best of the rounds' MLUPS (0 for none).
fn best(rounds: &[f64]) -> f64 {
    rounds.iter().cloned().fold(0.0, f64::max)
}

/// The rounds' MLUPS as the report lists them.
fn list(rounds: &[f64]) -> String {
    rounds
        .iter()
        .map(|m| format!("{m:.2}"))
        .collect::<Vec<_>>()
        .join(" ")
}

fn print_grid(gpu: &Gpu, args: &BenchArgs, setup: &Setup) {
    let n = setup.n;
    println!(
        "adapter:        {} ({:?}, {:?})",
        gpu.adapter.name, gpu.adapter.device_type, gpu.adapter.backend
    );
    println!(
        "grid:           {}x{}x{} ({} cells), operator {}, faces {}",
        n[0],
        n[1],
        n[2],
        setup.cells() as f64,
        args.operator,
        args.faces
    );
    println!(
        "steps:          {} per round, {} rounds",
        args.steps,
        args.rounds.max(1)
    );
}

/// Our kernels' MLUPS against the roofline of the copy `bandwidth` (bytes per second).
fn print_roofline(ours: &[f64], bandwidth: f64) {
    let mlups = best(ours);
    let roofline = bandwidth / BYTES_PER_CELL / 1e6;
    println!("MLUPS:          {mlups:.1} (best round; rounds: {})", list(ours));
    println!("bytes/cell/step {BYTES_PER_CELL} (FP32 populations, AA pattern: 19 reads + 19 writes + a 4-byte cell-list entry at most)");
    println!(
        "copy bandwidth: {:.1} GB/s (buffer-to-buffer copy, this run)",
        bandwidth / 1e9
    );
    println!(
        "roofline:       {roofline:.1} MLUPS; achieved {:.1}% of it",
        100.0 * mlups / roofline
    );
}

fn print_health_check(gpu: &Gpu, lattice: &GpuLattice) {
    let [full, one] = health_check_times(gpu, lattice);
    println!(
        "health check:   {full:.1} ms reading every cell back, {one:.2} ms reading the status and one cell (best of 3; a run checks every lattice.check_interval steps)"
    );
}

/// `--per-cell`: the per-cell kernel (a thread per cell, one dispatch), its rounds after ours
/// (`quads`, the quads' rounds of this run), and the ratio of the best rounds.
fn print_per_cell(gpu: &Arc<Gpu>, setup: &Setup, args: &BenchArgs, quads: &[f64]) -> Result<(), String> {
    let setup = Setup {
        kernel: Kernel::Cells,
        ..setup.clone()
    };
    let mut per_cell = GpuLattice::new(gpu.clone(), setup.clone(), Health::default(), None)?;
    per_cell.step(20);
    gpu.wait();
    let cells = setup.cells() as f64;
    let rounds: Vec<f64> = (0..args.rounds.max(1))
        .map(|_| {
            let start = Instant::now();
            per_cell.step(args.steps);
            gpu.wait();
            cells * args.steps as f64 / start.elapsed().as_secs_f64() / 1e6
        })
        .collect();
    println!(
        "per cell:       {:.1} MLUPS (best round; rounds: {}; the per-cell kernel, lattice.kernel = \"cells\"), {:.2}x the quads' kernels",
        best(&rounds),
        list(&rounds),
        best(&rounds) / best(quads)
    );
    Ok(())
}

/// The naive kernel's rounds (`built`: whether the device took its lattices), and ours over them.
fn print_naive(built: bool, rounds: &Rounds, ours: bool) {
    if !built {
        println!("naive kernel:   skipped (a lattice exceeds this device's buffer limits)");
        return;
    }
    let naive = best(&rounds.theirs);
    println!(
        "naive kernel:   {naive:.1} MLUPS (best round; rounds: {}; two lattices, pull, BGK, periodic, same grid, same run)",
        list(&rounds.theirs)
    );
    if ours {
        let ratios: Vec<f64> = rounds
            .ours
            .iter()
            .zip(&rounds.theirs)
            .map(|(a, b)| a / b)
            .collect();
        println!(
            "ours / naive:   {:.2}x (best rounds; per round: {})",
            best(&rounds.ours) / naive,
            list(&ratios)
        );
    }
}

/// Bytes per second of a large buffer-to-buffer copy (read + write counted), best of 5: copies
/// repeated within one submission until it lasts 20 ms or more, so that the submission's round
/// trip (about a millisecond: as long as one copy of 256 MiB on a GPU of 4 TB/s) is a small part.
pub fn copy_bandwidth(gpu: &Gpu) -> f64 {
    let bytes = (gpu.limits.max_buffer_size / 4).min(256 << 20);
    let make = |usage| {
        gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("copy"),
            size: bytes,
            usage,
            mapped_at_creation: false,
        })
    };
    let src = make(wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST);
    let dst = make(wgpu::BufferUsages::COPY_DST);
    let copies = |repeats: u32| {
        let start = Instant::now();
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        for _ in 0..repeats {
            encoder.copy_buffer_to_buffer(&src, 0, &dst, 0, bytes);
        }
        gpu.queue.submit([encoder.finish()]);
        gpu.wait();
        start.elapsed().as_secs_f64()
    };
    copies(1);
    let mut repeats = 1;
    while copies(repeats) < 0.02 && repeats < 1 << 12 {
        repeats *= 2;
    }
    (0..5)
        .map(|_| 2.0 * bytes as f64 * repeats as f64 / copies(repeats))
        .fold(0.0, f64::max)
}

/// Milliseconds (best of 3) of the health check as runs made it until 2026-12-04, the whole field
/// read back (`GpuLattice::fields`), and as they make it now (`GpuLattice::health`).
fn health_check_times(gpu: &Gpu, lattice: &GpuLattice) -> [f64; 2] {
    let best = |check: &dyn Fn()| {
        (0..3)
            .map(|_| {
                gpu.wait();
                let start = Instant::now();
                check();
                start.elapsed().as_secs_f64() * 1e3
            })
            .fold(f64::INFINITY, f64::min)
    };
    [
        best(&|| {
            let _ = lattice.fields();
        }),
        best(&|| {
            let _ = lattice.health();
        }),
    ]
}

/// "periodic" or "walls": every face periodic, or every face a wall at rest.
fn parse_faces(name: &str) -> Result<[Face; 6], String> {
    match name {
        "periodic" => Ok([Face::Periodic; 6]),
        "walls" => Ok([Face::Wall; 6]),
        other => Err(format!("--faces {other}: expected periodic or walls")),
    }
}
