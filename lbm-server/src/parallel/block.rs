//! One rank's block of a decomposed lattice ([`BlockLattice`]): its lattice on the rank's device,
//! stepped with the halo exchange in every step (overlapped with the interior's update, or after
//! the step), its own cells' fields read (each rank writes
//! its piece of a snapshot), the probe lines' cells gathered on rank 0 and its health checks
//! agreed by all ranks. On one rank it is the whole lattice, stepped and read as before.

use super::communicator::{all, Communicator};
use super::coupled_block::{block_options, SharesSent};
use super::decomposition::Decomposition;
use super::halo::Halo;
use crate::lbm::geometry::Setup;
use crate::lbm::gpu::{furthest_out_of_bounds, out_of_bounds, Gpu, GpuLattice, Health, Unhealthy};
use crate::lbm::imb::ImbOptions;
use std::sync::Arc;

/// One rank's block of the lattice.
pub struct BlockLattice {
    pub lattice: GpuLattice,
    pub decomposition: Decomposition,
    /// The whole lattice (for the cells' coordinates and the gathers).
    whole: Setup,
    pub(super) halo: Option<Halo>,
    /// What this rank sent rank 0 for the particles' loads (`coupled_block.rs`).
    pub(super) shares_sent: SharesSent,
    /// Whether [`BlockLattice::step`] overlaps the halo exchange with the interior's update
    /// (`[parallel] overlap`, on by default on a GPU), or exchanges after the whole step (exposed).
    overlap: bool,
    /// The scene's `[parallel] overlap` where it gave one ([`BlockLattice::set_overlap_asked`]).
    overlap_asked: Option<bool>,
}

/// An unhealthy cell of the whole lattice, and the rank that holds it.
pub struct RankUnhealthy {
    pub rank: usize,
    pub cell: Unhealthy,
}

impl BlockLattice {
    /// The block `d` of the lattice `setup` on `gpu`, at rest.
    pub fn new(
        gpu: Arc<Gpu>,
        setup: Setup,
        health: Health,
        d: Decomposition,
    ) -> Result<BlockLattice, String> {
        Self::with_coupling(gpu, setup, health, d, None)
    }

    /// The block `d` of the lattice `setup` on `gpu`, at rest, coupled to particles with
    /// `options` where given (the block's place in the whole lattice added: `coupled_block.rs`).
    pub fn with_coupling(
        gpu: Arc<Gpu>,
        setup: Setup,
        health: Health,
        d: Decomposition,
        options: Option<ImbOptions>,
    ) -> Result<BlockLattice, String> {
        let split = d.ranks() > 1;
        let local = if split {
            d.local_setup(&setup)
        } else {
            setup.clone()
        };
        let options = options.map(|o| block_options(o, &d, &setup));
        let mut lattice = GpuLattice::new(gpu, local, health, options)?;
        let halo = split.then(|| Halo::new(&lattice, &d, &setup));
        if split {
            let (regions, region_of) = Halo::regions(&d, d.local_n());
            lattice.set_regions(regions, region_of);
        }
        Ok(BlockLattice {
            lattice,
            decomposition: d,
            whole: setup,
            halo,
            shares_sent: SharesSent::default(),
            overlap: split,
            overlap_asked: None,
        })
    }

    /// Makes [`BlockLattice::step`] and [`BlockLattice::step_coupled_with`] overlap the halo
    /// exchange with the interior's update (`on`, the default where the lattice is decomposed),
    /// or exchange after the whole step; the same bits either way, coupled or not, whatever the
    /// way of the covered cells (`lbm/imb/by_region.rs`).
    pub fn set_overlap(&mut self, on: bool) {
        self.overlap = on && self.lattice.regions() > 0;
    }

    /// Overlaps the halo exchange as the scene's `[parallel] overlap` asks (`asked`), by default
    /// on a GPU and not on a CPU driver (scene::Parallel::overlap).
    pub fn set_overlap_asked(&mut self, asked: Option<bool>) {
        self.set_overlap(asked.unwrap_or(!self.lattice.on_cpu()));
        self.overlap_asked = asked;
    }

    /// Whether the steps overlap the halo exchange with the interior's update.
    pub fn overlaps(&self) -> bool {
        self.overlap
    }

    /// The halo exchange the steps take, as the run's first line says it (none on one rank).
    pub fn exchange_said(&self) -> Option<&'static str> {
        self.halo.as_ref()?;
        Some(match self.overlap {
            true => "halo exchange overlapped with the interior's update",
            false if self.overlap_asked.is_none() => {
                "halo exchange after the whole step (a CPU driver's default: [parallel] overlap = true overlaps)"
            }
            false => "halo exchange after the whole step ([parallel] overlap = false)",
        })
    }

    /// Completed steps.
    pub fn time(&self) -> u64 {
        self.lattice.time
    }

    /// The halo's bytes sent per step, and the time spent exchanging so far [s] (none on one
    /// rank).
    pub fn halo_cost(&self) -> (usize, f64) {
        self.halo
            .as_ref()
            .map_or((0, 0.0), |h| (h.bytes_per_step, h.time.as_secs_f64()))
    }

    /// The bytes this rank sent rank 0 per coupled step for the particles' loads, the mean over
    /// its coupled steps (none on one rank, nor from rank 0).
    pub fn shares_per_step(&self) -> usize {
        self.shares_sent.per_step()
    }

    /// Advances `steps` steps, exchanging the halo in each: overlapped with the interior's update
    /// ([`Halo::step_overlapped`]) or after the whole step ([`Halo::exchange`]).
    pub fn step(&mut self, steps: u64, comm: &dyn Communicator) {
        let Some(halo) = &mut self.halo else {
            self.lattice.step(steps);
            return;
        };
        for _ in 0..steps {
            if self.overlap {
                halo.step_overlapped(&mut self.lattice, comm);
            } else {
                self.lattice.step(1);
                halo.exchange(&self.lattice, comm);
            }
        }
    }

    /// This block's own cells' fields (density, velocity; x fastest, ghost layers left out: the
    /// whole lattice's on one rank), and the first unhealthy cell in the whole lattice's memory
    /// order, if any (at rank 0; elsewhere any rank's unhealthy cell: every rank knows whether
    /// one failed).
    pub fn own_fields(&self, comm: &dyn Communicator) -> (Vec<[f32; 4]>, Option<RankUnhealthy>) {
        let (fields, bad) = self.lattice.fields();
        if self.halo.is_none() {
            return (fields, bad.map(|cell| RankUnhealthy { rank: 0, cell }));
        }
        (self.own(&fields), self.agree(comm, bad))
    }

    /// The first unhealthy cell, as [`BlockLattice::own_fields`] finds it, without the fields.
    pub fn health(&self, comm: &dyn Communicator) -> Option<RankUnhealthy> {
        let bad = self.lattice.health();
        if self.halo.is_none() {
            return bad.map(|cell| RankUnhealthy { rank: 0, cell });
        }
        self.agree(comm, bad)
    }

    /// At rank 0, the cell of the whole lattice furthest out of the check's bounds, if any (of
    /// equals, the first in the whole lattice's memory order): each rank finds its own block's,
    /// rank 0 the furthest of those.
    pub fn furthest_unhealthy(&self, comm: &dyn Communicator) -> Option<RankUnhealthy> {
        if self.halo.is_none() {
            return self
                .lattice
                .furthest_unhealthy()
                .map(|cell| RankUnhealthy { rank: 0, cell });
        }
        let own = self.own(&self.lattice.fields().0);
        let limits = self.lattice.health_limits();
        let mine: Vec<u8> = furthest_out_of_bounds(&own, &limits)
            .map(|i| {
                let g = self.whole.index(self.decomposition.global(self.own_cell(i)));
                let by = out_of_bounds(own[i], &limits);
                cell_bytes(g, own[i], Some(by))
            })
            .unwrap_or_default();
        let furthest = comm
            .gather(&mine)
            .iter()
            .filter_map(|p| read_cell(p))
            .min_by(|a, b| b.2.total_cmp(&a.2).then(a.0.cmp(&b.0)))?;
        Some(self.whole_cell(furthest.0, furthest.1))
    }

    /// Keeps the fields on the device as the last good ones.
    pub fn keep_fields(&mut self) {
        self.lattice.keep_fields();
    }

    /// The kept fields of this block's own cells (as [`BlockLattice::own_fields`]), if kept.
    pub fn kept_own_fields(&self) -> Option<Vec<[f32; 4]>> {
        let kept = self.lattice.kept_fields()?;
        match self.halo {
            None => Some(kept),
            Some(_) => Some(self.own(&kept)),
        }
    }

    /// At rank 0, the values of the whole lattice's `cells` (indices, in their order) from every
    /// block's `own` fields (empty elsewhere): the probe lines' cells, not the whole field.
    pub fn gather_cells(&self, comm: &dyn Communicator, own: &[[f32; 4]], cells: &[usize]) -> Vec<[f32; 4]> {
        if self.halo.is_none() {
            return cells.iter().map(|&c| own[c]).collect();
        }
        let d = &self.decomposition;
        let mine: Vec<[f32; 4]> = cells
            .iter()
            .filter_map(|&c| d.own_index(self.whole.coords(c)))
            .map(|i| own[i])
            .collect();
        let pieces = comm.gather(bytemuck::cast_slice(&mine));
        if pieces.is_empty() {
            return Vec::new();
        }
        let mut next = vec![0usize; pieces.len()];
        cells
            .iter()
            .map(|&c| {
                let rank = d.owner(self.whole.coords(c));
                let values: &[[f32; 4]] = bytemuck::cast_slice(&pieces[rank]);
                next[rank] += 1;
                values[next[rank] - 1]
            })
            .collect()
    }

    /// The block's own cells of `local` (fields of the block's lattice), x fastest.
    fn own(&self, local: &[[f32; 4]]) -> Vec<[f32; 4]> {
        self.decomposition
            .own_cells()
            .iter()
            .map(|&(l, _)| local[l])
            .collect()
    }

    /// The coordinates in the block's lattice of its own cell `i` (x fastest).
    fn own_cell(&self, i: usize) -> [usize; 3] {
        let (d, s) = (&self.decomposition, self.decomposition.size);
        let x = [i % s[0], (i / s[0]) % s[1], i / (s[0] * s[1])];
        std::array::from_fn(|a| x[a] + d.lo(a))
    }

    /// The ranks agree whether a cell failed; rank 0 learns the first in the whole lattice's
    /// memory order.
    fn agree(&self, comm: &dyn Communicator, bad: Option<Unhealthy>) -> Option<RankUnhealthy> {
        let own = bad.filter(|b| !self.lattice.setup.is_ghost(b.coords));
        if all(comm, own.is_none()) {
            return None;
        }
        let mine: Vec<u8> = own
            .map(|b| {
                let g = self.whole.index(self.decomposition.global(b.coords));
                cell_bytes(g, [b.rho, b.u[0], b.u[1], b.u[2]], None)
            })
            .unwrap_or_default();
        let first = comm
            .gather(&mine)
            .iter()
            .filter_map(|p| read_cell(p))
            .min_by_key(|(cell, _, _)| *cell);
        Some(match first {
            Some((cell, v, _)) => self.whole_cell(cell, v),
            // Not rank 0: the failure is rank 0's to describe.
            None => self.whole_cell(0, [f32::NAN; 4]),
        })
    }

    /// Cell `cell` of the whole lattice with fields `v`, and the rank that holds it.
    fn whole_cell(&self, cell: usize, v: [f32; 4]) -> RankUnhealthy {
        let coords = self.whole.coords(cell);
        RankUnhealthy {
            rank: self.decomposition.owner(coords),
            cell: Unhealthy {
                cell,
                coords,
                rho: v[0],
                u: [v[1], v[2], v[3]],
            },
        }
    }
}

/// A cell of the whole lattice as a rank sends it to rank 0: its index, its fields and how far
/// they lie out of bounds (where measured).
fn cell_bytes(cell: usize, v: [f32; 4], by: Option<f64>) -> Vec<u8> {
    let mut bytes = (cell as u64).to_le_bytes().to_vec();
    bytes.extend_from_slice(bytemuck::cast_slice(&v));
    bytes.extend_from_slice(&by.unwrap_or(0.0).to_le_bytes());
    bytes
}

/// A cell sent by [`cell_bytes`] (none where the rank had none to send).
fn read_cell(p: &[u8]) -> Option<(usize, [f32; 4], f64)> {
    (p.len() == 32).then(|| {
        let cell = u64::from_le_bytes(p[..8].try_into().expect("8 bytes")) as usize;
        let v: [f32; 4] = bytemuck::pod_read_unaligned(&p[8..24]);
        (cell, v, f64::from_le_bytes(p[24..].try_into().expect("8 bytes")))
    })
}
