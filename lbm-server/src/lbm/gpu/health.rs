//! The health check (a cell's speed and density within limits) and the fields (density and
//! velocity, seed eq. 5-6) read back, or kept on the device as the last good ones.

use super::bindings::storage_buffer;
use super::state::GpuLattice;

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

/// An unhealthy cell found by a health check: the first in memory order ([`GpuLattice::health`]),
/// or the one furthest out of bounds ([`GpuLattice::furthest_unhealthy`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Unhealthy {
    pub cell: usize,
    pub coords: [usize; 3],
    pub rho: f32,
    pub u: [f32; 3],
}

impl Unhealthy {
    /// The quantity that failed the check.
    fn quantity(&self, health: &Health) -> String {
        if !(self.rho.is_finite() && self.u.iter().all(|v| v.is_finite())) {
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
        }
    }

    /// "cell K at (i, j, k), centre (x, y, z) m: QUANTITY", naming the quantity that failed the
    /// check, the centre in SI (`centre` of the cell's indices: `LatticeUnits::cell_centre`).
    pub fn describe(&self, health: &Health, centre: impl Fn([usize; 3]) -> [f64; 3]) -> String {
        let [x, y, z] = centre(self.coords);
        let [i, j, k] = self.coords;
        format!(
            "cell {} at ({i}, {j}, {k}), centre ({x:.4e}, {y:.4e}, {z:.4e}) m: {}",
            self.cell,
            self.quantity(health)
        )
    }
}

/// How far a cell's density and velocity `v` lie out of the check's bounds, as a multiple of
/// them: the larger of |u| / max_speed and |rho - 1| / max_density_deviation (out of bounds above
/// 1); infinite where a value is not finite.
pub fn out_of_bounds(v: [f32; 4], health: &Health) -> f64 {
    if !v.iter().all(|x| x.is_finite()) {
        return f64::INFINITY;
    }
    let speed = v[1..].iter().map(|&u| f64::from(u).powi(2)).sum::<f64>().sqrt();
    let density = (f64::from(v[0]) - 1.0).abs();
    (speed / health.max_speed).max(density / health.max_density_deviation)
}

/// The cell of `fields` furthest out of the check's bounds, if any is out (of equals, the first in
/// memory order).
pub fn furthest_out_of_bounds(fields: &[[f32; 4]], health: &Health) -> Option<usize> {
    let mut furthest = None;
    let mut most = 1.0;
    for (cell, &v) in fields.iter().enumerate() {
        let by = out_of_bounds(v, health);
        if by > most {
            (furthest, most) = (Some(cell), by);
        }
        if by == f64::INFINITY {
            break;
        }
    }
    furthest
}

impl GpuLattice {
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

    /// The cell furthest out of the check's bounds (largest |u| or |rho - 1| against its limit;
    /// a non-finite value furthest of all) in the fields of the last `health` or `fields`, if any
    /// is out: where a blow-up is, where the first in memory order is merely where the check
    /// found one. The whole field is read back: once, as a run fails.
    pub fn furthest_unhealthy(&self) -> Option<Unhealthy> {
        let bytes = self
            .gpu
            .read_buffer(&self.fields, (self.setup.cells() * 16) as u64);
        let fields: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
        let cell = furthest_out_of_bounds(fields, &self.health)?;
        Some(self.unhealthy(cell, fields[cell]))
    }

    /// The limits of the health check.
    pub fn health_limits(&self) -> Health {
        self.health
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

    /// The fields [`GpuLattice::keep_fields`] kept, if it was called.
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
}
