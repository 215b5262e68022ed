//! A step split into regions of cells, each submitted alone ([`GpuLattice::step_region`]): what
//! lets a decomposed lattice overlap its halo exchange with the update of its interior
//! (`crate::parallel::halo`). Region 0 is updated first (the shell: the cells the exchange reads
//! or writes), the others after it, in any order. In the AA pattern each slot is read and written
//! by one cell's update alone within a step (lbm.wgsl), so a step split into regions leaves the
//! same populations as the whole step, bit for bit: each region's cells go through the same
//! kernels (its own cell list by class, or the per-cell kernel over its list: cells.wgsl, KIND 1),
//! compiled with its way's constants (skip's cover-mask test, the fused solid term) and bound to
//! the coupling's buffers, bound again when they grow (`GpuLattice::rebind_regions`): a coupled
//! step with the covered cells skipped or fused splits its fluid kernels so
//! (`crate::lbm::imb`, `by_region.rs`).

use super::cell_list::CellList;
use super::state::GpuLattice;
use super::way::{FluidKernels, Way};

/// One region of one way: its cell list, parameters and bind groups.
pub(super) struct Region {
    classes: CellList,
    cell_list: wgpu::Buffer,
    pub(super) params: Vec<wgpu::Buffer>,
    bind_groups: [wgpu::BindGroup; 2],
}

/// A way's regions, and with the per-cell kernel its kernel over a list (cells.wgsl, KIND 1).
pub(super) struct Regions {
    pub(super) regions: Vec<Region>,
    pub(super) cells_listed: Option<wgpu::ComputePipeline>,
}

impl GpuLattice {
    /// Splits every step taken by [`GpuLattice::step_region`] into `regions` regions, cell k in
    /// region `region_of[k]` (0 the one updated first; a region may hold no cell), for every way
    /// built and to be built.
    pub fn set_regions(&mut self, regions: usize, region_of: Vec<u8>) {
        assert_eq!(region_of.len(), self.setup.cells(), "a region per cell");
        assert!(
            region_of.iter().all(|&r| (r as usize) < regions),
            "regions 0 to {regions}"
        );
        self.region_of = Some((regions, region_of));
        let built: Vec<Regions> = self.ways.iter().map(|w| self.build_regions(w)).collect();
        for (way, regions) in self.ways.iter_mut().zip(built) {
            way.regions = Some(regions);
        }
        for way in &self.ways {
            self.compile_kernels(way);
        }
    }

    /// Regions in the split of the step ([`GpuLattice::set_regions`]; none without one).
    pub fn regions(&self) -> usize {
        self.region_of.as_ref().map_or(0, |r| r.0)
    }

    /// Submits the update of region `r` in the step under way (region 0 first, with the faces'
    /// share of velocity during the setup's ramp; then each other region once; then
    /// [`GpuLattice::end_split_step`]).
    pub fn step_region(&mut self, r: usize) -> wgpu::SubmissionIndex {
        if r == 0 {
            self.ramp_faces();
        }
        let way = self.way();
        let regions = way.regions.as_ref().expect("a step split into regions");
        let region = &regions.regions[r];
        let bound = &region.bind_groups[(self.time % 2) as usize];
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        self.encode_cells(
            &mut encoder,
            &region.classes,
            bound,
            regions.cells_listed.as_ref(),
        );
        if r == 0 {
            self.encode_store_of_shell(&mut encoder);
        }
        self.gpu.queue.submit([encoder.finish()])
    }

    /// Ends a step whose every region has been submitted (a redo's coupled step: with the store
    /// of the covered cells outside the shell).
    pub fn end_split_step(&mut self) {
        self.submit_store_of_interior();
        self.time += 1;
    }

    /// The regions of `way`, from the lattice's split of the cells (none if it has none).
    pub(super) fn build_regions(&self, way: &Way) -> Regions {
        let (count, region_of) = self.region_of.as_ref().expect("a split into regions");
        let quads = self.takes_quads(way.kernel, way.mode);
        let regions = (0..*count)
            .map(|r| {
                self.region(&CellList::within(&self.setup, quads, &|k| {
                    region_of[k] as usize == r
                }))
            })
            .collect();
        let cells_listed = matches!(way.fluid, FluidKernels::Cells(_)).then(|| {
            let constants = self.way_constants(way.mode);
            self.pipeline("stream_collide_cells", &constants, 1)
        });
        Regions {
            regions,
            cells_listed,
        }
    }

    /// The buffers and bind groups of the region whose cells `classes` lists.
    fn region(&self, classes: &CellList) -> Region {
        let list: &[u32] = if classes.list.is_empty() {
            &[0]
        } else {
            &classes.list
        };
        let (cell_list, params) = self.list_and_params(list, classes);
        let bind_groups = [0, 1].map(|parity| self.bind_group(&params[parity], &cell_list));
        Region {
            classes: CellList {
                list: Vec::new(),
                ..*classes
            },
            cell_list,
            params,
            bind_groups,
        }
    }

    /// Rebinds every region of every way (after the coupling's buffers grew).
    pub(super) fn rebind_regions(&mut self) {
        let bound: Vec<Vec<[wgpu::BindGroup; 2]>> = self
            .ways
            .iter()
            .map(|w| {
                w.regions
                    .iter()
                    .flat_map(|r| &r.regions)
                    .map(|r| [0, 1].map(|parity| self.bind_group(&r.params[parity], &r.cell_list)))
                    .collect()
            })
            .collect();
        for (way, groups) in self.ways.iter_mut().zip(bound) {
            for (region, g) in way.regions.iter_mut().flat_map(|r| &mut r.regions).zip(groups) {
                region.bind_groups = g;
            }
        }
    }
}
