//! `lbm-server validate --only mass`, `momentum`: the mass of a closed box and the momentum of
//! fluid and a free particle.

use super::TRT;
use crate::lbm::cases;
use crate::lbm::gpu::Gpu;
use std::sync::Arc;

pub(super) fn mass(gpu: &Arc<Gpu>) -> String {
    let m = cases::closed_box_mass(gpu, 16, 10_000, TRT);
    format!(
        "\n## Mass conservation\n\nClosed 16^3 box with a moving lid (lattice speed 0.05), TRT, tau 0.6, random \
         initial populations, 10,000 steps (FP32 populations stored as f - w_i):\n\n\
         | mass before | mass after | relative drift |\n|---:|---:|---:|\n| {:.9} | {:.9} | {:.3e} |\n",
        m.before, m.after, m.relative_drift
    )
}

pub(super) fn momentum(gpu: &Arc<Gpu>) -> String {
    let m = cases::momentum_exchange(gpu, 16, 300);
    format!(
        "\n## Immersed moving boundary: momentum conservation\n\nPeriodic 16^3 box, fluid moving at 0.02 \
         along x around a free sphere (radius 16/6, density ratio 2) at rest, 300 steps, the sphere moved \
         with the returned force. Fluid + particle momentum:\n\n| initial | after 300 steps | relative \
         change | particle velocity |\n|---|---|---:|---|\n| {:.6?} | {:.6?} | {:.2e} | {:.5?} |\n",
        m.initial, m.last, m.relative_change, m.particle_velocity
    )
}
