//! `lbm-server bench`: lattice updates per second against this device's memory bandwidth.

use crate::lbm::geometry::{Face, Operator, Setup};
use crate::lbm::gpu::{Gpu, Health, Lattice};
use crate::lbm::mrt::Rates;
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Instant;

/// Bytes moved per cell per step: 19 populations read and written in f32, plus the 4-byte cell
/// flags (which links leave the fluid: no neighbour lookups in the kernel).
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
    let gpu = Arc::new(Gpu::new()?);
    let bandwidth = copy_bandwidth(&gpu);
    let setup = Setup::new(n, [Face::Periodic; 6], tau, operator);
    let cells = setup.cells() as f64;
    let mut lattice = Lattice::new(gpu.clone(), setup, Health::default(), None)?;
    lattice.step(20);
    gpu.wait();
    let start = Instant::now();
    lattice.step(args.steps);
    gpu.wait();
    let seconds = start.elapsed().as_secs_f64();
    let mlups = cells * args.steps as f64 / seconds / 1e6;
    let naive = naive_mlups(&gpu, n, args.steps);
    let roofline = bandwidth / BYTES_PER_CELL / 1e6;
    println!(
        "adapter:        {} ({:?}, {:?})",
        gpu.adapter.name, gpu.adapter.device_type, gpu.adapter.backend
    );
    println!(
        "grid:           {}x{}x{} ({} cells), operator {}",
        n[0], n[1], n[2], cells, args.operator
    );
    println!("steps:          {} in {:.3} s", args.steps, seconds);
    println!("MLUPS:          {mlups:.1}");
    println!("bytes/cell/step {BYTES_PER_CELL} (FP32 populations, AA pattern: 19 reads + 19 writes + a 4-byte flag word)");
    println!(
        "copy bandwidth: {:.1} GB/s (buffer-to-buffer copy, this run)",
        bandwidth / 1e9
    );
    println!(
        "roofline:       {roofline:.1} MLUPS; achieved {:.1}% of it",
        100.0 * mlups / roofline
    );
    if !args.particles.is_empty() {
        coupled_sweep(&gpu, n, tau, operator, args.steps, &args.particles, mlups)?;
    }
    match naive {
        Some(naive) => println!(
            "naive kernel:   {naive:.1} MLUPS (two lattices, pull, BGK, same grid, same run): ours is {:.2}x",
            mlups / naive
        ),
        None => println!("naive kernel:   skipped (grid too large for one binding)"),
    }
    Ok(())
}

/// Bytes per second of a large buffer-to-buffer copy (read + write counted), best of 5.
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
    let copy = || {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(&src, 0, &dst, 0, bytes);
        gpu.queue.submit([encoder.finish()]);
        gpu.wait();
    };
    copy();
    (0..5)
        .map(|_| {
            let start = Instant::now();
            copy();
            2.0 * bytes as f64 / start.elapsed().as_secs_f64()
        })
        .fold(0.0, f64::max)
}

/// MLUPS of the textbook two-lattice pull kernel (shaders/naive_pull.wgsl), or None when its
/// single-array lattice exceeds the binding limit.
fn naive_mlups(gpu: &Gpu, n: [usize; 3], steps: u64) -> Option<f64> {
    use wgpu::util::DeviceExt;
    let cells = n[0] * n[1] * n[2];
    let bytes = (19 * cells * 4) as u64;
    if bytes > gpu.limits.max_storage_buffer_binding_size {
        return None;
    }
    let d = &gpu.device;
    let lattice: Vec<f32> = (0..19 * cells)
        .map(|j| crate::lbm::lattice::W[j / cells] as f32)
        .collect();
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
    let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("naive_pull.wgsl"),
        source: wgpu::ShaderSource::Wgsl(include_str!("../../shaders/naive_pull.wgsl").into()),
    });
    let pipeline = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("naive_pull"),
        layout: None,
        module: &module,
        entry_point: Some("naive_pull"),
        compilation_options: Default::default(),
        cache: None,
    });
    let groups = [0, 1].map(|parity| {
        d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: uniform.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: buffers[parity].as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: buffers[1 - parity].as_entire_binding(),
                },
            ],
        })
    });
    let workgroups = (cells as u32).div_ceil(64);
    let (x, y) = (
        workgroups.min(65_535),
        workgroups.div_ceil(workgroups.min(65_535)),
    );
    let run = |count: u64| {
        let mut encoder = d.create_command_encoder(&Default::default());
        for step in 0..count {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &groups[(step % 2) as usize], &[]);
            pass.dispatch_workgroups(x, y, 1);
        }
        gpu.queue.submit([encoder.finish()]);
        gpu.wait();
    };
    run(10);
    let start = Instant::now();
    run(steps);
    Some(cells as f64 * steps as f64 / start.elapsed().as_secs_f64() / 1e6)
}

/// Coupled MLUPS for each particle count, against the LBM-only figure of the same run.
fn coupled_sweep(
    gpu: &Arc<Gpu>,
    n: [usize; 3],
    tau: f64,
    operator: Operator,
    steps: u64,
    counts: &[usize],
    lbm_only: f64,
) -> Result<(), String> {
    use crate::lbm::imb::{ImbOptions, SolidParticle};
    println!("coupled (spheres of 4 cells diameter, immersed moving boundary, one readback per step):");
    println!("| particles | MLUPS | ratio to LBM-only ({lbm_only:.1} MLUPS) |");
    println!("|---:|---:|---:|");
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
        let particles: Vec<SolidParticle> = (0..count)
            .map(|k| {
                let idx = [k % side, (k / side) % side, k / (side * side)];
                SolidParticle {
                    position: std::array::from_fn(|a| (idx[a] as f64 + 0.5) * spacing[a]),
                    radius: 2.0,
                    ..Default::default()
                }
            })
            .collect();
        let setup = Setup::new(n, [Face::Periodic; 6], tau, operator);
        let mut lattice = Lattice::new(gpu.clone(), setup, Health::default(), Some(ImbOptions::default()))?;
        for _ in 0..5 {
            lattice.step_coupled(&particles)?;
        }
        let start = Instant::now();
        for _ in 0..steps {
            lattice.step_coupled(&particles)?;
        }
        let mlups = (n[0] * n[1] * n[2]) as f64 * steps as f64 / start.elapsed().as_secs_f64() / 1e6;
        println!("| {count} | {mlups:.1} | {:.0}% |", 100.0 * mlups / lbm_only);
    }
    Ok(())
}
