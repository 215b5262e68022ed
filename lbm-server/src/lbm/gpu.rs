//! The lattice on the GPU (wgpu): buffers, pipelines and the AA-pattern step loop.

use super::geometry::{Cell, Face, Link, Operator, Setup};
use super::lattice::{opposite, C, W};
use super::mrt;
use wgpu::util::DeviceExt;

/// The kernels' source, kept in their own files: the lattice and the immersed moving boundary.
pub const SHADER: &str = include_str!("../../../shaders/lbm.wgsl");
pub const IMB_SHADER: &str = include_str!("../../../shaders/imb.wgsl");
/// The redo's list of covered cells with one atomic per subgroup, and with one per cell.
const LIST_SUBGROUP: &str = include_str!("../../../shaders/list_subgroup.wgsl");
const LIST_ATOMIC: &str = include_str!("../../../shaders/list_atomic.wgsl");

/// Invocations per workgroup (must match `@workgroup_size` in the shader).
const WORKGROUP: u32 = 64;
/// Most workgroups along one dispatch dimension.
const MAX_GROUPS: u32 = 65_535;
/// Bindings before the 19 population buffers.
const FIRST_POPULATION_BINDING: u32 = 5;
/// The immersed-boundary bindings follow the populations: particles, pairs, covered, slots, info.
pub(super) const FIRST_IMB_BINDING: u32 = FIRST_POPULATION_BINDING + 19;
/// The cell list (read-only) follows them.
const CELL_LIST_BINDING: u32 = FIRST_IMB_BINDING + 5;
/// The particles' force and torque (the coupling's output, the only part read back).
const LOADS_BINDING: u32 = CELL_LIST_BINDING + 1;
const BINDINGS: u32 = LOADS_BINDING + 1;

/// The device and its queue.
#[derive(Clone)]
pub struct Gpu {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub adapter: wgpu::AdapterInfo,
    pub limits: wgpu::Limits,
    /// How the redo's list of covered cells is kept (imb.wgsl): on a GPU by population and joined
    /// with subgroup operations, on a CPU driver (where both cost) cell by cell with one atomic
    /// per cell.
    pub list: ListLayout,
}

/// The redo's list of covered cells ([`Gpu::list`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ListLayout {
    /// Cells join the list with one atomic per subgroup (list_subgroup.wgsl), not one per cell
    /// (list_atomic.wgsl): where the device has subgroups, is not a CPU, and LBM_NO_SUBGROUPS is
    /// not set.
    pub subgroups: bool,
    /// The records as structure of arrays, each population in a run of its own (a GPU warp's
    /// accesses to one population in 4 sectors instead of 32), not one record per cell: on all but
    /// CPU drivers.
    pub by_population: bool,
}

/// What an adapter offers the lattice: enough to choose one and to say why none will do.
#[derive(Debug, Clone, PartialEq)]
struct AdapterOffer {
    name: String,
    backend: wgpu::Backend,
    device_type: wgpu::DeviceType,
    storage_buffers: u32,
}

impl AdapterOffer {
    fn of(adapter: &wgpu::Adapter) -> AdapterOffer {
        let info = adapter.get_info();
        AdapterOffer {
            name: info.name,
            backend: info.backend,
            device_type: info.device_type,
            storage_buffers: adapter.limits().max_storage_buffers_per_shader_stage,
        }
    }
}

/// The adapter to run on: of those with the [`BINDINGS`] storage buffers a lattice kernel binds,
/// a discrete GPU before an integrated one, before a virtual one, before a CPU driver (Mesa
/// lavapipe), and within each kind a Vulkan, Metal or DirectX 12 driver before OpenGL; the first
/// listed of equals. None: an error that names every adapter found and what it lacks (where
/// only OpenGL is found, as where Vulkan is not installed: its llvmpipe binds 16).
fn choose_adapter(found: &[AdapterOffer]) -> Result<usize, String> {
    let rank = |a: &AdapterOffer| {
        let kind = match a.device_type {
            wgpu::DeviceType::DiscreteGpu => 0,
            wgpu::DeviceType::IntegratedGpu => 1,
            wgpu::DeviceType::VirtualGpu => 2,
            wgpu::DeviceType::Cpu => 3,
            wgpu::DeviceType::Other => 4,
        };
        (kind, u8::from(a.backend == wgpu::Backend::Gl))
    };
    let usable = found
        .iter()
        .enumerate()
        .filter(|(_, a)| a.storage_buffers >= BINDINGS);
    if let Some((i, _)) = usable.min_by_key(|(i, a)| (rank(a), *i)) {
        return Ok(i);
    }
    const INSTALL: &str = "on a machine without a GPU install Mesa lavapipe (Debian: apt-get install mesa-vulkan-drivers libvulkan1), on one with a GPU its Vulkan driver";
    if found.is_empty() {
        return Err(format!("no GPU adapter found ({INSTALL})"));
    }
    let each: Vec<String> = found
        .iter()
        .map(|a| {
            format!(
                "{} ({:?}, {:?}) binds {}",
                a.name, a.backend, a.device_type, a.storage_buffers
            )
        })
        .collect();
    Err(format!(
        "no adapter binds the {BINDINGS} storage buffers per shader stage that the lattice's kernels need: {} ({INSTALL})",
        each.join("; ")
    ))
}

impl Gpu {
    /// Opens the adapter [`choose_adapter`] picks among those of the backends allowed by
    /// WGPU_BACKEND (default: all).
    pub fn new() -> Result<Gpu, String> {
        // WGPU_BACKEND (vulkan, metal, dx12, gl) and friends are honoured.
        let mut descriptor = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        // wgpu checks each indirect dispatch's workgroup counts with a dispatch of its own and two
        // barriers, four times per coupled step with the redo; `covered_groups` (imb.wgsl) writes
        // them within the limits itself. WGPU_VALIDATION_INDIRECT_CALL=1 turns the check back on.
        descriptor.flags = (descriptor.flags - wgpu::InstanceFlags::VALIDATION_INDIRECT_CALL).with_env();
        let backends = descriptor.backends;
        let instance = wgpu::Instance::new(descriptor);
        let adapters = pollster::block_on(instance.enumerate_adapters(backends));
        let found: Vec<AdapterOffer> = adapters.iter().map(AdapterOffer::of).collect();
        let chosen = choose_adapter(&found)?;
        let adapter = adapters
            .into_iter()
            .nth(chosen)
            .expect("an index into the adapters");
        let limits = adapter.limits();
        // Timestamps between passes where the device has them (`bench --passes`: each pass's time
        // by the device's clock).
        let stamps = wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS;
        let wanted = stamps | wgpu::Features::SUBGROUP;
        let on_gpu = adapter.get_info().device_type != wgpu::DeviceType::Cpu;
        let list = ListLayout {
            subgroups: on_gpu
                && adapter.features().contains(wgpu::Features::SUBGROUP)
                && std::env::var_os("LBM_NO_SUBGROUPS").is_none(),
            by_population: on_gpu,
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("lbm"),
            required_limits: limits.clone(),
            required_features: adapter.features() & wanted,
            ..Default::default()
        }))
        .map_err(|e| format!("cannot open the GPU device: {e}"))?;
        Ok(Gpu {
            device,
            queue,
            adapter: adapter.get_info(),
            limits,
            list,
        })
    }

    /// Waits until the queue is idle.
    pub fn wait(&self) {
        let _ = self.device.poll(wgpu::PollType::wait_indefinitely());
    }

    /// The same device with another layout of the covered cells' list (tests: every layout on
    /// one device; subgroups only where it has them).
    #[cfg(test)]
    pub fn with_list(&self, list: ListLayout) -> Gpu {
        assert!(!list.subgroups || self.device.features().contains(wgpu::Features::SUBGROUP));
        Gpu { list, ..self.clone() }
    }

    /// Waits for one submission (and those before it) only: later ones may still run.
    pub fn wait_for(&self, submission: wgpu::SubmissionIndex) {
        let _ = self.device.poll(wgpu::PollType::Wait {
            submission_index: Some(submission),
            timeout: None,
        });
    }

    /// Copies a GPU buffer back to the host.
    pub fn read_buffer(&self, buffer: &wgpu::Buffer, bytes: u64) -> Vec<u8> {
        self.read_range(buffer, 0, bytes)
    }

    /// `bytes` of `buffer` from `offset` (both multiples of 4).
    pub fn read_range(&self, buffer: &wgpu::Buffer, offset: u64, bytes: u64) -> Vec<u8> {
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(buffer, offset, &staging, 0, bytes);
        self.queue.submit([encoder.finish()]);
        let slice = staging.slice(..);
        slice.map_async(wgpu::MapMode::Read, |_| {});
        self.wait();
        let data = slice.get_mapped_range().expect("mapped").to_vec();
        staging.unmap();
        data
    }
}

/// Parameters as laid out in the shader's `Params`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    n: [u32; 4],
    face_lo: [u32; 4],
    face_hi: [u32; 4],
    relax: [f32; 4],
    force: [f32; 4],
    face_value: [[f32; 4]; 6],
    ranges: [u32; 4],
    quads: [u32; 4],
    wrapped: [u32; 4],
}

/// Limits of the health check, in lattice units.
#[derive(Debug, Clone, Copy)]
pub struct Health {
    /// Largest speed |u| allowed.
    pub max_speed: f64,
    /// Largest |rho - 1| allowed.
    pub max_density_deviation: f64,
}

impl Default for Health {
    fn default() -> Self {
        Self {
            max_speed: 0.4,
            max_density_deviation: 0.5,
        }
    }
}

/// A lattice living on the GPU.
pub struct Lattice {
    pub setup: Setup,
    pub(super) gpu: std::sync::Arc<Gpu>,
    populations: Vec<wgpu::Buffer>,
    flags: wgpu::Buffer,
    mrt: wgpu::Buffer,
    pub(super) fields: wgpu::Buffer,
    pub(super) status: wgpu::Buffer,
    layout: wgpu::BindGroupLayout,
    /// lbm.wgsl + imb.wgsl, compiled once; each way's pipelines set its constants.
    module: wgpu::ShaderModule,
    pipeline_layout: wgpu::PipelineLayout,
    health: Health,
    /// The coupling's settings (None: a lattice without particles).
    options: Option<super::imb::ImbOptions>,
    /// Whether the fluid kernels may take four-cell quads (not with `Lattice::per_cell`).
    quads: bool,
    /// Particle coupling (immersed moving boundary), when the scene has particles.
    pub(super) imb: Option<super::imb::Coupling>,
    /// The ways built so far ([`Lattice::set_covered_cells`]), and the one the steps take.
    ways: Vec<Way>,
    active: usize,
    /// Completed steps; its parity selects the AA phase.
    pub time: u64,
    /// The share of their velocity the velocity inlets and moving walls have now
    /// ([`Lattice::set_face_scale`]).
    face_scale: f64,
    /// The fields of the last check that passed, kept on the device ([`Lattice::keep_fields`]).
    kept: Option<wgpu::Buffer>,
    /// Test aid: the next way built gets a constant its kernels do not declare (a validation
    /// error, as a driver refusing a kernel would give).
    #[cfg(test)]
    pub(super) spoil_next_way: bool,
}

/// One way of giving the covered cells their solid term ([`super::imb::CoveredCells`]): the
/// fluid kernels with its constants and the cell classes they take (four-cell quads or one cell
/// at a time), their list and parameters, the coupling's passes, and the bind groups over the
/// lattice's buffers. Every way leaves the same populations after a step (bit for bit), so a
/// lattice may change ways between steps.
pub(super) struct Way {
    pub(super) mode: super::imb::CoveredCells,
    /// The classes of the cell list (see `CellList`).
    classes: CellList,
    cell_list: wgpu::Buffer,
    params: Vec<wgpu::Buffer>,
    pub(super) bind_groups: [wgpu::BindGroup; 2],
    /// The boundary cells, either parity.
    stream_collide: wgpu::ComputePipeline,
    /// The other fluid cells: even step of all, odd step of the interior, odd step of the wrapping.
    stream_collide_fluid: [wgpu::ComputePipeline; 3],
    /// The even step of quads (four consecutive cells) of interior or wrapping cells.
    stream_collide_quads: Option<wgpu::ComputePipeline>,
    /// The odd step of quads of interior cells.
    stream_collide_quads_odd: Option<wgpu::ComputePipeline>,
    macroscopic: wgpu::ComputePipeline,
    /// The coupling's passes, when the lattice has particles.
    pub(super) passes: Option<super::imb::Passes>,
}

/// The first unhealthy cell found by a health check.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Unhealthy {
    pub cell: usize,
    pub coords: [usize; 3],
    pub rho: f32,
    pub u: [f32; 3],
}

impl Unhealthy {
    /// "cell K at (i, j, k): QUANTITY", naming the quantity that failed the check.
    pub fn describe(&self, health: &Health) -> String {
        let quantity = if !(self.rho.is_finite() && self.u.iter().all(|v| v.is_finite())) {
            format!("non-finite values (density {}, velocity {:?})", self.rho, self.u)
        } else if f64::from((self.rho - 1.0).abs()) > health.max_density_deviation {
            let (lo, hi) = (
                1.0 - health.max_density_deviation,
                1.0 + health.max_density_deviation,
            );
            format!("density {} x the reference, outside [{lo}, {hi}]", self.rho)
        } else {
            let speed = self.u.iter().map(|v| v * v).sum::<f32>().sqrt();
            format!(
                "lattice speed {speed:.3} (Mach {:.2}) above the limit",
                speed * 3f32.sqrt()
            )
        };
        let [x, y, z] = self.coords;
        format!("cell {} at ({x}, {y}, {z}): {quantity}", self.cell)
    }
}

impl Lattice {
    /// Allocates the lattice, at rest (rho = 1, u = 0), with particle coupling when `imb` is given.
    pub fn new(
        gpu: std::sync::Arc<Gpu>,
        setup: Setup,
        health: Health,
        imb: Option<super::imb::ImbOptions>,
    ) -> Result<Lattice, String> {
        Self::build(gpu, setup, health, imb, true)
    }

    /// A lattice without coupling whose fluid kernels take every cell on its own, without the
    /// four-cell quads (`lbm-server bench --per-cell`: what the quads gain on this device).
    pub fn per_cell(gpu: std::sync::Arc<Gpu>, setup: Setup, health: Health) -> Result<Lattice, String> {
        Self::build(gpu, setup, health, None, false)
    }

    fn build(
        gpu: std::sync::Arc<Gpu>,
        setup: Setup,
        health: Health,
        imb: Option<super::imb::ImbOptions>,
        quads: bool,
    ) -> Result<Lattice, String> {
        fits_device(&gpu.limits, setup.n)?;
        let d = &gpu.device;
        let buffers = LatticeBuffers::new(d, &setup);
        let coupling = super::imb::Coupling::new(d, imb, setup.cells());
        let module = shader_module(&gpu);
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
        let mut lattice = Lattice {
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
            quads,
            imb: Some(coupling),
            ways: Vec::new(),
            active: 0,
            time: 0,
            face_scale: 1.0,
            kept: None,
            #[cfg(test)]
            spoil_next_way: false,
        };
        let mode = imb.map_or(super::imb::CoveredCells::Redo, |o| o.covered_cells);
        lattice.set_covered_cells(mode)?;
        Ok(lattice)
    }

    /// Makes the steps from the next on give the covered cells their solid term the way `mode`
    /// says (`Auto` taken as the redo), building that way's kernels the first time it is asked
    /// for. Every way leaves the same populations bit for bit (the reference tests run each), so
    /// a run may change ways between any two steps (`trials::WayTrials`). A way whose kernels the
    /// device does not build (a validation, internal or out-of-memory error: a driver's compiler
    /// refusing a kernel) leaves the lattice as it was and says why.
    pub fn set_covered_cells(&mut self, mode: super::imb::CoveredCells) -> Result<(), String> {
        let mode = mode.definite();
        if let Some(k) = self.ways.iter().position(|w| w.mode == mode) {
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
        let way = self.build_way(mode);
        self.compile_kernels(&way);
        let errors: Vec<String> = scopes
            .into_iter()
            .rev()
            .filter_map(|scope| pollster::block_on(scope.pop()))
            .map(|e| e.to_string())
            .collect();
        if !errors.is_empty() {
            return Err(format!(
                "the covered cells' {} kernels could not be built on {}: {}",
                mode.name(),
                self.gpu.adapter.name,
                errors.join("; ")
            ));
        }
        self.ways.push(way);
        self.active = self.ways.len() - 1;
        Ok(())
    }

    /// The way the steps take now.
    pub(super) fn way(&self) -> &Way {
        &self.ways[self.active]
    }

    /// The kernels, cell classes, parameters and bind groups of one way.
    fn build_way(&self, mode: super::imb::CoveredCells) -> Way {
        let d = &self.gpu.device;
        // Fused, the fluid kernels give the covered cells their solid term one cell at a time,
        // without the four-cell quads (the term would be compiled into them four times); skip's
        // quads leave their covered cells as they are (`skipped_lanes`).
        let classes = CellList::new(&self.setup, self.quads && !mode.fuses());
        let cell_list = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("cell list"),
            contents: bytemuck::cast_slice(if classes.list.is_empty() {
                &[0u32]
            } else {
                &classes.list
            }),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let params: Vec<wgpu::Buffer> = (0..2)
            .map(|parity| {
                let p = params(&self.setup, parity, self.health, &classes, self.face_scale);
                d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("params"),
                    contents: bytemuck::bytes_of(&p),
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                })
            })
            .collect();
        let constants = self.way_constants(mode);
        let pipeline_kind = |entry: &str, kind: u32| self.pipeline(entry, &constants, kind);
        let pipeline = |entry: &str| pipeline_kind(entry, 0);
        let bind_groups = [0, 1].map(|parity| self.bind_group(&params[parity], &cell_list));
        Way {
            mode,
            stream_collide: pipeline("stream_collide"),
            stream_collide_fluid: [0, 1, 2].map(|kind| pipeline_kind("stream_collide_fluid", kind)),
            stream_collide_quads: (classes.quads > 0).then(|| pipeline("stream_collide_quads")),
            stream_collide_quads_odd: (classes.interior_quads > 0)
                .then(|| pipeline("stream_collide_quads_odd")),
            macroscopic: pipeline("macroscopic"),
            passes: self
                .options
                .is_some()
                .then(|| super::imb::Passes::new(mode, &pipeline_kind)),
            classes,
            cell_list,
            params,
            bind_groups,
        }
    }

    /// The shaders' override constants of a way: the operator, the forcing, the coupling's
    /// settings and `mode`.
    fn way_constants(&self, mode: super::imb::CoveredCells) -> Vec<(&'static str, f64)> {
        let imb = self.options;
        let flag = |on: bool| f64::from(u8::from(on));
        let superposition =
            imb.is_some_and(|o| o.solid_collision == super::imb::SolidCollision::Superposition);
        vec![
            ("OPERATOR", self.setup.operator.code() as f64),
            ("FORCE", flag(self.setup.force != [0.0; 3])),
            ("SLOTS", imb.map_or(2, |o| o.slots) as f64),
            ("SEED_WEIGHTING", flag(imb.is_some_and(|o| o.seed_weighting))),
            ("SUPERPOSITION", flag(superposition)),
            ("FUSED", flag(mode.fused())),
            ("SKIP", flag(mode == super::imb::CoveredCells::Skip)),
            ("BY_POPULATION", flag(self.gpu.list.by_population)),
        ]
    }

    /// The kernel `entry` of the lattice's module with a way's `constants` and KIND `kind`.
    fn pipeline(&self, entry: &str, constants: &[(&str, f64)], kind: u32) -> wgpu::ComputePipeline {
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
    fn compile_kernels(&self, way: &Way) {
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
            &super::imb::Coupling::new(d, None, 0),
            &way.cell_list,
        );
        let mut kernels = vec![&way.stream_collide, &way.macroscopic];
        kernels.extend(&way.stream_collide_fluid);
        kernels.extend(
            way.stream_collide_quads
                .iter()
                .chain(&way.stream_collide_quads_odd),
        );
        kernels.extend(way.passes.iter().flat_map(|p| p.kernels()));
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

    /// Name of the GPU adapter.
    pub fn adapter(&self) -> &str {
        &self.gpu.adapter.name
    }

    /// Rebuilds every way's bind groups (after the coupling's buffers grew).
    pub(super) fn rebind(&mut self) {
        let bound: Vec<[wgpu::BindGroup; 2]> = self
            .ways
            .iter()
            .map(|w| [0, 1].map(|parity| self.bind_group(&w.params[parity], &w.cell_list)))
            .collect();
        for (way, groups) in self.ways.iter_mut().zip(bound) {
            way.bind_groups = groups;
        }
    }

    /// The lattice's buffers bound with `params` and a way's `cell_list`.
    fn bind_group(&self, params: &wgpu::Buffer, cell_list: &wgpu::Buffer) -> wgpu::BindGroup {
        make_bind_group(
            &self.gpu.device,
            &self.layout,
            [params, &self.flags, &self.mrt, &self.fields, &self.status],
            &self.populations,
            self.imb.as_ref().expect("coupling buffers"),
            cell_list,
        )
    }

    /// Replaces the populations (shifted, natural layout) and restarts the AA phase at even.
    pub fn upload(&self, f: &[Cell]) {
        for (i, buffer) in self.populations.iter().enumerate() {
            let column: Vec<f32> = f.iter().map(|c| c[i] as f32).collect();
            self.gpu
                .queue
                .write_buffer(buffer, 0, bytemuck::cast_slice(&column));
        }
    }

    /// Sets populations and resets the clock to an even step.
    pub fn set_populations(&mut self, f: &[Cell]) {
        self.upload(f);
        self.time = 0;
    }

    /// Gives the velocity inlets and moving walls `scale` times the velocity of their face from
    /// the next step on (the setup's ramp calls it; the density of an outlet is kept).
    pub fn set_face_scale(&mut self, scale: f64) {
        if scale == self.face_scale {
            return;
        }
        self.face_scale = scale;
        let values = face_values(&self.setup.faces, scale);
        let offset = std::mem::offset_of!(Params, face_value) as u64;
        for params in self.ways.iter().flat_map(|w| &w.params) {
            self.gpu
                .queue
                .write_buffer(params, offset, bytemuck::cast_slice(&values));
        }
    }

    /// During the setup's ramp, gives the faces their share of velocity for the next step
    /// ([`Setup::face_ramp`]); true while the ramp lasts.
    pub(super) fn ramp_faces(&mut self) -> bool {
        let ramping = (self.time as f64) < self.setup.ramp_steps;
        if ramping {
            self.set_face_scale(self.setup.face_ramp(self.time));
        }
        ramping
    }

    /// Advances `steps` steps (submitted in batches; returns once submitted, not completed).
    /// During the setup's ramp each step is submitted alone, after its face velocities.
    pub fn step(&mut self, steps: u64) {
        let mut steps = steps;
        while steps > 0 && self.ramp_faces() {
            let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
            self.encode_step(&mut encoder);
            self.gpu.queue.submit([encoder.finish()]);
            steps -= 1;
        }
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        for done in 0..steps {
            self.encode_step(&mut encoder);
            if done % 64 == 63 {
                let full = std::mem::replace(
                    &mut encoder,
                    self.gpu.device.create_command_encoder(&Default::default()),
                );
                self.gpu.queue.submit([full.finish()]);
            }
        }
        self.gpu.queue.submit([encoder.finish()]);
    }

    fn dispatch(&self, encoder: &mut wgpu::CommandEncoder, pipeline: &wgpu::ComputePipeline, parity: u64) {
        self.dispatch_groups(
            encoder,
            pipeline,
            parity,
            (self.setup.cells() as u32).div_ceil(WORKGROUP),
        );
    }

    /// Dispatches `groups` workgroups (2D beyond the per-dimension limit).
    pub(super) fn dispatch_groups(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        pipeline: &wgpu::ComputePipeline,
        parity: u64,
        groups: u32,
    ) {
        if groups == 0 {
            return;
        }
        let x = groups.min(MAX_GROUPS);
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &self.way().bind_groups[parity as usize], &[]);
        pass.dispatch_workgroups(x, groups.div_ceil(x), 1);
    }

    /// Adds one stream-collide step to `encoder`: the fluid cells by class (one or two dispatches),
    /// then the boundary cells.
    pub(super) fn encode_step(&mut self, encoder: &mut wgpu::CommandEncoder) {
        let parity = self.time % 2;
        let way = self.way();
        let c = &way.classes;
        let [interior, wrapping, boundary] = c.sizes;
        let groups = |cells: u32| cells.div_ceil(WORKGROUP);
        let fluid = &way.stream_collide_fluid;
        if parity == 0 {
            if let Some(quads) = &way.stream_collide_quads {
                self.dispatch_groups(encoder, quads, parity, groups(c.quads));
            }
            let rest = interior + wrapping - c.in_quads[0] - c.in_quads[1];
            self.dispatch_groups(encoder, &fluid[0], parity, groups(rest));
        } else {
            if let Some(quads) = &way.stream_collide_quads_odd {
                self.dispatch_groups(encoder, quads, parity, groups(c.interior_quads));
            }
            if c.interior_quads == 0 {
                self.dispatch_groups(encoder, &fluid[1], parity, groups(interior));
            }
            self.dispatch_groups(encoder, &fluid[2], parity, groups(c.wrapped().1));
        }
        self.dispatch_groups(encoder, &way.stream_collide, parity, groups(boundary));
        self.time += 1;
    }

    /// The first unhealthy cell if any, as `fields` finds it, with only that cell read back (a
    /// run's health check: on a GPU the whole field is 16 bytes per cell over the bus).
    pub fn health(&self) -> Option<Unhealthy> {
        self.first_unhealthy().map(|cell| {
            let bytes = self.gpu.read_range(&self.fields, cell as u64 * 16, 16);
            self.unhealthy(cell, bytemuck::cast_slice::<u8, [f32; 4]>(&bytes)[0])
        })
    }

    /// Computes the fields (density, velocity) on the device and returns the lowest index of an
    /// unhealthy cell, reading back only the status.
    fn first_unhealthy(&self) -> Option<usize> {
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        self.dispatch(&mut encoder, &self.way().macroscopic, self.time % 2);
        self.gpu.queue.submit([encoder.finish()]);
        let status: Vec<u32> = bytemuck::cast_slice(&self.gpu.read_buffer(&self.status, 16)).to_vec();
        (status[0] != u32::MAX).then_some(status[0] as usize)
    }

    fn unhealthy(&self, cell: usize, v: [f32; 4]) -> Unhealthy {
        Unhealthy {
            cell,
            coords: self.setup.coords(cell),
            rho: v[0],
            u: [v[1], v[2], v[3]],
        }
    }

    /// Keeps the fields of the last `health` or `fields` on the device (a copy there, not over the
    /// bus): what a run writes as its last good snapshot when a later check fails.
    pub fn keep_fields(&mut self) {
        let bytes = (self.setup.cells() * 16) as u64;
        let kept = self
            .kept
            .get_or_insert_with(|| storage_buffer(&self.gpu.device, "kept fields", bytes));
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(&self.fields, 0, kept, 0, bytes);
        self.gpu.queue.submit([encoder.finish()]);
    }

    /// The fields [`Lattice::keep_fields`] kept, if it was called.
    pub fn kept_fields(&self) -> Option<Vec<[f32; 4]>> {
        let kept = self.kept.as_ref()?;
        let bytes = self.gpu.read_buffer(kept, (self.setup.cells() * 16) as u64);
        Some(bytemuck::cast_slice(&bytes).to_vec())
    }

    /// Density and velocity of every cell, and the first unhealthy cell if any.
    pub fn fields(&self) -> (Vec<[f32; 4]>, Option<Unhealthy>) {
        let bad = self.first_unhealthy();
        let bytes = self
            .gpu
            .read_buffer(&self.fields, (self.setup.cells() * 16) as u64);
        let fields: Vec<[f32; 4]> = bytemuck::cast_slice(&bytes).to_vec();
        let bad = bad.map(|cell| self.unhealthy(cell, fields[cell]));
        (fields, bad)
    }

    /// The populations (shifted) at the current time in natural layout, whatever the AA phase.
    pub fn populations(&self) -> Vec<Cell> {
        let columns: Vec<Vec<f32>> = self
            .populations
            .iter()
            .map(|b| bytemuck::cast_slice(&self.gpu.read_buffer(b, (self.setup.cells() * 4) as u64)).to_vec())
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

/// A lattice's own buffers: the 19 populations, the cell flags, the MRT matrices, the fields
/// (density and velocity) and the status words.
struct LatticeBuffers {
    populations: Vec<wgpu::Buffer>,
    flags: wgpu::Buffer,
    mrt: wgpu::Buffer,
    fields: wgpu::Buffer,
    status: wgpu::Buffer,
}

impl LatticeBuffers {
    fn new(d: &wgpu::Device, setup: &Setup) -> LatticeBuffers {
        let bytes = (setup.cells() * 4) as u64;
        let init = |label: &str, contents: &[u8], usage| {
            d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        // [0] first unhealthy cell, [1] dropped covers, [2] covered cells beyond the list's room,
        // [4] and [8] covered cells (two lists),
        // [5..8] and [9..12] their workgroups.
        let mut status = [0u32; 16];
        status[0] = u32::MAX;
        LatticeBuffers {
            // wgpu zero-initialises every buffer: the shifted populations start at rest (f = w,
            // rho = 1) without an upload (which took a 5 GB host array at 256 x 256 x 512).
            populations: (0..19)
                .map(|i| storage_buffer(d, &format!("f{i}"), bytes.div_ceil(16) * 16))
                .collect(),
            flags: init(
                "flags",
                bytemuck::cast_slice(&cell_flags(setup)),
                wgpu::BufferUsages::STORAGE,
            ),
            mrt: init(
                "mrt",
                bytemuck::cast_slice(&mrt_matrices(setup)),
                wgpu::BufferUsages::UNIFORM,
            ),
            fields: storage_buffer(d, "fields", bytes * 4),
            status: init("status", bytemuck::cast_slice(&status), STORAGE),
        }
    }
}

/// lbm.wgsl and imb.wgsl with the list's join for this device (subgroups or one atomic per cell),
/// unrolled and compiled once.
fn shader_module(gpu: &Gpu) -> wgpu::ShaderModule {
    let list = if gpu.list.subgroups {
        LIST_SUBGROUP
    } else {
        LIST_ATOMIC
    };
    let source = format!("{SHADER}\n{IMB_SHADER}\n{list}");
    gpu.device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("lbm.wgsl + imb.wgsl"),
        source: wgpu::ShaderSource::Wgsl(super::unroll::unroll(&source).into()),
    })
}

/// Params (uniform), flags (read-only), MRT matrices (uniform), then fields, status, the 19
/// population buffers and the coupling's (read-write), the cell list (read-only): one layout for
/// all kernels.
fn bind_group_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let storage = |binding: u32, read_only: bool| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let uniform = |binding: u32| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let mut entries = vec![uniform(0), storage(1, true), uniform(2)];
    entries.extend((3..CELL_LIST_BINDING - 1).map(|b| storage(b, false)));
    entries.push(storage(CELL_LIST_BINDING - 1, true));
    entries.push(storage(CELL_LIST_BINDING, true));
    entries.push(storage(LOADS_BINDING, false));
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("lattice"),
        entries: &entries,
    })
}

const STORAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_SRC)
    .union(wgpu::BufferUsages::COPY_DST);

/// A storage buffer that can be copied to and from (zero-filled by wgpu).
pub(super) fn storage_buffer(device: &wgpu::Device, label: &str, bytes: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes,
        usage: STORAGE,
        mapped_at_creation: false,
    })
}

#[allow(clippy::too_many_arguments)]
/// Bytes per cell of the largest buffer indexed by cell: the fields (density and velocity, four
/// f32), as large as the coupling's slots at 4 slots per cell.
const LARGEST_BYTES_PER_CELL: u64 = 16;

/// Refuses a grid whose largest per-cell buffer exceeds what one storage binding of this device
/// may hold (each buffer is bound whole), or whose cell index would not fit an i32.
pub fn fits_device(limits: &wgpu::Limits, n: [usize; 3]) -> Result<(), String> {
    let cells = n.iter().map(|&k| k as u64).product::<u64>();
    let largest = cells * LARGEST_BYTES_PER_CELL;
    let limit = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
    if largest <= limit && cells < (1u64 << 31) {
        return Ok(());
    }
    let [x, y, z] = n;
    Err(format!(
        "grid {x}x{y}x{z} ({cells} cells) needs {largest} bytes in one buffer (the fields, \
         {LARGEST_BYTES_PER_CELL} bytes per cell), above this device's storage binding limit of {limit} \
         bytes: at most {} cells here (Mesa lavapipe, the CPU driver, allows 128 MiB: 8.4 M cells); use a \
         coarser lattice.dx or a smaller domain, or a GPU",
        (limit / LARGEST_BYTES_PER_CELL).min((1u64 << 31) - 1)
    ))
}

/// The lattice's bind group: `front` (params, flags, MRT matrices, fields, status) at bindings
/// 0-4, then the populations, the coupling's buffers, the cell list and the loads.
fn make_bind_group(
    d: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    front: [&wgpu::Buffer; 5],
    populations: &[wgpu::Buffer],
    coupling: &super::imb::Coupling,
    cell_list: &wgpu::Buffer,
) -> wgpu::BindGroup {
    let mut entries: Vec<_> = (0u32..).zip(front).map(|(i, b)| entry(i, b)).collect();
    entries.extend(
        populations
            .iter()
            .enumerate()
            .map(|(i, b)| entry(FIRST_POPULATION_BINDING + i as u32, b)),
    );
    entries.extend(
        coupling
            .buffers()
            .iter()
            .enumerate()
            .map(|(i, b)| entry(FIRST_IMB_BINDING + i as u32, b)),
    );
    entries.push(entry(CELL_LIST_BINDING, cell_list));
    entries.push(entry(LOADS_BINDING, coupling.loads()));
    d.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("lattice"),
        layout,
        entries: &entries,
    })
}

fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}

/// Bit i set when link i of the cell leaves the fluid.
const SOLID_FLAG: u32 = 1 << 19;
/// The cell lies on a periodic face: its neighbours need wrapping.
const WRAPS_FLAG: u32 = 1 << 20;

/// One word per cell: the links that leave the fluid, solid, and periodic-face bits.
pub fn cell_flags(setup: &Setup) -> Vec<u32> {
    (0..setup.cells())
        .map(|k| {
            if setup.solid[k] {
                return SOLID_FLAG;
            }
            let links: u32 = (0..19)
                .filter(|&i| matches!(setup.link(k, C[i]), Link::Boundary(..)))
                .map(|i| 1u32 << i)
                .sum();
            let x = setup.coords(k);
            let on_periodic_face = (0..3).any(|a| {
                (x[a] == 0 && setup.faces[2 * a] == Face::Periodic)
                    || (x[a] + 1 == setup.n[a] && setup.faces[2 * a + 1] == Face::Periodic)
            });
            links | if on_periodic_face { WRAPS_FLAG } else { 0 }
        })
        .collect()
}

/// The fluid cells by class, and the quads. Classes: interior (no link leaves the fluid or wraps:
/// fixed neighbour offsets), wrapping (no link leaves the fluid, some cross a periodic face),
/// boundary (some link leaves the fluid). Quads: q such that cells 4q..4q+3 are all interior or
/// wrapping, whose even step moves four cells per vector access; interior quads, of four interior
/// cells, do so in the odd step too when nx is a multiple of 4 (with or without particles).
pub struct CellList {
    /// Interior cells (those of interior quads first, then those of other quads), wrapping cells
    /// (those of quads last), boundary cells, each group in increasing order, then the quads, then
    /// the interior quads.
    pub list: Vec<u32>,
    /// Interior, wrapping, boundary cells.
    pub sizes: [u32; 3],
    /// Interior and wrapping cells that belong to a quad.
    pub in_quads: [u32; 2],
    /// Interior cells that belong to an interior quad.
    pub in_interior_quads: u32,
    pub quads: u32,
    pub interior_quads: u32,
}

impl CellList {
    /// The cells of the odd step through the periodic wrap (first, count): the wrapping cells and,
    /// when there are interior quads, the interior cells outside them too (one dispatch fewer).
    pub fn wrapped(&self) -> (u32, u32) {
        let [interior, wrapping, _] = self.sizes;
        if self.interior_quads > 0 {
            (
                self.in_interior_quads,
                interior + wrapping - self.in_interior_quads,
            )
        } else {
            (interior, wrapping)
        }
    }

    /// The cell list, with the quads when `quads` (without, every interior and wrapping cell goes
    /// through `stream_collide_fluid`).
    pub fn new(setup: &Setup, quads: bool) -> CellList {
        let flags = cell_flags(setup);
        let cells = flags.len();
        let class = |flag: u32| {
            if flag & SOLID_FLAG != 0 {
                3
            } else if flag & 0x7ffff != 0 {
                2
            } else if flag & WRAPS_FLAG != 0 {
                1
            } else {
                0
            }
        };
        let all = |q: usize, most: u32| (4 * q..4 * q + 4).all(|k| class(flags[k]) <= most);
        let quads: Vec<u32> = (0..cells / 4)
            .filter(|&q| quads && all(q, 1))
            .map(|q| q as u32)
            .collect();
        let interior_quads: Vec<u32> = quads
            .iter()
            .copied()
            .filter(|&q| setup.n[0].is_multiple_of(4) && all(q as usize, 0))
            .collect();
        // 0: in no quad, 1: in a quad, 2: in an interior quad.
        let mut membership = vec![0u8; cells];
        for (quads, value) in [(&quads, 1), (&interior_quads, 2)] {
            for q in quads {
                membership[4 * *q as usize..4 * *q as usize + 4].fill(value);
            }
        }
        let (flags, membership) = (&flags, &membership);
        let select = |c: u32, m: u8| {
            (0..cells)
                .filter(move |&k| class(flags[k]) == c && membership[k] == m)
                .map(|k| k as u32)
        };
        let mut list: Vec<u32> = select(0, 2).collect();
        let in_interior_quads = list.len() as u32;
        list.extend(select(0, 1));
        let interior_in_quads = list.len() as u32;
        list.extend(select(0, 0));
        let interior = list.len() as u32;
        list.extend(select(1, 0));
        let before = list.len() as u32;
        list.extend(select(1, 1));
        let wrapping_in_quads = list.len() as u32 - before;
        let wrapping = list.len() as u32 - interior;
        list.extend(select(2, 0));
        let boundary = list.len() as u32 - interior - wrapping;
        list.extend(&quads);
        list.extend(&interior_quads);
        CellList {
            list,
            sizes: [interior, wrapping, boundary],
            in_quads: [interior_in_quads, wrapping_in_quads],
            in_interior_quads,
            quads: quads.len() as u32,
            interior_quads: interior_quads.len() as u32,
        }
    }
}

/// Each face's velocity times `scale` (a start from rest) and density, for `Params::face_value`.
fn face_values(faces: &[Face; 6], scale: f64) -> [[f32; 4]; 6] {
    faces.map(|f| {
        let ([x, y, z], rho) = f.values();
        [x * scale, y * scale, z * scale, rho].map(|v| v as f32)
    })
}

fn params(setup: &Setup, parity: usize, health: Health, classes: &CellList, face_scale: f64) -> Params {
    let face = |f: usize| setup.faces[f].code();
    Params {
        n: [
            setup.n[0] as u32,
            setup.n[1] as u32,
            setup.n[2] as u32,
            parity as u32,
        ],
        face_lo: [face(0), face(1), face(2), face(3)],
        face_hi: [face(4), face(5), 0, 0],
        relax: [
            (1.0 / setup.tau) as f32,
            setup.omega_minus() as f32,
            health.max_speed as f32,
            health.max_density_deviation as f32,
        ],
        force: vec4(setup.force, 0.0),
        face_value: face_values(&setup.faces, face_scale),
        ranges: [
            classes.sizes[0],
            classes.sizes[1],
            classes.sizes[2],
            classes.quads,
        ],
        quads: [
            classes.in_quads[0],
            classes.in_quads[1],
            classes.in_interior_quads,
            classes.interior_quads,
        ],
        wrapped: [classes.wrapped().0, classes.wrapped().1, 0, 0],
    }
}

/// The MRT matrices A and B, padded to 181 vec4 (zeros for other operators: the buffer must
/// exist anyway).
fn mrt_matrices(setup: &Setup) -> Vec<f32> {
    let (a, b) = match setup.operator {
        Operator::Mrt { rates } => mrt::collision_matrices(&rates),
        _ => ([[0.0; 19]; 19], [[0.0; 19]; 19]),
    };
    let mut values: Vec<f32> = a
        .iter()
        .chain(b.iter())
        .flat_map(|row| row.iter().map(|v| *v as f32))
        .collect();
    values.resize(181 * 4, 0.0);
    values
}

/// Shifted equilibrium populations of a whole lattice for given density and velocity per cell.
pub fn equilibrium_field(setup: &Setup, state: impl Fn([usize; 3]) -> (f64, [f64; 3])) -> Vec<Cell> {
    (0..setup.cells())
        .map(|k| {
            let (rho, u) = state(setup.coords(k));
            std::array::from_fn(|i| super::lattice::equilibrium_shifted(i, rho, u))
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

/// The quad kernels (four cells per invocation) against the f64 reference step: the other tests'
/// grids have no interior quads (nx not a multiple of 4).
/// A 3-vector and a fourth value as the f32 vec4 of a GPU record.
pub(crate) fn vec4(v: [f64; 3], w: f64) -> [f32; 4] {
    [v[0] as f32, v[1] as f32, v[2] as f32, w as f32]
}

#[cfg(test)]
mod quad_tests {
    use super::super::geometry::{Face, Operator, Setup};
    use super::super::mrt::Rates;
    use super::super::random::{random_populations, Random};
    use super::super::reference;
    use super::*;

    fn check(setup: Setup, seed: u64) {
        let classes = CellList::new(&setup, true);
        assert!(
            classes.quads > 0 && classes.interior_quads > 0,
            "the grid has quads"
        );
        let mut f = random_populations(&setup, seed);
        let gpu = std::sync::Arc::new(Gpu::new().expect("a wgpu adapter (lavapipe in CI)"));
        let mut lattice = Lattice::new(gpu, setup.clone(), Health::default(), None).unwrap();
        lattice.set_populations(&f);
        let tolerance = 64.0 * f32::EPSILON as f64 * 0.35;
        for step in 1..=4 {
            f = reference::step(&setup, &f);
            lattice.step(1);
            let err = lattice
                .populations()
                .iter()
                .zip(&f)
                .flat_map(|(a, b)| a.iter().zip(b).map(|(p, q)| (p - q).abs()))
                .fold(0.0, f64::max);
            assert!(err < tolerance, "step {step} differs by {err:e}");
        }
    }

    #[test]
    fn bgk_periodic_quads_match_reference() {
        let setup = Setup::new([16, 6, 5], [Face::Periodic; 6], 0.8, Operator::Bgk);
        check(setup, 11);
    }

    #[test]
    fn mrt_walls_solids_force_quads_match_reference() {
        let faces = [
            Face::Periodic,
            Face::Periodic,
            Face::Wall,
            Face::MovingWall([0.02, 0.0, 0.01]),
            Face::Periodic,
            Face::Periodic,
        ];
        let rates = Rates::dhumieres(1.0 / 0.7);
        let mut setup = Setup::new([12, 7, 6], faces, 0.7, Operator::Mrt { rates });
        setup.force = [1e-4, -2e-4, 3e-5];
        let mut r = Random::new(12);
        for s in setup.solid.iter_mut() {
            *s = r.next() > 0.95;
        }
        check(setup, 13);
    }

    #[test]
    fn trt_periodic_quads_match_reference() {
        let setup = Setup::new(
            [12, 6, 6],
            [Face::Periodic; 6],
            0.6,
            Operator::Trt { magic: 3.0 / 16.0 },
        );
        check(setup, 14);
    }
}

#[cfg(test)]
mod adapter_tests {
    use super::*;
    use wgpu::{Backend, DeviceType};

    fn offer(name: &str, backend: Backend, device_type: DeviceType, storage_buffers: u32) -> AdapterOffer {
        AdapterOffer {
            name: name.into(),
            backend,
            device_type,
            storage_buffers,
        }
    }

    #[test]
    fn a_gpu_goes_before_a_cpu_driver_and_vulkan_before_opengl() {
        let gl = offer("llvmpipe", Backend::Gl, DeviceType::Cpu, 16);
        let lavapipe = offer("llvmpipe", Backend::Vulkan, DeviceType::Cpu, 4096);
        let gl_enough = offer("llvmpipe", Backend::Gl, DeviceType::Cpu, 64);
        let gpu = offer("NVIDIA H200", Backend::Vulkan, DeviceType::DiscreteGpu, 4096);
        assert_eq!(choose_adapter(&[gl.clone(), lavapipe.clone()]), Ok(1));
        assert_eq!(choose_adapter(&[gl_enough.clone(), lavapipe.clone()]), Ok(1));
        assert_eq!(
            choose_adapter(&[lavapipe.clone(), gpu.clone(), gl_enough.clone()]),
            Ok(1)
        );
        assert_eq!(
            choose_adapter(&[gl_enough, lavapipe.clone(), lavapipe]),
            Ok(1),
            "the first of equals"
        );
    }

    #[test]
    fn without_an_adapter_that_binds_enough_the_error_names_each_and_what_to_install() {
        let why = choose_adapter(&[offer(
            "llvmpipe (LLVM 15.0.6, 256 bits)",
            Backend::Gl,
            DeviceType::Cpu,
            16,
        )])
        .expect_err("16 storage buffers are too few");
        assert!(why.contains(&format!("the {BINDINGS} storage buffers")), "{why}");
        assert!(
            why.contains("llvmpipe (LLVM 15.0.6, 256 bits) (Gl, Cpu) binds 16"),
            "{why}"
        );
        assert!(why.contains("mesa-vulkan-drivers"), "{why}");
        let none = choose_adapter(&[]).expect_err("no adapter");
        assert!(
            none.starts_with("no GPU adapter found") && none.contains("mesa-vulkan-drivers"),
            "{none}"
        );
    }
}
