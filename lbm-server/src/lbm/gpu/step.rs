//! The fluid's step: stream and collide (seed eq. 1) over the cells by class, batched into
//! submissions, in the AA pattern's alternating phases.

use super::cell_list::CellList;
use super::state::GpuLattice;
use super::way::FluidKernels;

/// Invocations per workgroup (must match `@workgroup_size` in the shader).
const WORKGROUP: u32 = 64;
/// Most workgroups along one dispatch dimension.
const MAX_GROUPS: u32 = 65_535;

impl GpuLattice {
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

    pub(super) fn dispatch(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        pipeline: &wgpu::ComputePipeline,
        parity: u64,
    ) {
        self.dispatch_groups(
            encoder,
            pipeline,
            parity,
            (self.setup.cells() as u32).div_ceil(WORKGROUP),
        );
    }

    /// Dispatches `groups` workgroups (2D beyond the per-dimension limit).
    pub(in crate::lbm) fn dispatch_groups(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        pipeline: &wgpu::ComputePipeline,
        parity: u64,
        groups: u32,
    ) {
        let bound = &self.way().bind_groups[parity as usize];
        dispatch_bound(encoder, pipeline, bound, groups);
    }

    /// Adds one stream-collide step to `encoder`: the per-cell kernel over every cell, or the
    /// fluid cells by class (one or two dispatches), then the boundary cells.
    pub(in crate::lbm) fn encode_step(&mut self, encoder: &mut wgpu::CommandEncoder) {
        let way = self.way();
        let bound = &way.bind_groups[(self.time % 2) as usize];
        self.encode_cells(encoder, &way.classes, bound, None);
        self.time += 1;
    }

    /// The fluid kernels of this step's parity over the cells that `classes` lists, bound by
    /// `bound` (the way's whole list, or a region's: `region.rs`): the per-cell kernel over every
    /// cell, or with `listed` (its KIND 1) over the listed cells; or the quads' kernels by class.
    pub(super) fn encode_cells(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        classes: &CellList,
        bound: &wgpu::BindGroup,
        listed: Option<&wgpu::ComputePipeline>,
    ) {
        let groups = |cells: u32| cells.div_ceil(WORKGROUP);
        match (&self.way().fluid, listed) {
            (FluidKernels::Cells(_), Some(listed)) => {
                let [interior, wrapping, boundary] = classes.sizes;
                dispatch_bound(encoder, listed, bound, groups(interior + wrapping + boundary));
            }
            (FluidKernels::Cells(cells), None) => {
                dispatch_bound(encoder, cells, bound, groups(self.setup.cells() as u32));
            }
            (quads @ FluidKernels::Quads { .. }, _) => {
                encode_quads(encoder, quads, classes, bound, self.time % 2);
            }
        }
    }
}

/// The quads' kernels of step parity `parity` over the fluid cells of `c` by class (one or two
/// dispatches), then the boundary cells, bound by `bound`.
fn encode_quads(
    encoder: &mut wgpu::CommandEncoder,
    kernels: &FluidKernels,
    c: &CellList,
    bound: &wgpu::BindGroup,
    parity: u64,
) {
    let FluidKernels::Quads {
        stream_collide,
        stream_collide_fluid: fluid,
        stream_collide_quads,
        stream_collide_quads_odd,
    } = kernels
    else {
        unreachable!("the quads' kernels")
    };
    let [interior, wrapping, boundary] = c.sizes;
    let mut dispatch = |pipeline: &wgpu::ComputePipeline, cells: u32| {
        dispatch_bound(encoder, pipeline, bound, cells.div_ceil(WORKGROUP));
    };
    if parity == 0 {
        if let Some(quads) = stream_collide_quads {
            dispatch(quads, c.quads);
        }
        dispatch(&fluid[0], interior + wrapping - c.in_quads[0] - c.in_quads[1]);
    } else {
        if let Some(quads) = stream_collide_quads_odd {
            dispatch(quads, c.interior_quads);
        }
        if c.interior_quads == 0 {
            dispatch(&fluid[1], interior);
        }
        dispatch(&fluid[2], c.wrapped().1);
    }
    dispatch(stream_collide, boundary);
}

/// Dispatches `groups` workgroups of `pipeline` bound by `bound` (2D beyond the per-dimension
/// limit).
pub(super) fn dispatch_bound(
    encoder: &mut wgpu::CommandEncoder,
    pipeline: &wgpu::ComputePipeline,
    bound: &wgpu::BindGroup,
    groups: u32,
) {
    if groups == 0 {
        return;
    }
    let x = groups.min(MAX_GROUPS);
    let mut pass = encoder.begin_compute_pass(&Default::default());
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, bound, &[]);
    pass.dispatch_workgroups(x, groups.div_ceil(x), 1);
}

/// The quad kernels (four cells per invocation) against the f64 reference step: the other tests'
/// grids have no interior quads (nx not a multiple of 4).
#[cfg(test)]
mod quad_tests {
    use super::super::{CellList, Gpu, GpuLattice, Health};
    use crate::lbm::geometry::{Face, Operator, Setup};
    use crate::lbm::kernel::Kernel;
    use crate::lbm::mrt::Rates;
    use crate::lbm::random::{random_populations, Random};
    use crate::lbm::reference;
    use crate::lbm::storage::Storage;

    /// Populations after 4 steps of `setup` with `kernel` from random populations of `seed`.
    fn four_steps(setup: &Setup, kernel: Kernel, seed: u64) -> Vec<crate::lbm::geometry::Cell> {
        let gpu = std::sync::Arc::new(Gpu::new().expect("a wgpu adapter (lavapipe in CI)"));
        let setup = Setup {
            kernel,
            ..setup.clone()
        };
        let mut lattice = GpuLattice::new(gpu, setup.clone(), Health::default(), None).unwrap();
        lattice.set_populations(&random_populations(&setup, seed));
        lattice.step(4);
        lattice.populations()
    }

    /// The per-cell kernel leaves the quads' populations bit for bit, with every operator, walls,
    /// a moving wall, solids, a body force, periodic faces, and each storage.
    #[test]
    fn the_per_cell_kernel_gives_the_quads_bits() {
        let operators = [
            Operator::Bgk,
            Operator::Trt { magic: 3.0 / 16.0 },
            Operator::Mrt {
                rates: Rates::dhumieres(1.0 / 0.7),
            },
        ];
        for (o, operator) in operators.into_iter().enumerate() {
            let setup = walls_solids_force(operator, 40 + o as u64);
            for storage in Storage::ALL {
                let setup = Setup {
                    storage,
                    ..setup.clone()
                };
                let quads = four_steps(&setup, Kernel::Quads, 41);
                assert!(
                    four_steps(&setup, Kernel::Cells, 41) == quads,
                    "operator {o}, {storage:?}: the kernels differ"
                );
            }
        }
    }

    fn check(setup: Setup, seed: u64) {
        let classes = CellList::new(&setup, true);
        assert!(
            classes.quads > 0 && classes.interior_quads > 0,
            "the grid has quads"
        );
        let mut f = random_populations(&setup, seed);
        let gpu = std::sync::Arc::new(Gpu::new().expect("a wgpu adapter (lavapipe in CI)"));
        let mut lattice = GpuLattice::new(gpu, setup.clone(), Health::default(), None).unwrap();
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

    /// 12 x 7 x 6 cells at tau 0.7, periodic along x and z, a wall and a moving wall along y, a
    /// body force, and solid cells drawn from `seed` (one in twenty).
    fn walls_solids_force(operator: Operator, seed: u64) -> Setup {
        let faces = [
            Face::Periodic,
            Face::Periodic,
            Face::Wall,
            Face::MovingWall([0.02, 0.0, 0.01]),
            Face::Periodic,
            Face::Periodic,
        ];
        let mut setup = Setup::new([12, 7, 6], faces, 0.7, operator);
        setup.force = [1e-4, -2e-4, 3e-5];
        let mut r = Random::new(seed);
        for s in setup.solid.iter_mut() {
            *s = r.next() > 0.95;
        }
        setup
    }

    #[test]
    fn mrt_walls_solids_force_quads_match_reference() {
        let rates = Rates::dhumieres(1.0 / 0.7);
        let setup = walls_solids_force(Operator::Mrt { rates }, 12);
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
