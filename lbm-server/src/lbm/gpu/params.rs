//! The kernels' parameters (the shader's `Params`): grid, step parity, relaxation, body force,
//! the faces' values (with their share of velocity during the ramp) and the cell list's ranges;
//! the MRT matrices; a GPU record's vec4.

use super::cell_list::CellList;
use super::health::Health;
use super::state::GpuLattice;
use crate::lbm::geometry::{Face, Operator, Setup};
use crate::lbm::mrt;

/// Parameters as laid out in the shader's `Params`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct Params {
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

/// Each face's velocity times `scale` (a start from rest) and density, for `Params::face_value`.
fn face_values(faces: &[Face; 6], scale: f64) -> [[f32; 4]; 6] {
    faces.map(|f| {
        let ([x, y, z], rho) = f.values();
        [x * scale, y * scale, z * scale, rho].map(|v| v as f32)
    })
}

pub(super) fn params(
    setup: &Setup,
    parity: usize,
    health: Health,
    classes: &CellList,
    face_scale: f64,
) -> Params {
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
        // omega = 1/tau of the collision (seed eq. 1; tau from the viscosity by eq. 4).
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
pub(super) fn mrt_matrices(setup: &Setup) -> Vec<f32> {
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

/// A 3-vector and a fourth value as the f32 vec4 of a GPU record.
pub(crate) fn vec4(v: [f64; 3], w: f64) -> [f32; 4] {
    [v[0] as f32, v[1] as f32, v[2] as f32, w as f32]
}

impl GpuLattice {
    /// the next step on (the setup's ramp calls it; the density of an outlet is kept).
    pub fn set_face_scale(&mut self, scale: f64) {
        if scale == self.face_scale {
            return;
        }
        self.face_scale = scale;
        let values = face_values(&self.setup.faces, scale);
        let offset = std::mem::offset_of!(Params, face_value) as u64;
        let regions = self.ways.iter().flat_map(|w| &w.regions);
        let of_regions = regions.flat_map(|r| &r.regions).flat_map(|r| &r.params);
        for params in self.ways.iter().flat_map(|w| &w.params).chain(of_regions) {
            self.gpu
                .queue
                .write_buffer(params, offset, bytemuck::cast_slice(&values));
        }
    }

    /// During the setup's ramp, gives the faces their share of velocity for the next step
    /// ([`Setup::face_ramp`]); true while the ramp lasts.
    pub(in crate::lbm) fn ramp_faces(&mut self) -> bool {
        let ramping = (self.time as f64) < self.setup.ramp_steps;
        if ramping {
            self.set_face_scale(self.setup.face_ramp(self.time));
        }
        ramping
    }
}
