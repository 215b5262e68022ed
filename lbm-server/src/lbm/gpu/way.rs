//! The ways of stepping the lattice, each a fluid kernel ([`Kernel`]) and a way of giving the
//! covered cells their solid term ([`CoveredCells`]): each way's kernels, compiled from lbm.wgsl,
//! cells.wgsl and imb.wgsl with its constants, its cell list and parameters, and its bind groups.

use super::bindings::{make_bind_group, storage_buffer};
use super::cell_list::CellList;
use super::device::Gpu;
use super::params::{params, Params};
use super::region::Regions;
use super::state::GpuLattice;
use crate::lbm::imb::{Coupling, CoveredCells, ImbBlock, Passes, SolidCollision};
use crate::lbm::kernel::Kernel;
use crate::lbm::storage::{Storage, StorageOnDevice};
use wgpu::util::DeviceExt;

/// The kernels' source, kept in their own files: the lattice, and the immersed moving boundary
/// (imb.wgsl and its parts, in order: imb.wgsl's header).
pub const SHADER: &str = include_str!("../../../../shaders/lbm.wgsl");
pub const IMB_SHADER: &str = concat!(
    include_str!("../../../../shaders/imb.wgsl"),
    "\n",
    include_str!("../../../../shaders/imb_covered.wgsl"),
    "\n",
    include_str!("../../../../shaders/imb_solid_term.wgsl"),
    "\n",
    include_str!("../../../../shaders/imb_loads.wgsl"),
);
/// The per-cell kernel (`Kernel::Cells`).
const CELLS_SHADER: &str = include_str!("../../../../shaders/cells.wgsl");
/// The redo's list of covered cells with one atomic per subgroup, and with one per cell.
const LIST_SUBGROUP: &str = include_str!("../../../../shaders/list_subgroup.wgsl");
const LIST_ATOMIC: &str = include_str!("../../../../shaders/list_atomic.wgsl");

/// One way of stepping the lattice: the fluid kernels ([`Kernel`]) and the way of giving the
/// covered cells their solid term ([`CoveredCells`]), compiled with their constants, with the
/// cell classes the kernels take, their list and parameters, the coupling's passes, and the bind
/// groups over the lattice's buffers. Every way leaves the same populations after a step (bit for
/// bit), so a lattice may change ways between steps.
pub(in crate::lbm) struct Way {
    pub(in crate::lbm) mode: CoveredCells,
    pub(in crate::lbm) kernel: Kernel,
    /// The classes of the cell list (see `CellList`).
    pub(super) classes: CellList,
    pub(super) cell_list: wgpu::Buffer,
    pub(super) params: Vec<wgpu::Buffer>,
    pub(in crate::lbm) bind_groups: [wgpu::BindGroup; 2],
    /// The fluid kernels.
    pub(super) fluid: FluidKernels,
    pub(super) macroscopic: wgpu::ComputePipeline,
    /// The coupling's passes, when the lattice has particles.
    pub(in crate::lbm) passes: Option<Passes>,
    /// The regions a step is split into, where the lattice has them (`region.rs`).
    pub(super) regions: Option<Regions>,
}

/// The pipelines of a [`Kernel`].
pub(super) enum FluidKernels {
    Quads {
        /// The boundary cells, either parity.
        stream_collide: wgpu::ComputePipeline,
        /// The other fluid cells: even step of all, odd step of the interior, odd step of the
        /// wrapping.
        stream_collide_fluid: [wgpu::ComputePipeline; 3],
        /// The even step of quads (four consecutive cells) of interior or wrapping cells.
        stream_collide_quads: Option<wgpu::ComputePipeline>,
        /// The odd step of quads of interior cells.
        stream_collide_quads_odd: Option<wgpu::ComputePipeline>,
    },
    /// Every cell, either parity.
    Cells(wgpu::ComputePipeline),
}

impl FluidKernels {
    fn pipelines(&self) -> Vec<&wgpu::ComputePipeline> {
        match self {
            FluidKernels::Quads {
                stream_collide,
                stream_collide_fluid,
                stream_collide_quads,
                stream_collide_quads_odd,
            } => std::iter::once(stream_collide)
                .chain(stream_collide_fluid)
                .chain(stream_collide_quads)
                .chain(stream_collide_quads_odd)
                .collect(),
            FluidKernels::Cells(cells) => vec![cells],
        }
    }
}

impl GpuLattice {
    /// Makes the steps from the next on give the covered cells their solid term the way `mode`
    /// says (`Auto` taken as the redo), with the fluid kernels they take now.
    #[cfg(test)]
    pub fn set_covered_cells(&mut self, mode: CoveredCells) -> Result<(), String> {
        self.set_way(self.kernel(), mode)
    }

    /// The fluid kernels the steps take now.
    pub fn kernel(&self) -> Kernel {
        self.way().kernel
    }

    /// Makes the steps from the next on take the fluid kernels `kernel` and give the covered
    /// cells their solid term the way `mode` says (`Auto` taken as the redo), building that way's
    /// kernels the first time it is asked for. Every way leaves the same populations bit for bit
    /// (the reference tests run each), so a run may change ways between any two steps
    /// (`trials::Trial`). A way whose kernels the device does not build (a validation, internal
    /// or out-of-memory error: a driver's compiler refusing a kernel) leaves the lattice as it
    /// was and says why.
    pub fn set_way(&mut self, kernel: Kernel, mode: CoveredCells) -> Result<(), String> {
        let mode = mode.definite();
        if let Some(k) = self
            .ways
            .iter()
            .position(|w| w.mode == mode && w.kernel == kernel)
        {
            self.active = k;
            return Ok(());
        }
        let d = self.gpu.device.clone();
        let scopes = [
            wgpu::ErrorFilter::OutOfMemory,
            wgpu::ErrorFilter::Internal,
            wgpu::ErrorFilter::Validation,
        ]
        .map(|filter| d.push_error_scope(filter));
        let way = self.build_way(kernel, mode);
        self.compile_kernels(&way);
        let errors: Vec<String> = scopes
            .into_iter()
            .rev()
            .filter_map(|scope| pollster::block_on(scope.pop()))
            .map(|e| e.to_string())
            .collect();
        if !errors.is_empty() {
            return Err(format!(
                "the covered cells' {} kernels could not be built on {} (with the {} fluid kernels): {}",
                mode.name(),
                self.gpu.adapter.name,
                kernel.name(),
                errors.join("; ")
            ));
        }
        self.ways.push(way);
        self.active = self.ways.len() - 1;
        Ok(())
    }

    /// The way the steps take now.
    pub(in crate::lbm) fn way(&self) -> &Way {
        &self.ways[self.active]
    }

    /// The kernels, cell classes, parameters and bind groups of one way.
    fn build_way(&self, kernel: Kernel, mode: CoveredCells) -> Way {
        let quads = self.takes_quads(kernel, mode);
        let classes = CellList::new(&self.setup, quads);
        // The per-cell kernel reads no cell list.
        let list: &[u32] = match kernel {
            Kernel::Quads if !classes.list.is_empty() => &classes.list,
            _ => &[0u32],
        };
        let (cell_list, params) = self.list_and_params(list, &classes);
        let constants = self.way_constants(mode);
        let pipeline_kind = |entry: &str, kind: u32| self.pipeline(entry, &constants, kind);
        let pipeline_part = |entry: &str, kind: u32, part: u32| match part {
            0 => pipeline_kind(entry, kind),
            _ => {
                let mut constants = constants.clone();
                constants.push(("STORE_PART", f64::from(part)));
                self.pipeline(entry, &constants, kind)
            }
        };
        let pipeline = |entry: &str| pipeline_kind(entry, 0);
        let bind_groups = [0, 1].map(|parity| self.bind_group(&params[parity], &cell_list));
        let fluid = match kernel {
            Kernel::Quads => FluidKernels::Quads {
                stream_collide: pipeline("stream_collide"),
                stream_collide_fluid: [0, 1, 2].map(|kind| pipeline_kind("stream_collide_fluid", kind)),
                stream_collide_quads: (classes.quads > 0).then(|| pipeline("stream_collide_quads")),
                stream_collide_quads_odd: (classes.interior_quads > 0)
                    .then(|| pipeline("stream_collide_quads_odd")),
            },
            Kernel::Cells => FluidKernels::Cells(pipeline("stream_collide_cells")),
        };
        let mut way = Way {
            mode,
            kernel,
            fluid,
            macroscopic: pipeline("macroscopic"),
            passes: self
                .options
                .map(|o| Passes::new(mode, o.block.is_some(), &pipeline_part)),
            classes,
            cell_list,
            params,
            bind_groups,
            regions: None,
        };
        if self.region_of.is_some() {
            way.regions = Some(self.build_regions(&way));
        }
        way
    }

    /// The cell list `list` on the device, and the parameters of each parity with the cells'
    /// `classes` (a way's, or a region's: `region.rs`).
    pub(super) fn list_and_params(
        &self,
        list: &[u32],
        classes: &CellList,
    ) -> (wgpu::Buffer, Vec<wgpu::Buffer>) {
        let d = &self.gpu.device;
        let cell_list = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("cell list"),
            contents: bytemuck::cast_slice(list),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let params: Vec<wgpu::Buffer> = (0..2)
            .map(|parity| {
                let p = params(&self.setup, parity, self.health, classes, self.face_scale);
                d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("params"),
                    contents: bytemuck::bytes_of(&p),
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                })
            })
            .collect();
        (cell_list, params)
    }

    /// Whether the way of `kernel` and `mode` takes the four-cell quads. Fused, the quads'
    /// kernels give the covered cells their solid term one cell at a time, without the four-cell
    /// quads (the term would be compiled into them four times); skip's quads leave their covered
    /// cells as they are (`skipped_lanes`). The quads' vector accesses move four f32
    /// populations: FP32 only.
    pub(super) fn takes_quads(&self, kernel: Kernel, mode: CoveredCells) -> bool {
        kernel == Kernel::Quads && self.setup.storage == Storage::Fp32 && !mode.fuses()
    }

    /// The shaders' override constants of a way: the operator, the forcing, the coupling's
    /// settings and `mode`.
    pub(super) fn way_constants(&self, mode: CoveredCells) -> Vec<(&'static str, f64)> {
        let imb = self.options;
        let flag = |on: bool| f64::from(u8::from(on));
        let superposition = imb.is_some_and(|o| o.solid_collision == SolidCollision::Superposition);
        let mut constants = vec![
            ("OPERATOR", self.setup.operator.code() as f64),
            ("FORCE", flag(self.setup.force != [0.0; 3])),
            ("SLOTS", imb.map_or(2, |o| o.slots) as f64),
            ("SEED_WEIGHTING", flag(imb.is_some_and(|o| o.seed_weighting))),
            ("SUPERPOSITION", flag(superposition)),
            ("FUSED", flag(mode.fused())),
            ("SKIP", flag(mode == CoveredCells::Skip)),
            ("BY_POPULATION", flag(self.gpu.list.by_population)),
        ];
        constants.extend(ImbBlock::constants(imb.and_then(|o| o.block)));
        constants
    }

    /// The kernel `entry` of the lattice's module with a way's `constants` and KIND `kind`.
    pub(super) fn pipeline(
        &self,
        entry: &str,
        constants: &[(&str, f64)],
        kind: u32,
    ) -> wgpu::ComputePipeline {
        let mut constants = constants.to_vec();
        constants.push(("KIND", f64::from(kind)));
        #[cfg(test)]
        if self.spoil_next_way {
            constants.push(("NO_SUCH_CONSTANT", 1.0));
        }
        self.gpu
            .device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&self.pipeline_layout),
                module: &self.module,
                entry_point: Some(entry),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants: &constants,
                    ..Default::default()
                },
                cache: None,
            })
    }

    /// Dispatches every kernel of `way` once over no cell (zero counts in the parameters, no
    /// particle, an empty list of covered cells: each returns at once), bound to scratch buffers
    /// so that a way built during a run leaves its state alone. CPU drivers such as lavapipe
    /// compile a kernel at its first dispatch: without this the first steps of a run stalled for
    /// seconds with a cold shader cache (5-9 s on this 2-core machine for 16^3 cells with
    /// particles), while the run should be watching its peer (`tests/failures.rs`).
    pub(super) fn compile_kernels(&self, way: &Way) {
        let d = &self.gpu.device;
        let empty = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("params: no cell"),
            contents: bytemuck::bytes_of(&<Params as bytemuck::Zeroable>::zeroed()),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let scratch = |label: &str| storage_buffer(d, label, 64);
        let populations: Vec<wgpu::Buffer> = (0..19).map(|_| scratch("scratch population")).collect();
        let bind_group = make_bind_group(
            d,
            &self.layout,
            [
                &empty,
                &self.flags,
                &self.mrt,
                &scratch("scratch fields"),
                &scratch("scratch status"),
            ],
            &populations,
            &Coupling::new(d, None, 0),
            &way.cell_list,
        );
        let mut kernels = way.fluid.pipelines();
        kernels.push(&way.macroscopic);
        kernels.extend(way.passes.iter().flat_map(|p| p.kernels()));
        kernels.extend(way.regions.iter().flat_map(|r| &r.cells_listed));
        let mut encoder = d.create_command_encoder(&Default::default());
        for kernel in kernels {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(kernel);
            pass.set_bind_group(0, &bind_group, &[]);
            pass.dispatch_workgroups(1, 1, 1);
        }
        self.gpu.queue.submit([encoder.finish()]);
        self.gpu.wait();
    }
}

/// lbm.wgsl, cells.wgsl and imb.wgsl with the list's join for this device (subgroups or one atomic per cell)
/// and the populations' `storage` (its buffers and load/store pair; the quads with FP32), unrolled
/// and compiled once.
pub(super) fn shader_module(gpu: &Gpu, storage: Storage) -> wgpu::ShaderModule {
    let list = if gpu.list.subgroups {
        LIST_SUBGROUP
    } else {
        LIST_ATOMIC
    };
    let storage = storage.shader();
    let source = format!("{SHADER}\n{CELLS_SHADER}\n{IMB_SHADER}\n{list}\n{storage}");
    gpu.device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("lbm.wgsl + imb.wgsl"),
        source: wgpu::ShaderSource::Wgsl(crate::lbm::unroll::unroll(&source).into()),
    })
}
