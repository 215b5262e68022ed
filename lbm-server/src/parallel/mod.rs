//! A lattice decomposed over ranks: each rank holds one block of the lattice, with a ghost layer
//! at each face it shares with another rank, on its own device.
//!
//! - `communicator.rs`: what the ranks say to one another ([`Communicator`]); one process is a
//!   communicator of one rank, MPI's world another (`mpi_world.rs`, built with `--features mpi`).
//! - `decomposition.rs`: the blocks, chosen or given by the scene, and one rank's block.
//! - `halo.rs`: the exchange of the populations that cross the block faces, in every step,
//!   overlapped with the interior's update or after the whole step.
//! - `block.rs`: one rank's lattice, stepped, read and checked with the others ([`BlockLattice`]).
//! - `pieces.rs`: the field snapshots as ParaView parallel image data, a piece per rank
//!   ([`FieldPieces`]).
//! - `hosts.rs`: the ranks' hosts; a run with particles keeps its ranks on rank 0's host.
//! - `block.rs`: one rank's lattice, stepped, read and checked with the others ([`BlockLattice`]);
//!   `coupled_block.rs`: its coupled step with particles (the loads made at rank 0 from every
//!   rank's share: the loads of the particles within its block, the covered cells it holds of
//!   those across a cut).
//! - `checkpoint.rs`: a checkpoint of the blocks, the same as one process's: written from every
//!   rank's own cells gathered at rank 0, resumed on any number of ranks (rank 0 sends each rank
//!   its block with its ghost layers).
//! - `summary.rs`: what summary.json says of the ranks.
//! - `thread_ranks.rs`: ranks as threads of one process (the tests; `bench --thread-ranks`).
//!
//! Every rank runs the same code, one rank included: a run on one rank is the single-process run.

mod block;
mod checkpoint;
#[cfg(test)]
mod checkpoint_tests;
mod communicator;
mod coupled_block;
#[cfg(test)]
mod coupled_overlap_tests;
#[cfg(test)]
mod coupled_tests;
mod decomposition;
mod halo;
mod hosts;
#[cfg(feature = "mpi")]
mod mpi_world;
mod pieces;
mod summary;
#[cfg(test)]
mod tests;
mod thread_ranks;

pub use block::{BlockLattice, RankUnhealthy};
pub use checkpoint::{checkpoint_due, resume_blocks};
pub use communicator::launched_ranks;
use communicator::OneRank;
pub use communicator::{all, interrupted, rank0s, wait_for_rank_0, Communicator};
pub use decomposition::{check_blocks, choose_blocks, Decomposition};
pub use hosts::{dem_hosts, hosts};
pub use pieces::{write_last_good_of_ranks, write_snapshot_of_ranks, FieldPieces};
pub use summary::ParallelSummary;
pub use thread_ranks::ThreadRanks;

/// Whether this build runs on several ranks (`--features mpi`).
pub const MPI_BUILD: bool = cfg!(feature = "mpi");

/// The ranks of this run: MPI's world in an MPI build started by a launcher (mpirun, srun),
/// else one rank (MPI left alone). A process that a launcher started among several ranks in a
/// build without MPI is refused: each would run the whole scene alone.
pub fn start() -> Result<Box<dyn Communicator>, String> {
    #[cfg(feature = "mpi")]
    {
        if launched_ranks().is_none() {
            return Ok(Box::new(OneRank));
        }
        Ok(Box::new(mpi_world::MpiWorld::start()?))
    }
    #[cfg(not(feature = "mpi"))]
    {
        match launched_ranks() {
            Some(n) if n > 1 => Err(format!(
                "started as one of {n} ranks (mpirun or srun), but this lbm-server is built without \
                 MPI, and each rank would run the whole scene alone: build it with `cargo build \
                 --release -p lbm-server --features mpi` (needs libopenmpi-dev and libclang-dev)"
            )),
            _ => Ok(Box::new(OneRank)),
        }
    }
}

/// The blocks of a run of the lattice `n` (periodic along `periodic`) on `ranks` ranks: the
/// scene's `[parallel] blocks` checked, or chosen for the fewest halo cells.
pub fn blocks_of(
    n: [usize; 3],
    periodic: [bool; 3],
    given: Option<[usize; 3]>,
    ranks: usize,
) -> Result<[usize; 3], String> {
    if let Some(blocks) = given {
        if !MPI_BUILD && blocks.iter().product::<usize>() > 1 {
            return Err(format!(
                "parallel.blocks = [{}, {}, {}]: more than one block needs the MPI build \
                 (`cargo build --release -p lbm-server --features mpi`, run under mpirun)",
                blocks[0], blocks[1], blocks[2]
            ));
        }
        check_blocks(n, blocks, ranks)?;
        return Ok(blocks);
    }
    let cells: usize = n.iter().product();
    if ranks > cells {
        return Err(format!(
            "{ranks} ranks for a lattice of {cells} cells: more ranks than cells"
        ));
    }
    choose_blocks(n, periodic, ranks)
}
