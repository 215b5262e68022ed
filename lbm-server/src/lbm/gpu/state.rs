//! A lattice living on the GPU: its buffers, kernels and clock, made at rest, and its
//! populations set and read back in natural layout.

use super::bindings::{bind_group_layout, fits_device, LatticeBuffers};
use super::device::Gpu;
use super::health::Health;
use super::way::{shader_module, Way};
use crate::lbm::d3q19::{opposite, C, W};
use crate::lbm::geometry::{Cell, Link, Setup};
use crate::lbm::imb::{Coupling, CoveredCells, ImbOptions};
use crate::lbm::storage::StorageOnDevice;

/// A lattice living on the GPU.
pub struct GpuLattice {
    pub setup: Setup,
    pub(in crate::lbm) gpu: std::sync::Arc<Gpu>,
    pub(super) populations: Vec<wgpu::Buffer>,
    pub(super) flags: wgpu::Buffer,
    pub(super) mrt: wgpu::Buffer,
    pub(in crate::lbm) fields: wgpu::Buffer,
    pub(in crate::lbm) status: wgpu::Buffer,
    pub(super) layout: wgpu::BindGroupLayout,
    /// lbm.wgsl + imb.wgsl, compiled once; each way's pipelines set its constants.
    pub(super) module: wgpu::ShaderModule,
    pub(super) pipeline_layout: wgpu::PipelineLayout,
    pub(super) health: Health,
    /// The coupling's settings (None: a lattice without particles).
    pub(in crate::lbm) options: Option<ImbOptions>,
    /// Particle coupling (immersed moving boundary), when the scene has particles.
    pub(in crate::lbm) imb: Option<Coupling>,
    /// The ways built so far ([`GpuLattice::set_covered_cells`]), and the one the steps take.
    pub(super) ways: Vec<Way>,
    pub(super) active: usize,
    /// The regions, and each cell's, where the steps may be split into regions (`region.rs`).
    pub(super) region_of: Option<(usize, Vec<u8>)>,
    /// Completed steps; its parity selects the AA phase.
    pub time: u64,
    /// The share of their velocity the velocity inlets and moving walls have now
    /// ([`GpuLattice::set_face_scale`]).
    pub(super) face_scale: f64,
    /// The fields of the last check that passed, kept on the device ([`GpuLattice::keep_fields`]).
    pub(super) kept: Option<wgpu::Buffer>,
    /// Test aid: the next way built gets a constant its kernels do not declare (a validation
    /// error, as a driver refusing a kernel would give).
    #[cfg(test)]
    pub(crate) spoil_next_way: bool,
}

impl GpuLattice {
    /// Allocates the lattice, at rest (rho = 1, u = 0), with particle coupling when `imb` is given,
    /// stepped by the setup's fluid kernels.
    pub fn new(
        gpu: std::sync::Arc<Gpu>,
        setup: Setup,
        health: Health,
        imb: Option<ImbOptions>,
    ) -> Result<GpuLattice, String> {
        fits_device(&gpu.limits, setup.n)?;
        let d = &gpu.device;
        let buffers = LatticeBuffers::new(d, &setup);
        let coupling = Coupling::new(d, imb, setup.cells());
        let storage = setup.storage;
        let module = shader_module(&gpu, storage);
        let layout = bind_group_layout(d);
        let pipeline_layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("lattice"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let LatticeBuffers {
            populations,
            flags,
            mrt,
            fields,
            status,
        } = buffers;
        let mut lattice = GpuLattice {
            setup,
            gpu,
            populations,
            flags,
            mrt,
            fields,
            status,
            layout,
            module,
            pipeline_layout,
            health,
            options: imb,
            imb: Some(coupling),
            ways: Vec::new(),
            active: 0,
            region_of: None,
            time: 0,
            face_scale: 1.0,
            kept: None,
            #[cfg(test)]
            spoil_next_way: false,
        };
        let mode = imb.map_or(CoveredCells::Redo, |o| o.covered_cells);
        lattice.set_way(lattice.setup.kernel, mode)?;
        Ok(lattice)
    }

    /// Whether the lattice's device is a CPU driver, not a GPU.
    pub fn on_cpu(&self) -> bool {
        self.gpu.on_cpu()
    }

    /// Waits until the device has done every step submitted.
    pub fn finish(&self) {
        self.gpu.wait();
    }

    /// Name of the GPU adapter.
    pub fn adapter(&self) -> &str {
        &self.gpu.adapter.name
    }

    /// Replaces the populations (shifted, natural layout) and restarts the AA phase at even.
    pub fn upload(&self, f: &[Cell]) {
        let storage = self.setup.storage;
        for (i, buffer) in self.populations.iter().enumerate() {
            let column: Vec<f32> = f.iter().map(|c| c[i] as f32).collect();
            let mut bytes = storage.encode(&column);
            bytes.resize(bytes.len().next_multiple_of(4), 0);
            self.gpu.queue.write_buffer(buffer, 0, &bytes);
        }
    }

    /// Sets populations and resets the clock to an even step.
    pub fn set_populations(&mut self, f: &[Cell]) {
        self.upload(f);
        self.time = 0;
    }

    /// Gives the velocity inlets and moving walls `scale` times the velocity of their face from
    /// The populations (shifted) at the current time in natural layout, whatever the AA phase.
    pub fn populations(&self) -> Vec<Cell> {
        let columns: Vec<Vec<f32>> = self
            .populations
            .iter()
            .map(|b| {
                let storage = self.setup.storage;
                let cells = self.setup.cells();
                let bytes = (cells * storage.bytes()).next_multiple_of(4) as u64;
                storage.decode(&self.gpu.read_buffer(b, bytes), cells)
            })
            .collect();
        (0..self.setup.cells())
            .map(|k| {
                std::array::from_fn(|i| {
                    if self.time.is_multiple_of(2) || self.setup.solid[k] {
                        return columns[i][k] as f64;
                    }
                    // Odd phase: f_i(x) sits in slot opposite(i) of x - c_i, or in slot i of x
                    // when that link leaves the fluid.
                    match self.setup.link(k, C[opposite(i)]) {
                        Link::Cell(s) => columns[opposite(i)][s] as f64,
                        Link::Boundary(..) => columns[i][k] as f64,
                    }
                })
            })
            .collect()
    }
}

/// Shifted equilibrium populations of a whole lattice for given density and velocity per cell.
pub fn equilibrium_field(setup: &Setup, state: impl Fn([usize; 3]) -> (f64, [f64; 3])) -> Vec<Cell> {
    (0..setup.cells())
        .map(|k| {
            let (rho, u) = state(setup.coords(k));
            std::array::from_fn(|i| crate::lbm::d3q19::equilibrium_shifted(i, rho, u))
        })
        .collect()
}

/// Total mass sum(rho) of the fluid cells, from shifted populations.
pub fn total_mass(setup: &Setup, f: &[Cell]) -> f64 {
    (0..setup.cells())
        .filter(|k| !setup.solid[*k])
        .map(|k| f[k].iter().zip(W.iter()).map(|(fi, wi)| fi + wi).sum::<f64>())
        .sum()
}
