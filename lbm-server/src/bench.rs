//! `lbm-server bench`: lattice updates per second against this device's memory bandwidth.

use crate::lbm::geometry::{Face, Operator, Setup};
use crate::lbm::gpu::{Gpu, Health, Lattice};
use crate::lbm::imb::{CoveredCells, ImbOptions, SolidParticle};
use crate::lbm::mrt::Rates;
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
    /// 4 cells diameter on a regular lattice, immersed moving boundary; MLUPS and ratio to LBM-only.
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
    /// Also time the LBM-only step with every cell on its own, without the four-cell quads (a
    /// thread per cell, as the naive kernel: what the quads gain or cost on this device).
    #[arg(long)]
    per_cell: bool,
    /// Timed rounds, ours and the naive kernel alternating (best round reported).
    #[arg(long, default_value_t = 3)]
    rounds: u32,
    /// Which kernels to time: both, ours or naive (for instruction counts under a profiler).
    #[arg(long, default_value = "both", hide = true)]
    kernel: String,
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
    match run(&args) {
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
    let (time_ours, time_naive) = match args.kernel.as_str() {
        "both" => (true, true),
        "ours" => (true, false),
        "naive" => (false, true),
        other => return Err(format!("--kernel = {other:?}: expected both, ours or naive")),
    };
    let rounds = args.rounds.max(1);
    let faces = parse_faces(&args.faces)?;
    let gpu = Arc::new(Gpu::new()?);
    let bandwidth = copy_bandwidth(&gpu);
    let setup = Setup::new(n, faces, tau, operator);
    let cells = setup.cells() as f64;
    let mut lattice = Lattice::new(gpu.clone(), setup.clone(), Health::default(), None)?;
    let naive = if time_naive { Naive::new(&gpu, n) } else { None };
    // Warm-up, then rounds alternating ours and the naive kernel, so that both see the same load.
    lattice.step(20);
    gpu.wait();
    if let Some(naive) = &naive {
        naive.run(&gpu, 20);
    }
    let mlups = |seconds: f64| cells * args.steps as f64 / seconds / 1e6;
    let (mut ours, mut theirs) = (Vec::new(), Vec::new());
    for _ in 0..rounds {
        if time_ours {
            let start = Instant::now();
            lattice.step(args.steps);
            gpu.wait();
            ours.push(mlups(start.elapsed().as_secs_f64()));
        }
        if let Some(naive) = &naive {
            let start = Instant::now();
            naive.run(&gpu, args.steps);
            theirs.push(mlups(start.elapsed().as_secs_f64()));
        }
    }
    let best = |v: &[f64]| v.iter().cloned().fold(0.0, f64::max);
    let list = |v: &[f64]| v.iter().map(|m| format!("{m:.2}")).collect::<Vec<_>>().join(" ");
    let roofline = bandwidth / BYTES_PER_CELL / 1e6;
    println!(
        "adapter:        {} ({:?}, {:?})",
        gpu.adapter.name, gpu.adapter.device_type, gpu.adapter.backend
    );
    println!(
        "grid:           {}x{}x{} ({} cells), operator {}, faces {}",
        n[0], n[1], n[2], cells, args.operator, args.faces
    );
    println!("steps:          {} per round, {rounds} rounds", args.steps);
    let mlups = best(&ours);
    if time_ours {
        println!("MLUPS:          {mlups:.1} (best round; rounds: {})", list(&ours));
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
    if time_ours {
        let [full, one] = health_check_times(&gpu, &lattice);
        println!(
            "health check:   {full:.1} ms reading every cell back, {one:.2} ms reading the status and one cell (best of 3; a run checks every lattice.check_interval steps)"
        );
    }
    if time_ours && args.per_cell {
        let mut per_cell = Lattice::per_cell(gpu.clone(), setup.clone(), Health::default())?;
        per_cell.step(20);
        gpu.wait();
        let rounds: Vec<f64> = (0..rounds)
            .map(|_| {
                let start = Instant::now();
                per_cell.step(args.steps);
                gpu.wait();
                cells * args.steps as f64 / start.elapsed().as_secs_f64() / 1e6
            })
            .collect();
        println!(
            "per cell:       {:.1} MLUPS (best round; rounds: {}; our kernels without the four-cell quads)",
            best(&rounds),
            list(&rounds)
        );
    }
    if !args.particles.is_empty() {
        let modes = covered_cell_modes(&args.covered_cells)?;
        coupled_sweep(
            &gpu,
            lattice,
            setup.clone(),
            args.steps,
            &args.particles,
            mlups,
            args.passes,
            &modes,
            args.dem_ms,
        )?;
    }
    if time_naive {
        match naive {
            Some(_) => {
                let naive = best(&theirs);
                println!(
                    "naive kernel:   {naive:.1} MLUPS (best round; rounds: {}; two lattices, pull, BGK, periodic, same grid, same run)",
                    list(&theirs)
                );
                if time_ours {
                    let ratios: Vec<f64> = ours.iter().zip(&theirs).map(|(a, b)| a / b).collect();
                    println!(
                        "ours / naive:   {:.2}x (best rounds; per round: {})",
                        mlups / naive,
                        list(&ratios)
                    );
                }
            }
            None => println!("naive kernel:   skipped (a lattice exceeds this device's buffer limits)"),
        }
    }
    Ok(())
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

/// The textbook two-lattice pull kernel (shaders/naive_pull.wgsl), ready to run on a periodic grid.
struct Naive {
    pipeline: wgpu::ComputePipeline,
    groups: [wgpu::BindGroup; 2],
    workgroups: (u32, u32),
}

impl Naive {
    /// None when a lattice (two binding ranges, directions 0-9 and 10-18) exceeds the limits.
    fn new(gpu: &Gpu, n: [usize; 3]) -> Option<Naive> {
        use wgpu::util::DeviceExt;
        let cells = n[0] * n[1] * n[2];
        let align = u64::from(gpu.limits.min_storage_buffer_offset_alignment);
        let lo_bytes = (10 * cells * 4) as u64;
        let hi_offset = lo_bytes.div_ceil(align) * align;
        let hi_bytes = (9 * cells * 4) as u64;
        let total = hi_offset + hi_bytes;
        if lo_bytes > gpu.limits.max_storage_buffer_binding_size || total > gpu.limits.max_buffer_size {
            return None;
        }
        let d = &gpu.device;
        let mut lattice = vec![0f32; (total / 4) as usize];
        for i in 0..19 {
            let start = if i < 10 {
                i * cells
            } else {
                hi_offset as usize / 4 + (i - 10) * cells
            };
            lattice[start..start + cells].fill(crate::lbm::lattice::W[i] as f32);
        }
        let buffers: Vec<wgpu::Buffer> = (0..2)
            .map(|_| {
                d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("naive"),
                    contents: bytemuck::cast_slice(&lattice),
                    usage: wgpu::BufferUsages::STORAGE,
                })
            })
            .collect();
        let params: [u32; 8] = [
            n[0] as u32,
            n[1] as u32,
            n[2] as u32,
            0,
            (1.0f32 / 0.6).to_bits(),
            0,
            0,
            0,
        ];
        let uniform = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("naive params"),
            contents: bytemuck::cast_slice(&params),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let source = crate::lbm::unroll::unroll(include_str!("../../shaders/naive_pull.wgsl"));
        let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("naive_pull.wgsl"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let pipeline = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("naive_pull"),
            layout: None,
            module: &module,
            entry_point: Some("naive_pull"),
            compilation_options: Default::default(),
            cache: None,
        });
        fn range(buffer: &wgpu::Buffer, offset: u64, size: u64) -> wgpu::BindingResource<'_> {
            wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer,
                offset,
                size: std::num::NonZeroU64::new(size),
            })
        }
        let groups = [0, 1].map(|parity| {
            let (src, dst) = (&buffers[parity], &buffers[1 - parity]);
            let resources = [
                uniform.as_entire_binding(),
                range(src, 0, lo_bytes),
                range(src, hi_offset, hi_bytes),
                range(dst, 0, lo_bytes),
                range(dst, hi_offset, hi_bytes),
            ];
            let entries: Vec<wgpu::BindGroupEntry> = resources
                .into_iter()
                .enumerate()
                .map(|(binding, resource)| wgpu::BindGroupEntry {
                    binding: binding as u32,
                    resource,
                })
                .collect();
            d.create_bind_group(&wgpu::BindGroupDescriptor {
                label: None,
                layout: &pipeline.get_bind_group_layout(0),
                entries: &entries,
            })
        });
        let workgroups = (cells as u32).div_ceil(64);
        let x = workgroups.min(65_535);
        Some(Naive {
            pipeline,
            groups,
            workgroups: (x, workgroups.div_ceil(x)),
        })
    }

    /// Runs `steps` steps (one submit) and waits for them.
    fn run(&self, gpu: &Gpu, steps: u64) {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        for step in 0..steps {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &self.groups[(step % 2) as usize], &[]);
            pass.dispatch_workgroups(self.workgroups.0, self.workgroups.1, 1);
        }
        gpu.queue.submit([encoder.finish()]);
        gpu.wait();
    }
}

/// The ways of treating the covered cells that `--covered-cells` names.
fn covered_cell_modes(name: &str) -> Result<Vec<CoveredCells>, String> {
    match name {
        "both" => return Ok(vec![CoveredCells::Redo, CoveredCells::Fused]),
        "all" => return Ok(CoveredCells::DEFINITE.to_vec()),
        _ => {}
    }
    CoveredCells::from_name(name)
        .map(|mode| vec![mode])
        .ok_or_else(|| format!("--covered-cells {name}: expected auto, fused, redo, skip, both or all"))
}

/// Milliseconds (best of 3) of the health check as runs made it until 2026-12-04, the whole field
/// read back (`Lattice::fields`), and as they make it now (`Lattice::health`).
fn health_check_times(gpu: &Gpu, lattice: &Lattice) -> [f64; 2] {
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

/// Coupled MLUPS for each particle count (and way of treating the covered cells), against the
/// LBM-only figure of the same run; first the LBM-only `lattice` of that figure stepped as the
/// lockstep steps (then freed).
#[allow(clippy::too_many_arguments)]
fn coupled_sweep(
    gpu: &Arc<Gpu>,
    mut lattice: Lattice,
    setup: Setup,
    steps: u64,
    counts: &[usize],
    lbm_only: f64,
    passes: bool,
    modes: &[CoveredCells],
    dem_ms: f64,
) -> Result<(), String> {
    if !(dem_ms.is_finite() && dem_ms >= 0.0) {
        return Err(format!("--dem-ms = {dem_ms}: expected 0 or more milliseconds"));
    }
    let dem = std::time::Duration::from_secs_f64(dem_ms / 1e3);
    let n = setup.n;
    let mut breakdown = Vec::new();
    let mut clocked = Vec::new();
    let mut host = Vec::new();
    println!("coupled (spheres of 4 cells diameter, immersed moving boundary, one readback per step):");
    if dem_ms > 0.0 {
        println!("(the host waits {dem_ms} ms per step after the loads, a stand-in for the DEM's step)");
    }
    println!("| particles | covered cells | MLUPS | ratio to LBM-only ({lbm_only:.1} MLUPS) |");
    println!("|---:|---|---:|---:|");
    // The lockstep's own cost: LBM-only steps, each submitted and waited for as a coupled step is.
    let mlups = lockstep_mlups(gpu, &mut lattice, steps, dem);
    println!(
        "| 0 (no coupling: one submit and wait per step) | - | {mlups:.1} | {:.0}% |",
        100.0 * mlups / lbm_only
    );
    drop(lattice);
    // The fluid kernels that test the cover mask (no quads, one bit per cell), no particle.
    for mode in [CoveredCells::Fused, CoveredCells::Skip] {
        if !modes.contains(&mode) {
            continue;
        }
        let name = mode.name();
        let options = ImbOptions {
            covered_cells: mode,
            ..Default::default()
        };
        let mut lattice = Lattice::new(gpu.clone(), setup.clone(), Health::default(), Some(options))?;
        let mlups = lockstep_mlups(gpu, &mut lattice, steps, dem);
        println!(
            "| 0 ({name} fluid kernels, no particle: one submit and wait per step) | {name} | {mlups:.1} | {:.0}% |",
            100.0 * mlups / lbm_only
        );
    }
    for &count in counts {
        let side = (count as f64).cbrt().round().max(1.0) as usize;
        if side * side * side != count {
            return Err(format!(
                "--particles {count}: use cubes (1, 8, 64, 512, 4096, 32768)"
            ));
        }
        let spacing: [f64; 3] = std::array::from_fn(|a| n[a] as f64 / side as f64);
        if spacing.iter().any(|s| *s < 4.0) {
            return Err(format!(
                "--particles {count}: {side}^3 spheres of 4 cells do not fit the grid"
            ));
        }
        let particles = sphere_lattice(side, spacing);
        for &mode in modes {
            let options = ImbOptions {
                covered_cells: mode,
                ..Default::default()
            };
            let mut lattice = Lattice::new(gpu.clone(), setup.clone(), Health::default(), Some(options))?;
            let name = lattice.covered_cells().name();
            for _ in 0..5 {
                lattice.step_coupled(&particles)?;
            }
            let start = Instant::now();
            for _ in 0..steps {
                lattice.step_coupled(&particles)?;
                std::thread::sleep(dem);
            }
            // The last step's fluid kernels may still run (with the redo they do not hold the loads).
            gpu.wait();
            let mlups = (n[0] * n[1] * n[2]) as f64 * steps as f64 / start.elapsed().as_secs_f64() / 1e6;
            println!(
                "| {count} | {name} | {mlups:.1} | {:.0}% |",
                100.0 * mlups / lbm_only
            );
            if passes {
                breakdown.push((count, name, time_passes(&mut lattice, &particles, steps)?));
                if let Some(times) = clock_passes(&mut lattice, &particles, steps)? {
                    clocked.push((count, name, times));
                }
                if host.last().is_none_or(|(c, _)| *c != count) {
                    host.push((count, lattice.host_pass_times(&particles, 21)?));
                }
            }
        }
    }
    if passes {
        let split = "each pass submitted and waited for on its own";
        print_passes(&breakdown, ["wall", "CPU (all threads)"], split);
        let unsplit = "the device's timestamps between the passes of steps not split, as a run makes them";
        print_passes(&clocked, ["device clock"], unsplit);
        print_host_passes(&host);
    }
    Ok(())
}

/// The host's passes per particle count (`Lattice::host_pass_times`).
fn print_host_passes(host: &[(usize, [f64; 2])]) {
    println!(
        "host passes of a coupled step ({} threads, no device; median of 21):",
        rayon::current_num_threads()
    );
    println!("| particles | sizes, checks, records into staging (ms) | loads converted (ms) |");
    println!("|---:|---:|---:|");
    for (count, [upload, loads]) in host {
        println!("| {count} | {upload:.3} | {loads:.3} |");
    }
}

/// MLUPS of `steps` fluid steps, each submitted and waited for on its own, then `dem` idle.
fn lockstep_mlups(gpu: &Gpu, lattice: &mut Lattice, steps: u64, dem: std::time::Duration) -> f64 {
    gpu.wait();
    let start = Instant::now();
    for _ in 0..steps {
        lattice.step(1);
        gpu.wait();
        std::thread::sleep(dem);
    }
    lattice.setup.cells() as f64 * steps as f64 / start.elapsed().as_secs_f64() / 1e6
}

/// side^3 spheres of radius 2 cells at the centres of a regular lattice of `spacing`.
fn sphere_lattice(side: usize, spacing: [f64; 3]) -> Vec<SolidParticle> {
    (0..side * side * side)
        .map(|k| {
            let idx = [k % side, (k / side) % side, k / (side * side)];
            SolidParticle {
                position: std::array::from_fn(|a| (idx[a] as f64 + 0.5) * spacing[a]),
                radius: 2.0,
                ..Default::default()
            }
        })
        .collect()
}

/// Mean milliseconds of each pass of the coupled step over `steps` steps, each pass submitted on
/// its own: wall time and this process's CPU time (all threads: lavapipe's workers do the work, and
/// the CPU time moves less than the wall time when other jobs share the cores).
fn time_passes(
    lattice: &mut Lattice,
    particles: &[SolidParticle],
    steps: u64,
) -> Result<PassTimes<2>, String> {
    let clock = || [start_of_run().elapsed().as_secs_f64(), process_cpu_seconds()];
    let mut sums: PassTimes<2> = Vec::new();
    for _ in 0..steps {
        let times = lattice.step_coupled_timed(particles, &clock)?;
        let ms = times.iter().map(|(name, t)| (*name, t.map(|t| t * 1e3)));
        add_mean(&mut sums, ms, steps);
    }
    Ok(sums)
}

/// Milliseconds of each pass by the device's clock over `steps` steps not split into submissions
/// (mean), where the device has timestamps.
fn clock_passes(
    lattice: &mut Lattice,
    particles: &[SolidParticle],
    steps: u64,
) -> Result<Option<PassTimes<1>>, String> {
    let Some(clock) = lattice.pass_clock() else {
        return Ok(None);
    };
    let mut sums = Vec::new();
    for _ in 0..steps {
        let times = lattice.step_coupled_clocked(particles, &clock)?;
        add_mean(&mut sums, times.iter().map(|(name, t)| (*name, [*t])), steps);
    }
    Ok(Some(sums))
}

/// Adds one step's times of each pass (ms) over `steps` to `sums` (the passes in the same order).
fn add_mean<const N: usize>(
    sums: &mut PassTimes<N>,
    times: impl Iterator<Item = (&'static str, [f64; N])>,
    steps: u64,
) {
    for (k, (name, t)) in times.enumerate() {
        if k == sums.len() {
            sums.push((name, [0.0; N]));
        }
        for (total, t) in sums[k].1.iter_mut().zip(t) {
            *total += t / steps as f64;
        }
    }
}

fn start_of_run() -> Instant {
    static START: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();
    *START.get_or_init(Instant::now)
}

/// CPU seconds of this process, all threads (0 where the clock is not available).
fn process_cpu_seconds() -> f64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes one timespec, which `t` is.
    let ok = unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut t) } == 0;
    if ok {
        t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9
    } else {
        0.0
    }
}

/// Milliseconds by N clocks of each pass of a coupled step, in the order of the step.
type PassTimes<const N: usize> = Vec<(&'static str, [f64; N])>;

/// The time of each pass per particle count: one table per way of treating the covered cells
/// (their passes differ) and clock; `how` the passes were timed.
fn print_passes<const N: usize>(breakdown: &[(usize, &str, PassTimes<N>)], clocks: [&str; N], how: &str) {
    for mode in CoveredCells::DEFINITE.map(CoveredCells::name) {
        let rows: Vec<(usize, &PassTimes<N>)> = breakdown
            .iter()
            .filter(|(_, m, _)| *m == mode)
            .map(|(count, _, times)| (*count, times))
            .collect();
        print_pass_table(mode, &rows, clocks, how);
    }
}

fn print_pass_table<const N: usize>(
    mode: &str,
    breakdown: &[(usize, &PassTimes<N>)],
    clocks: [&str; N],
    how: &str,
) {
    let Some((_, first)) = breakdown.first() else {
        return;
    };
    let names: Vec<&str> = first.iter().map(|(name, _)| *name).collect();
    for (k, what) in clocks.iter().enumerate() {
        println!("coupled step by pass, covered cells {mode}, {what} ms per step (mean; {how}):");
        println!(
            "| particles | {} | total | total without fluid |",
            names.join(" | ")
        );
        println!("|---:|{}---:|---:|", "---:|".repeat(names.len()));
        for (count, times) in breakdown {
            let cells: Vec<String> = times.iter().map(|(_, t)| format!("{:.2}", t[k])).collect();
            let total: f64 = times.iter().map(|(_, t)| t[k]).sum();
            let fluid: f64 = times
                .iter()
                .filter(|(name, _)| *name == "fluid")
                .map(|(_, t)| t[k])
                .sum();
            println!(
                "| {count} | {} | {total:.2} | {:.2} |",
                cells.join(" | "),
                total - fluid
            );
        }
    }
}
