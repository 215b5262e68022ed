//! One rank's block of a decomposed lattice ([`BlockLattice`]): its lattice on the rank's device,
//! stepped with the halo exchange after every step, its fields gathered on rank 0 and its health
//! checks agreed by all ranks. On one rank it is the whole lattice, stepped and read as before.

use super::communicator::{all, Communicator};
use super::coupled_block::block_options;
use super::decomposition::Decomposition;
use super::halo::Halo;
use crate::lbm::geometry::Setup;
use crate::lbm::gpu::{furthest_out_of_bounds, Gpu, GpuLattice, Health, Unhealthy};
use crate::lbm::imb::ImbOptions;
use std::sync::Arc;

/// One rank's block of the lattice.
pub struct BlockLattice {
    pub lattice: GpuLattice,
    pub decomposition: Decomposition,
    /// The whole lattice (for the cells' coordinates and the gathers).
    whole: Setup,
    pub(super) halo: Option<Halo>,
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
        let lattice = GpuLattice::new(gpu, local, health, options)?;
        let halo = split.then(|| Halo::new(&lattice, &d, &setup));
        Ok(BlockLattice {
            lattice,
            decomposition: d,
            whole: setup,
            halo,
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

    /// Advances `steps` steps, exchanging the halo after each.
    pub fn step(&mut self, steps: u64, comm: &dyn Communicator) {
        let Some(halo) = &mut self.halo else {
            self.lattice.step(steps);
            return;
        };
        for _ in 0..steps {
            self.lattice.step(1);
            halo.exchange(&self.lattice, comm);
        }
    }

    /// The whole lattice's fields (density, velocity) at rank 0 (empty elsewhere), and the first
    /// unhealthy cell in the whole lattice's memory order, if any (at rank 0; elsewhere any rank's
    /// unhealthy cell: every rank knows whether one failed).
    pub fn fields(&self, comm: &dyn Communicator) -> (Vec<[f32; 4]>, Option<RankUnhealthy>) {
        let (fields, bad) = self.lattice.fields();
        if self.halo.is_none() {
            return (fields, bad.map(|cell| RankUnhealthy { rank: 0, cell }));
        }
        let whole = self.gather(comm, &fields);
        (whole, self.agree(comm, bad))
    }

    /// The first unhealthy cell, as [`BlockLattice::fields`] finds it, without the fields.
    pub fn health(&self, comm: &dyn Communicator) -> Option<RankUnhealthy> {
        let bad = self.lattice.health();
        if self.halo.is_none() {
            return bad.map(|cell| RankUnhealthy { rank: 0, cell });
        }
        self.agree(comm, bad)
    }

    /// At rank 0, the cell of the whole lattice furthest out of the check's bounds, if any.
    pub fn furthest_unhealthy(&self, comm: &dyn Communicator) -> Option<RankUnhealthy> {
        if self.halo.is_none() {
            return self
                .lattice
                .furthest_unhealthy()
                .map(|cell| RankUnhealthy { rank: 0, cell });
        }
        let (fields, _) = self.fields(comm);
        let cell = furthest_out_of_bounds(&fields, &self.lattice.health_limits())?;
        Some(self.whole_cell(cell, fields[cell]))
    }

    /// Keeps the fields on the device as the last good ones.
    pub fn keep_fields(&mut self) {
        self.lattice.keep_fields();
    }

    /// The kept fields of the whole lattice, at rank 0.
    pub fn kept_fields(&self, comm: &dyn Communicator) -> Option<Vec<[f32; 4]>> {
        let kept = self.lattice.kept_fields();
        if self.halo.is_none() {
            return kept;
        }
        let kept = kept.unwrap_or_else(|| vec![[0.0; 4]; self.lattice.setup.cells()]);
        Some(self.gather(comm, &kept)).filter(|_| comm.rank() == 0)
    }

    /// The block's own cells of `local` (fields of the block's lattice), gathered at rank 0 into
    /// the whole lattice (empty elsewhere).
    fn gather(&self, comm: &dyn Communicator, local: &[[f32; 4]]) -> Vec<[f32; 4]> {
        let own: Vec<[f32; 4]> = self
            .decomposition
            .own_cells()
            .iter()
            .map(|&(l, _)| local[l])
            .collect();
        let pieces = comm.gather(bytemuck::cast_slice(&own));
        if pieces.is_empty() {
            return Vec::new();
        }
        let mut whole = vec![[0f32; 4]; self.whole.cells()];
        for (rank, piece) in pieces.iter().enumerate() {
            let d = self.block_of(rank);
            let values: &[[f32; 4]] = bytemuck::cast_slice(piece);
            for (&(_, g), v) in d.own_cells().iter().zip(values) {
                whole[g] = *v;
            }
        }
        whole
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
                let g = self.decomposition.global(b.coords);
                let v = [b.rho, b.u[0], b.u[1], b.u[2]];
                let mut bytes = (self.whole.index(g) as u64).to_le_bytes().to_vec();
                bytes.extend_from_slice(bytemuck::cast_slice(&v));
                bytes
            })
            .unwrap_or_default();
        let first = comm
            .gather(&mine)
            .iter()
            .filter(|p| p.len() == 24)
            .map(|p| {
                let cell = u64::from_le_bytes(p[..8].try_into().expect("8 bytes")) as usize;
                let v: [f32; 4] = bytemuck::pod_read_unaligned(&p[8..24]);
                (cell, v)
            })
            .min_by_key(|(cell, _)| *cell);
        Some(match first {
            Some((cell, v)) => self.whole_cell(cell, v),
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

    fn block_of(&self, rank: usize) -> Decomposition {
        let d = &self.decomposition;
        Decomposition::new(d.n, d.periodic(), d.blocks, rank)
    }
}
