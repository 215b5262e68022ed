//! The coupled step with the halo exchange overlapped with the interior's update
//! (`lbm/imb/by_region.rs`) against the exposed exchange and the single lattice: loads and fields
//! bit for bit, with the covered cells skipped, fused and redone, on 2 ranks and on a cut along two axes,
//! spheres across the cuts, in the shell and inside a block, and more spheres from a step on (the
//! coupling's buffers grow, the regions rebound); ranks as threads (`tests.rs`), without MPI.

use super::coupled_tests::{on_blocks, same_bits, single};
use super::tests::periodic_of;
use crate::lbm::geometry::Setup;
use crate::lbm::gpu::Gpu;
use crate::lbm::imb::{CoveredCells, SolidParticle};
use crate::lbm::kernel::Kernel;
use std::sync::Arc;

/// A sphere at `position` of `radius` cells, moving at `velocity` and turning.
fn sphere(position: [f64; 3], radius: f64, velocity: [f64; 3]) -> SolidParticle {
    SolidParticle {
        position,
        radius,
        velocity,
        angular_velocity: [0.01, -0.02, 0.015],
    }
}

/// The particles at step `t` on the 8 x 8 x 12 walled lattice cut at z = 6 (rank 0's shell: its
/// cells at z = 5, and its ghost layer): one across the cut, one on rank 0's shell, one inside
/// each block; from step 3 two more (one across the cut), the particles' and pairs' buffers grown.
fn across_z(t: u64) -> Vec<SolidParticle> {
    let s = 0.04 * t as f64;
    let mut spheres = vec![
        sphere([4.0, 4.0, 6.0 + s], 1.8, [0.0, 0.0, 0.04]),
        sphere([2.0, 3.0, 4.3], 1.2, [0.02, 0.0, 0.0]),
        sphere([4.5 - s, 4.0, 2.0], 1.4, [-0.04, 0.0, 0.0]),
        sphere([4.0, 3.5 + s, 9.5], 1.4, [0.0, 0.04, 0.0]),
    ];
    if t >= 3 {
        spheres.push(sphere([6.5, 5.0, 5.8], 1.3, [0.0, 0.0, 0.0]));
        spheres.push(sphere([1.5, 5.5, 8.0], 1.1, [0.01, 0.0, 0.0]));
    }
    spheres
}

/// The particles at step `t` on the 12 x 12 x 6 periodic lattice cut into [2, 2, 1] blocks (x and
/// y cut at 6 and across the periodic faces; each block's shell its own cells at 0 and 5 or 6
/// and 11 along x and y, and its ghost layers): one on the edge where the cuts meet, one across the
/// periodic x faces, one inside rank 0's block, one on a block's shell; from step 2 two more.
fn across_x_and_y(t: u64) -> Vec<SolidParticle> {
    let s = 0.05 * t as f64;
    let mut spheres = vec![
        sphere([6.0 + s, 6.0, 3.0], 1.6, [0.05, 0.0, 0.0]),
        sphere([0.2 - s, 3.0, 3.0], 1.3, [-0.05, 0.0, 0.0]),
        sphere([2.5, 2.5 + s, 3.0], 1.2, [0.0, 0.05, 0.0]),
        sphere([10.8, 8.5, 2.0 + s], 1.1, [0.0, 0.0, 0.05]),
    ];
    if t >= 2 {
        spheres.push(sphere([3.0, 9.0, 1.0], 1.4, [0.0, 0.0, -0.02]));
        spheres.push(sphere([8.6, 5.9, 4.0], 1.2, [0.0, 0.01, 0.0]));
    }
    spheres
}

/// For every way of the covered cells: `steps` coupled steps of `setup` cut into `blocks`, the exchange
/// overlapped and exposed, give the single lattice's loads and fields bit for bit.
fn check(particles: fn(u64) -> Vec<SolidParticle>, setup: &Setup, blocks: [usize; 3], steps: u64) {
    let gpu = Arc::new(Gpu::new().expect("a wgpu adapter (lavapipe in CI)"));
    for mode in [CoveredCells::Skip, CoveredCells::Fused, CoveredCells::Redo] {
        let want = single(&gpu, particles, setup, steps, mode);
        for overlap in [true, false] {
            let have = on_blocks(&gpu, particles, setup, blocks, steps, (mode, overlap));
            let what = format!(
                "{mode:?} {:?}, blocks {blocks:?}, overlapped {overlap}",
                setup.kernel
            );
            same_bits(&want, &have, &what);
        }
    }
}

/// Two ranks, walls, a moving wall during the faces' ramp, solid cells, the quads' kernels.
#[test]
fn the_overlapped_coupled_step_on_2_ranks_gives_the_single_lattices_bits() {
    let mut setup = crate::lbm::tests::trt_walls_and_solids([8, 8, 12]);
    setup.ramp_steps = 3.0;
    check(across_z, &setup, [1, 1, 2], 5);
}

/// Four ranks cut along x and y (two cut axes, the interior in two parts), periodic, the
/// per-cell kernel (its region kernel over a list).
#[test]
fn the_overlapped_coupled_step_cut_along_two_axes_gives_the_single_lattices_bits() {
    let setup = Setup {
        kernel: Kernel::Cells,
        ..periodic_of([12, 12, 6])
    };
    check(across_x_and_y, &setup, [2, 2, 1], 4);
}
