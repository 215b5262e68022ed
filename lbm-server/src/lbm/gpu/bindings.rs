//! The buffers and bindings every kernel of a lattice shares: the binding numbers, the lattice's
//! own buffers, the one layout and its bind groups, and whether a grid fits the device.

use super::cell_list::cell_flags;
use super::params::mrt_matrices;
use super::state::GpuLattice;
use crate::lbm::geometry::Setup;
use crate::lbm::imb::Coupling;
use crate::lbm::storage::StorageOnDevice;
use wgpu::util::DeviceExt;

/// Bindings before the 19 population buffers.
const FIRST_POPULATION_BINDING: u32 = 5;
/// The immersed-boundary bindings follow the populations: particles, pairs, covered, slots, info.
const FIRST_IMB_BINDING: u32 = FIRST_POPULATION_BINDING + 19;
/// The cell list (read-only) follows them.
const CELL_LIST_BINDING: u32 = FIRST_IMB_BINDING + 5;
/// The particles' force and torque (the coupling's output, the only part read back).
const LOADS_BINDING: u32 = CELL_LIST_BINDING + 1;
pub(super) const BINDINGS: u32 = LOADS_BINDING + 1;

/// A lattice's own buffers: the 19 populations, the cell flags, the MRT matrices, the fields
/// (density and velocity) and the status words.
pub(super) struct LatticeBuffers {
    pub(super) populations: Vec<wgpu::Buffer>,
    pub(super) flags: wgpu::Buffer,
    pub(super) mrt: wgpu::Buffer,
    pub(super) fields: wgpu::Buffer,
    pub(super) status: wgpu::Buffer,
}

impl LatticeBuffers {
    pub(super) fn new(d: &wgpu::Device, setup: &Setup) -> LatticeBuffers {
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
                .map(|i| storage_buffer(d, &format!("f{i}"), setup.storage.buffer_bytes(setup.cells())))
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

/// Params (uniform), flags (read-only), MRT matrices (uniform), then fields, status, the 19
/// population buffers and the coupling's (read-write), the cell list (read-only): one layout for
/// all kernels.
pub(super) fn bind_group_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let storage = storage_entry;
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

/// A compute kernel's storage buffer at `binding` in a bind group layout.
pub(super) fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

const STORAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_SRC)
    .union(wgpu::BufferUsages::COPY_DST);

/// A storage buffer that can be copied to and from (zero-filled by wgpu).
pub(in crate::lbm) fn storage_buffer(device: &wgpu::Device, label: &str, bytes: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes,
        usage: STORAGE,
        mapped_at_creation: false,
    })
}

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
pub(super) fn make_bind_group(
    d: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    front: [&wgpu::Buffer; 5],
    populations: &[wgpu::Buffer],
    coupling: &Coupling,
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

impl GpuLattice {
    /// Rebuilds every way's bind groups (after the coupling's buffers grew).
    pub(in crate::lbm) fn rebind(&mut self) {
        let bound: Vec<[wgpu::BindGroup; 2]> = self
            .ways
            .iter()
            .map(|w| [0, 1].map(|parity| self.bind_group(&w.params[parity], &w.cell_list)))
            .collect();
        for (way, groups) in self.ways.iter_mut().zip(bound) {
            way.bind_groups = groups;
        }
        self.rebind_regions();
    }

    /// The lattice's buffers bound with `params` and a way's `cell_list`.
    pub(super) fn bind_group(&self, params: &wgpu::Buffer, cell_list: &wgpu::Buffer) -> wgpu::BindGroup {
        make_bind_group(
            &self.gpu.device,
            &self.layout,
            [params, &self.flags, &self.mrt, &self.fields, &self.status],
            &self.populations,
            self.imb.as_ref().expect("coupling buffers"),
            cell_list,
        )
    }
}
