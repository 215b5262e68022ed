//! What summary.json says of the ranks ([`ParallelSummary`]).

use super::{BlockLattice, Communicator};
use serde::Serialize;

/// How the run was spread over ranks: their count, the blocks along x, y and z, and each rank's
/// host and device (rank order).
#[derive(Debug, Clone, Serialize)]
pub struct ParallelSummary {
    pub ranks: usize,
    pub blocks: [usize; 3],
    pub devices: Vec<String>,
    /// Bytes each rank's halo sent per step (rank order), and the share of the wall time its
    /// host spent in the exchange (overlapped: from the interior's submission on, part of it
    /// hidden behind the interior's update).
    pub halo_bytes_per_step: Vec<usize>,
    pub halo_share: Vec<f64>,
    /// Bytes each rank sent rank 0 per coupled step for the particles' loads (rank order; the
    /// mean over the run's steps; none from rank 0, none without particles).
    pub loads_bytes_per_step: Vec<usize>,
    /// Whether the exchange overlapped the interior's update (`[parallel] overlap`; a coupled
    /// run's exchange follows the whole step where the covered cells are redone).
    pub halo_overlapped: bool,
}

impl ParallelSummary {
    /// Gathered from every rank at rank 0 (elsewhere: this rank's alone).
    pub fn gather(
        comm: &dyn Communicator,
        lattice: &BlockLattice,
        device: &str,
        wall: f64,
    ) -> ParallelSummary {
        let (bytes, time) = lattice.halo_cost();
        let loads = lattice.shares_per_step();
        let mine = format!(
            "{}\t{}\t{bytes}\t{}\t{loads}",
            comm.host(),
            device,
            time / wall.max(1e-9)
        );
        let rows: Vec<Vec<String>> = comm
            .gather(mine.as_bytes())
            .iter()
            .map(|r| String::from_utf8_lossy(r).split('\t').map(String::from).collect())
            .collect();
        ParallelSummary {
            ranks: comm.size(),
            blocks: lattice.decomposition.blocks,
            devices: rows.iter().map(|r| format!("{}: {}", r[0], r[1])).collect(),
            halo_bytes_per_step: rows.iter().map(|r| r[2].parse().unwrap_or(0)).collect(),
            halo_share: rows.iter().map(|r| r[3].parse().unwrap_or(0.0)).collect(),
            loads_bytes_per_step: rows.iter().map(|r| r[4].parse().unwrap_or(0)).collect(),
            halo_overlapped: lattice.overlaps(),
        }
    }
}
