//! The device: the adapter chosen among those found, its queue, and reading buffers back.

use super::bindings::BINDINGS;

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
#[cfg(test)]
fn choose_adapter(found: &[AdapterOffer]) -> Result<usize, String> {
    choose_adapter_for(found, 0)
}

/// The adapter of a rank that is `local`-th on its node ([`Gpu::for_local_rank`]): of the
/// adapters of the kind [`choose_adapter`] picks, number `local` modulo their count, so that the
/// ranks of a node spread over its GPUs; ranks on a CPU driver share it.
fn choose_adapter_for(found: &[AdapterOffer], local: usize) -> Result<usize, String> {
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
    if let Some(best) = usable.clone().map(|(_, a)| rank(a)).min() {
        let equals: Vec<usize> = usable.filter(|(_, a)| rank(a) == best).map(|(i, _)| i).collect();
        let kind = found[equals[0]].device_type;
        let spread = matches!(
            kind,
            wgpu::DeviceType::DiscreteGpu | wgpu::DeviceType::IntegratedGpu
        );
        return Ok(if spread {
            equals[local % equals.len()]
        } else {
            equals[0]
        });
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

/// The adapter [`choose_adapter`] picks among those of the backends allowed by WGPU_BACKEND
/// (default: all).
fn chosen_adapter(local: usize) -> Result<wgpu::Adapter, String> {
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
    let chosen = choose_adapter_for(&found, local)?;
    Ok(adapters
        .into_iter()
        .nth(chosen)
        .expect("an index into the adapters"))
}

impl Gpu {
    /// The limits of the adapter [`Gpu::new`] opens, its device left closed: a lattice is checked
    /// against them before a run removes or allocates anything.
    pub fn adapter_limits() -> Result<wgpu::Limits, String> {
        chosen_adapter(0).map(|adapter| adapter.limits())
    }

    /// Opens the adapter [`choose_adapter`] picks among those of the backends allowed by
    /// WGPU_BACKEND (default: all).
    pub fn new() -> Result<Gpu, String> {
        Gpu::for_local_rank(0)
    }

    /// Opens the adapter of a rank that is `local`-th of the ranks on its node: GPU number `local`
    /// modulo the node's GPUs of the kind [`Gpu::new`] picks, or the CPU driver where there is
    /// none.
    pub fn for_local_rank(local: usize) -> Result<Gpu, String> {
        let adapter = chosen_adapter(local)?;
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

    /// Whether the device is a CPU driver (lavapipe, llvmpipe), not a GPU.
    pub fn on_cpu(&self) -> bool {
        self.adapter.device_type == wgpu::DeviceType::Cpu
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
    fn ranks_of_a_node_spread_over_its_gpus_and_share_a_cpu_driver() {
        let lavapipe = offer("llvmpipe", Backend::Vulkan, DeviceType::Cpu, 4096);
        let gpu = offer("NVIDIA H200", Backend::Vulkan, DeviceType::DiscreteGpu, 4096);
        let found = [lavapipe.clone(), gpu.clone(), gpu.clone()];
        let chosen: Vec<usize> = (0..4).map(|l| choose_adapter_for(&found, l).unwrap()).collect();
        assert_eq!(chosen, [1, 2, 1, 2]);
        let cpu = [lavapipe.clone(), lavapipe];
        assert_eq!(choose_adapter_for(&cpu, 1), Ok(0));
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
