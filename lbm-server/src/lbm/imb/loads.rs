//! The loads back on the host: read from the device once their submission is done, and
//! converted in parallel chunks into the caller's values.

use super::chunks::{for_each_chunk, CHUNK};
use super::records::{GpuLoad, Load};
use crate::lbm::gpu::GpuLattice;

impl GpuLattice {
    /// The `bytes` of loads, once the submission `with_loads` is done, handed to `read`.
    pub(super) fn read_loads(
        &self,
        bytes: u64,
        with_loads: wgpu::SubmissionIndex,
        read: &mut dyn FnMut(&[GpuLoad]) -> Result<(), String>,
    ) -> Result<(), String> {
        if bytes == 0 {
            return read(&[]);
        }
        let coupling = self.imb.as_ref().expect("coupling");
        let slice = coupling.readback.slice(..bytes);
        slice.map_async(wgpu::MapMode::Read, |_| {});
        self.gpu.wait_for(with_loads);
        let read_out = {
            let data = slice
                .get_mapped_range()
                .map_err(|e| format!("particle readback: {e:?}"))?;
            let loads: &[GpuLoad] =
                bytemuck::try_cast_slice(&data).map_err(|e| format!("particle readback: {e}"))?;
            read(loads)
        };
        coupling.readback.unmap();
        read_out
    }
}

/// `out` (replaced) holds `load(j, load of j)` for every particle j of the GPU's loads.
pub(super) fn convert_loads<T: Send>(
    loads: &[GpuLoad],
    out: &mut Vec<T>,
    load: &(impl Fn(usize, Load) -> T + Sync),
) -> Result<(), String> {
    out.clear();
    out.reserve(loads.len());
    let slots = out.spare_capacity_mut()[..loads.len()]
        .chunks_mut(CHUNK)
        .collect();
    for_each_chunk(slots, |c, chunk| {
        for (j, slot) in (c * CHUNK..).zip(chunk) {
            let l = loads[j].map(f64::from);
            slot.write(load(
                j,
                Load {
                    force: [l[0], l[1], l[2]],
                    torque: [l[3], l[4], l[5]],
                },
            ));
        }
    });
    // SAFETY: `for_each_chunk` wrote every one of the first loads.len() slots.
    unsafe { out.set_len(loads.len()) };
    Ok(())
}
