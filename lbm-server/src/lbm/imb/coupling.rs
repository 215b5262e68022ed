//! The coupling's buffers ([`Coupling`]): particles, pairs, covers, slots and loads, grown to
//! hold a step's particles, and what the lattice tells of them (covered cells, slots, lost covers).

use super::options::{CoveredCells, ImbOptions};
use super::records::{LostCovers, LOADS_BUFFER_BYTES, LOAD_BYTES, PAIR_BYTES, PARTICLE_BYTES, SAVED_BYTES};
use crate::lbm::gpu::{storage_buffer, GpuLattice};

/// Buffers of the coupling (tiny placeholders when the scene has no particles).
pub struct Coupling {
    pub(super) particles: wgpu::Buffer,
    /// Force and torque per particle, apart from the states so that only they are read back; after
    /// them `reduce`'s partial loads (REDUCE_SLICES per particle).
    pub(super) loads: wgpu::Buffer,
    pub(super) pairs: wgpu::Buffer,
    /// The cover mask (fused and skip): one bit per cell, 32 to a word.
    pub(super) covered: wgpu::Buffer,
    pub(super) slots: wgpu::Buffer,
    pub(super) info: wgpu::Buffer,
    pub(super) readback: wgpu::Buffer,
    /// The workgroups of the covered cells (copied from status[5..8]: a buffer bound as storage
    /// cannot be the indirect argument of the same dispatch).
    pub(super) indirect: wgpu::Buffer,
    pub(super) particle_capacity: u64,
    pub(super) pair_capacity: u64,
    pub(super) slots_per_cell: u32,
    /// Covered cells the `fields` buffer can hold (`Saved` records).
    pub(super) saved_capacity: u32,
    /// Most covered cells the list may hold (below the device's limit only in tests).
    pub(super) saved_cap: u64,
    /// The particles and pairs of the step staged last.
    pub(super) staged: (u32, u64),
}

impl Coupling {
    pub fn new(d: &wgpu::Device, options: Option<ImbOptions>, cells: usize) -> Coupling {
        let per_cell = |bytes: u64| {
            if options.is_some() {
                bytes * cells as u64
            } else {
                256
            }
        };
        let slots = options.map_or(1, |o| o.slots as u64);
        Coupling {
            particles: storage_buffer(d, "particles", PARTICLE_BYTES),
            loads: storage_buffer(d, "loads", LOADS_BUFFER_BYTES),
            pairs: storage_buffer(d, "pairs", PAIR_BYTES),
            covered: storage_buffer(d, "covered", per_cell(4).div_ceil(128) * 4),
            slots: storage_buffer(d, "slots", per_cell(4 * slots)),
            info: storage_buffer(d, "imb info", 16),
            readback: readback_buffer(d, LOAD_BYTES),
            indirect: d.create_buffer(&wgpu::BufferDescriptor {
                label: Some("covered cells' workgroups"),
                size: 32,
                usage: wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            particle_capacity: 1,
            pair_capacity: 1,
            slots_per_cell: slots as u32,
            saved_capacity: 0,
            saved_cap: u64::MAX,
            staged: (0, 0),
        }
    }

    /// The buffers in binding order.
    pub fn buffers(&self) -> [&wgpu::Buffer; 5] {
        [
            &self.particles,
            &self.pairs,
            &self.covered,
            &self.slots,
            &self.info,
        ]
    }

    /// The particles' force and torque (its own binding).
    pub fn loads(&self) -> &wgpu::Buffer {
        &self.loads
    }
}

fn readback_buffer(d: &wgpu::Device, bytes: u64) -> wgpu::Buffer {
    d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("particle readback"),
        size: bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

impl GpuLattice {
    /// Where the covered cells take their solid term now (definite; the redo without coupling).
    pub fn covered_cells(&self) -> CoveredCells {
        self.way().mode
    }

    /// Particles one cell can hold.
    pub fn slots(&self) -> u32 {
        self.imb.as_ref().map_or(0, |c| c.slots_per_cell)
    }

    /// Since the start (one readback): the particle-cell covers that did not fit a cell's slots,
    /// and the covered cells that did not fit the list of covered cells (their solid term was
    /// missing); (0, 0) when none.
    pub fn lost_covers(&self) -> LostCovers {
        let status: Vec<u32> = bytemuck::cast_slice(&self.gpu.read_buffer(&self.status, 16)).to_vec();
        LostCovers {
            dropped: status[1],
            unlisted: status[2],
        }
    }

    /// Room in the list of covered cells.
    pub fn covered_cell_capacity(&self) -> u32 {
        self.imb.as_ref().map_or(0, |c| c.saved_capacity)
    }

    /// Test aid: the words of the cover mask and the slots that are not zero
    /// (`reduce` clears them all for the next step).
    #[cfg(test)]
    pub fn cover_words_left(&self) -> usize {
        let c = self.imb.as_ref().expect("coupling");
        [&c.covered, &c.slots]
            .iter()
            .map(|b| {
                let words: Vec<u32> = bytemuck::cast_slice(&self.gpu.read_buffer(b, b.size())).to_vec();
                words.iter().filter(|&&w| w != 0).count()
            })
            .sum()
    }

    /// Test aid: caps the list of covered cells at `cells`.
    #[cfg(test)]
    pub fn cap_covered_cells(&mut self, cells: u64) {
        if let Some(c) = self.imb.as_mut() {
            c.saved_cap = cells;
        }
    }

    /// Grows the particle and pair buffers to hold `particles` and `pairs`.
    pub(super) fn reserve(&mut self, particles: u64, pairs: u64) -> Result<(), String> {
        let limit = self.gpu.limits.max_storage_buffer_binding_size;
        if pairs * PAIR_BYTES > limit {
            return Err(format!(
                "{pairs} particle-cell pairs exceed this device's binding limit of {limit} bytes"
            ));
        }
        let d = self.gpu.device.clone();
        let fused = self.covered_cells() == CoveredCells::Fused;
        let coupling = self.imb.as_mut().expect("coupling");
        let mut grew = false;
        if particles > coupling.particle_capacity {
            coupling.particle_capacity = particles.next_power_of_two();
            coupling.particles = storage_buffer(&d, "particles", coupling.particle_capacity * PARTICLE_BYTES);
            coupling.loads = storage_buffer(&d, "loads", coupling.particle_capacity * LOADS_BUFFER_BYTES);
            coupling.readback = readback_buffer(&d, coupling.particle_capacity * LOAD_BYTES);
            grew = true;
        }
        if pairs > coupling.pair_capacity {
            coupling.pair_capacity = pairs.next_power_of_two();
            coupling.pairs = storage_buffer(&d, "pairs", coupling.pair_capacity * PAIR_BYTES);
            grew = true;
        }
        // The redo's covered cells, at most min(cells, pairs), over the `fields` buffer (fused: none).
        let cells = self.setup.cells() as u64;
        let most = (limit.min(self.gpu.limits.max_buffer_size) / SAVED_BYTES)
            .min(cells)
            .min(coupling.saved_cap);
        let want = pairs.min(cells).next_power_of_two().min(most);
        if !fused && want > coupling.saved_capacity as u64 {
            let bytes = (want * SAVED_BYTES).max(cells * 16);
            self.fields = storage_buffer(&d, "fields", bytes);
            coupling.saved_capacity = (bytes / SAVED_BYTES).min(most) as u32;
            grew = true;
        }
        if grew {
            self.rebind();
        }
        Ok(())
    }
}
