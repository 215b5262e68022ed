//! The textbook two-lattice pull kernel (shaders/naive_pull.wgsl), the yardstick of our kernels.

use crate::lbm::gpu::Gpu;
use wgpu::util::DeviceExt;

/// The naive kernel ready to run on a periodic grid, its two lattices at rest.
pub struct Naive {
    pipeline: wgpu::ComputePipeline,
    groups: [wgpu::BindGroup; 2],
    workgroups: (u32, u32),
}

/// Where a lattice's populations lie in its buffer: directions 0-9 from 0, 10-18 from
/// `hi_offset` (two binding ranges, the second aligned as the device asks).
struct Layout {
    cells: usize,
    lo_bytes: u64,
    hi_offset: u64,
    hi_bytes: u64,
}

impl Layout {
    /// None when a binding range or the buffer exceeds the device's limits.
    fn new(gpu: &Gpu, n: [usize; 3]) -> Option<Layout> {
        let cells = n[0] * n[1] * n[2];
        let align = u64::from(gpu.limits.min_storage_buffer_offset_alignment);
        let lo_bytes = (10 * cells * 4) as u64;
        let layout = Layout {
            cells,
            lo_bytes,
            hi_offset: lo_bytes.div_ceil(align) * align,
            hi_bytes: (9 * cells * 4) as u64,
        };
        let fits = lo_bytes <= gpu.limits.max_storage_buffer_binding_size
            && layout.total() <= gpu.limits.max_buffer_size;
        fits.then_some(layout)
    }

    fn total(&self) -> u64 {
        self.hi_offset + self.hi_bytes
    }

    /// A lattice at rest: each population its weight.
    fn at_rest(&self) -> Vec<f32> {
        let mut lattice = vec![0f32; (self.total() / 4) as usize];
        for i in 0..19 {
            let start = if i < 10 {
                i * self.cells
            } else {
                self.hi_offset as usize / 4 + (i - 10) * self.cells
            };
            lattice[start..start + self.cells].fill(crate::lbm::d3q19::W[i] as f32);
        }
        lattice
    }
}

impl Naive {
    /// None when a lattice (two binding ranges, directions 0-9 and 10-18) exceeds the limits.
    pub fn new(gpu: &Gpu, n: [usize; 3]) -> Option<Naive> {
        let layout = Layout::new(gpu, n)?;
        let d = &gpu.device;
        let at_rest = layout.at_rest();
        let lattices = [0, 1].map(|_| {
            d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("naive"),
                contents: bytemuck::cast_slice(&at_rest),
                usage: wgpu::BufferUsages::STORAGE,
            })
        });
        let uniform = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("naive params"),
            contents: bytemuck::cast_slice(&params(n)),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let pipeline = pipeline(d);
        let groups = [0, 1].map(|parity| {
            let (src, dst) = (&lattices[parity], &lattices[1 - parity]);
            bind_group(d, &pipeline, &uniform, [src, dst], &layout)
        });
        let workgroups = (layout.cells as u32).div_ceil(64);
        let x = workgroups.min(65_535);
        Some(Naive {
            pipeline,
            groups,
            workgroups: (x, workgroups.div_ceil(x)),
        })
    }

    /// Runs `steps` steps (one submit) and waits for them.
    pub fn run(&self, gpu: &Gpu, steps: u64) {
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

/// The kernel's uniform: the grid and 1 / tau (tau 0.6).
fn params(n: [usize; 3]) -> [u32; 8] {
    [
        n[0] as u32,
        n[1] as u32,
        n[2] as u32,
        0,
        (1.0f32 / 0.6).to_bits(),
        0,
        0,
        0,
    ]
}

fn pipeline(d: &wgpu::Device) -> wgpu::ComputePipeline {
    let source = crate::lbm::unroll::unroll(include_str!("../../../shaders/naive_pull.wgsl"));
    let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("naive_pull.wgsl"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("naive_pull"),
        layout: None,
        module: &module,
        entry_point: Some("naive_pull"),
        compilation_options: Default::default(),
        cache: None,
    })
}

/// The bind group of a step from lattice `src` into lattice `dst`.
fn bind_group(
    d: &wgpu::Device,
    pipeline: &wgpu::ComputePipeline,
    uniform: &wgpu::Buffer,
    [src, dst]: [&wgpu::Buffer; 2],
    layout: &Layout,
) -> wgpu::BindGroup {
    fn range(buffer: &wgpu::Buffer, offset: u64, size: u64) -> wgpu::BindingResource<'_> {
        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer,
            offset,
            size: std::num::NonZeroU64::new(size),
        })
    }
    let resources = [
        uniform.as_entire_binding(),
        range(src, 0, layout.lo_bytes),
        range(src, layout.hi_offset, layout.hi_bytes),
        range(dst, 0, layout.lo_bytes),
        range(dst, layout.hi_offset, layout.hi_bytes),
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
}
