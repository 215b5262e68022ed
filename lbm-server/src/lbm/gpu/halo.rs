//! The halo kernels of a lattice decomposed over ranks (halo.wgsl): the stored bits of the
//! populations of one layer of cells packed into a flat buffer of words and read back, or written
//! from one (a population a word with 32-bit storage, two with 16-bit storage: a message carries
//! what the storage holds, bit for bit, in as few bytes). Which populations, and where they go, is
//! `crate::parallel::halo`'s business.

use super::bindings::{storage_buffer, storage_entry};
use super::state::GpuLattice;
use crate::lbm::storage::StorageOnDevice;
use wgpu::util::DeviceExt;

const HALO_SHADER: &str = include_str!("../../../../shaders/halo.wgsl");
/// Invocations per workgroup (`@workgroup_size` in halo.wgsl).
const WORKGROUP: u32 = 64;

/// The pack and unpack kernels of one lattice.
pub struct HaloKernels {
    layout: wgpu::BindGroupLayout,
    pack: wgpu::ComputePipeline,
    unpack: wgpu::ComputePipeline,
    /// Populations per word of a message (`PER_WORD` in halo.wgsl): 4 bytes over the storage's.
    per_word: u32,
}

/// One layer's populations: their list of (cell, direction), their words on the device, and a
/// buffer to read them back through.
pub struct HaloLayer {
    words: u32,
    values: wgpu::Buffer,
    readback: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

impl HaloLayer {
    /// Words of the layer's message (its populations' stored bits, packed).
    pub fn words(&self) -> usize {
        self.words as usize
    }
}

impl GpuLattice {
    /// Compiles the halo kernels for this lattice's storage.
    pub fn halo_kernels(&self) -> HaloKernels {
        let d = &self.gpu.device;
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("halo"),
            entries: &[storage_entry(0, true), storage_entry(1, false)],
        });
        let pipeline_layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("halo"),
            bind_group_layouts: &[Some(&self.layout), Some(&layout)],
            immediate_size: 0,
        });
        let source = format!("{}\n{HALO_SHADER}", self.setup.storage.access_shader());
        let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("halo.wgsl"),
            source: wgpu::ShaderSource::Wgsl(crate::lbm::unroll::unroll(&source).into()),
        });
        let per_word = (4 / self.setup.storage.bytes()) as u32;
        let pipeline = |unpack: bool| {
            d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(if unpack { "halo unpack" } else { "halo pack" }),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some("halo"),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants: &[
                        ("UNPACK", f64::from(u8::from(unpack))),
                        ("PER_WORD", f64::from(per_word)),
                    ],
                    ..Default::default()
                },
                cache: None,
            })
        };
        HaloKernels {
            pack: pipeline(false),
            unpack: pipeline(true),
            layout,
            per_word,
        }
    }

    /// A layer of the populations `entries` lists, each (cell, direction) in this lattice.
    pub fn halo_layer(&self, kernels: &HaloKernels, entries: &[[u32; 2]]) -> HaloLayer {
        let d = &self.gpu.device;
        let list = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("halo list"),
            contents: bytemuck::cast_slice(entries),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let words = (entries.len() as u32).div_ceil(kernels.per_word);
        let bytes = (words as u64 * 4).max(4);
        let values = storage_buffer(d, "halo words", bytes);
        let readback = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("halo readback"),
            size: bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("halo"),
            layout: &kernels.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: list.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: values.as_entire_binding(),
                },
            ],
        });
        HaloLayer {
            words,
            values,
            readback,
            bind_group,
        }
    }

    /// The populations of each layer, packed and read back (one submission, one wait).
    pub fn pack_halo(&self, kernels: &HaloKernels, layers: &[&HaloLayer]) -> Vec<Vec<u32>> {
        let packed = self.submit_pack(kernels, layers);
        self.read_packed(layers, packed)
    }

    /// Packs the populations of each layer and copies them where the host reads them, in a
    /// submission of their own (returned), their read-back asked for: what the device does next
    /// may run while the host waits for them alone ([`GpuLattice::read_packed`]).
    pub fn submit_pack(&self, kernels: &HaloKernels, layers: &[&HaloLayer]) -> wgpu::SubmissionIndex {
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        for layer in layers {
            self.dispatch_halo(&mut encoder, &kernels.pack, layer);
            encoder.copy_buffer_to_buffer(&layer.values, 0, &layer.readback, 0, layer.readback.size());
        }
        let packed = self.gpu.queue.submit([encoder.finish()]);
        for layer in layers {
            layer.readback.slice(..).map_async(wgpu::MapMode::Read, |_| {});
        }
        packed
    }

    /// The layers' words that the submission `packed` ([`GpuLattice::submit_pack`]) packed,
    /// once it is done (later submissions may still run).
    pub fn read_packed(&self, layers: &[&HaloLayer], packed: wgpu::SubmissionIndex) -> Vec<Vec<u32>> {
        self.gpu.wait_for(packed);
        layers
            .iter()
            .map(|layer| {
                let slice = layer.readback.slice(..);
                let words: Vec<u32> = {
                    let bytes = slice.get_mapped_range().expect("mapped");
                    bytemuck::cast_slice(&bytes)[..layer.words()].to_vec()
                };
                layer.readback.unmap();
                words
            })
            .collect()
    }

    /// Writes `words` into each layer's populations (submitted, not waited for: the next step
    /// or pack follows it in the queue).
    pub fn unpack_halo(&self, kernels: &HaloKernels, layers: &[(&HaloLayer, &[u32])]) {
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        for (layer, words) in layers {
            assert_eq!(words.len(), layer.words(), "a halo message of the layer's length");
            if !words.is_empty() {
                self.gpu
                    .queue
                    .write_buffer(&layer.values, 0, bytemuck::cast_slice(words));
            }
            self.dispatch_halo(&mut encoder, &kernels.unpack, layer);
        }
        self.gpu.queue.submit([encoder.finish()]);
    }

    fn dispatch_halo(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        pipeline: &wgpu::ComputePipeline,
        layer: &HaloLayer,
    ) {
        let groups = layer.words.div_ceil(WORKGROUP);
        if groups == 0 {
            return;
        }
        let x = groups.min(65_535);
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &self.way().bind_groups[0], &[]);
        pass.set_bind_group(1, &layer.bind_group, &[]);
        pass.dispatch_workgroups(x, groups.div_ceil(x), 1);
    }
}
