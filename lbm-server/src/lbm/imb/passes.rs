//! The coupling's kernels, built with each way ([`Passes`]), and those of one coupled step
//! ([`StepPasses`]: the covered cells' passes of its parity).

use super::options::CoveredCells;
use crate::lbm::gpu::GpuLattice;

/// The coupling's kernels: `cover` and `reduce`, and with the redo the passes around the fluid step.
pub(in crate::lbm) struct Passes {
    cover: wgpu::ComputePipeline,
    reduce: wgpu::ComputePipeline,
    sum_loads: wgpu::ComputePipeline,
    redo: Option<Redo>,
}

/// The passes of [`CoveredCells::Redo`] and [`CoveredCells::Skip`]: `covered_groups`, then
/// `collide_covered` (before the fluid kernels) and, with the redo, `store_covered` after them
/// (skip's fluid kernels clear the cover mask as they read it), for each KIND (bit 0 the parity,
/// bit 1 the covered cells with a link that leaves the fluid).
struct Redo {
    groups: wgpu::ComputePipeline,
    collide: [wgpu::ComputePipeline; 4],
    store: Option<[wgpu::ComputePipeline; 4]>,
}

impl Passes {
    /// The cover and reduce pipelines of the way `mode`, and with the redo and skip the covered
    /// cells' collide and store (or uncover) pipelines; `make(entry, KIND)`.
    pub(in crate::lbm) fn new(
        mode: CoveredCells,
        make: &dyn Fn(&str, u32) -> wgpu::ComputePipeline,
    ) -> Passes {
        let redo = (mode != CoveredCells::Fused).then(|| Redo {
            groups: make("covered_groups", 0),
            collide: [0, 1, 2, 3].map(|kind| make("collide_covered", kind)),
            store: (mode != CoveredCells::Skip).then(|| [0, 1, 2, 3].map(|kind| make("store_covered", kind))),
        });
        Passes {
            cover: make("cover", 0),
            reduce: make("reduce", 0),
            sum_loads: make("sum_loads", 0),
            redo,
        }
    }

    /// Every kernel of the passes.
    pub(in crate::lbm) fn kernels(&self) -> Vec<&wgpu::ComputePipeline> {
        let mut all = vec![&self.cover, &self.reduce, &self.sum_loads];
        if let Some(r) = &self.redo {
            all.push(&r.groups);
            all.extend(r.collide.iter().chain(r.store.iter().flatten()));
        }
        all
    }
}

/// The pipelines of one coupled step.
pub(super) struct StepPasses {
    pub(super) cover: wgpu::ComputePipeline,
    pub(super) reduce: wgpu::ComputePipeline,
    pub(super) sum_loads: wgpu::ComputePipeline,
    /// The redo and skip: the passes over the list of covered cells.
    pub(super) covered: Option<CoveredPasses>,
}

/// The passes over the covered cells of one step's parity, for the front and the back of the list.
pub(super) struct CoveredPasses {
    pub(super) groups: wgpu::ComputePipeline,
    pub(super) collide: [wgpu::ComputePipeline; 2],
    /// The redo's `store_covered` (skip: none).
    pub(super) store: Option<[wgpu::ComputePipeline; 2]>,
}

impl GpuLattice {
    /// The pipelines of this step's passes, those over the covered cells of this parity.
    pub(super) fn step_passes(&self) -> Result<StepPasses, String> {
        let passes = self
            .way()
            .passes
            .as_ref()
            .ok_or("this lattice was made without particle coupling")?;
        // KIND = parity + 2 * (list of the cells with a link that leaves the fluid).
        let kind = |list: usize| (self.time % 2) as usize + 2 * list;
        Ok(StepPasses {
            cover: passes.cover.clone(),
            reduce: passes.reduce.clone(),
            sum_loads: passes.sum_loads.clone(),
            covered: passes.redo.as_ref().map(|r| CoveredPasses {
                groups: r.groups.clone(),
                collide: [0, 1].map(|list| r.collide[kind(list)].clone()),
                store: r.store.as_ref().map(|s| [0, 1].map(|list| s[kind(list)].clone())),
            }),
        })
    }
}
