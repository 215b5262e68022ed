//! The lattice's state as a checkpoint holds it ([`RawState`]): the populations exactly as the
//! device stores them (the storage's own encoding, in the AA phase of the lattice's clock), the
//! status words, the clock and the faces' share of velocity. Read back in one submission, and
//! written back to the bit.

use super::state::GpuLattice;
use crate::lbm::storage::{Storage, StorageOnDevice};

/// Status words of a lattice (bindings.rs).
const STATUS_WORDS: usize = 16;

/// A lattice's state, host side.
pub struct RawState {
    /// Per direction (19), its `cells` populations in the storage's encoding (little-endian f32,
    /// or two bytes each for FP16S / FP16C), without the buffer's padding.
    pub populations: Vec<Vec<u8>>,
    /// The status words (health, lost covers, the covered cells' counts).
    pub status: Vec<u8>,
    /// Completed steps (its parity is the AA phase the populations are in).
    pub time: u64,
    /// The share of their velocity the inlets and moving walls had.
    pub face_scale: f64,
}

impl GpuLattice {
    /// The state, read back in one submission (the copy off the device is all it waits for).
    pub fn raw_state(&self) -> RawState {
        let bytes = self.population_bytes();
        let padded = self.setup.storage.buffer_bytes(self.setup.cells());
        let status_bytes = (STATUS_WORDS * 4) as u64;
        let total = padded * 19 + status_bytes;
        let d = &self.gpu.device;
        let staging = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("checkpoint readback"),
            size: total,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = d.create_command_encoder(&Default::default());
        for (i, b) in self.populations.iter().enumerate() {
            encoder.copy_buffer_to_buffer(b, 0, &staging, i as u64 * padded, padded);
        }
        encoder.copy_buffer_to_buffer(&self.status, 0, &staging, 19 * padded, status_bytes);
        self.gpu.queue.submit([encoder.finish()]);
        let slice = staging.slice(..);
        slice.map_async(wgpu::MapMode::Read, |_| {});
        self.gpu.wait();
        let data = slice.get_mapped_range().expect("mapped");
        let populations = (0..19)
            .map(|i| {
                let start = i * padded as usize;
                data[start..start + bytes].to_vec()
            })
            .collect();
        let status = data[19 * padded as usize..].to_vec();
        drop(data);
        staging.unmap();
        RawState {
            populations,
            status,
            time: self.time,
            face_scale: self.face_scale,
        }
    }

    /// Puts `state` back: the populations and status words as they were, the clock and the faces'
    /// share of velocity.
    pub fn restore_raw(&mut self, state: &RawState) {
        for (buffer, bytes) in self.populations.iter().zip(&state.populations) {
            let mut padded = bytes.clone();
            padded.resize(padded.len().next_multiple_of(4), 0);
            self.gpu.queue.write_buffer(buffer, 0, &padded);
        }
        self.gpu.queue.write_buffer(&self.status, 0, &state.status);
        self.time = state.time;
        self.set_face_scale(state.face_scale);
        self.gpu.wait();
    }

    /// Bytes of one direction's populations (no padding).
    pub fn population_bytes(&self) -> usize {
        self.setup.cells() * self.setup.storage.bytes()
    }

    /// The storage of the populations.
    pub fn storage(&self) -> Storage {
        self.setup.storage
    }
}
