//! A checkpoint of a lattice decomposed over ranks: the same state, to the byte, as one process
//! holds it (docs/checkpoint.md).
//!
//! Written: each rank copies its block off its device and sends rank 0 its own cells alone (no
//! ghost layer), which puts them into the whole lattice's order and combines the status words;
//! rank 0 writes the checkpoint as one process does ([`BlockLattice::whole_state`]).
//!
//! Resumed, on any number of ranks: rank 0 reads the checkpoint (checked before), and sends each
//! rank its block with its ghost layers (a scatter: the ranks get the very bytes rank 0 checked,
//! and need nothing from the file system), each ghost cell holding what the whole lattice holds
//! in the cell it stands for ([`resume_blocks`]). That is every slot an uninterrupted block's
//! own cells read in their next step, in either phase of the AA pattern (halo.rs): after an even
//! step the ghost cells hold, in the slots their neighbours read, the populations the exchange
//! wrote there, which are the whole lattice's; after an odd step the own cells read their own
//! slots alone. What else a ghost cell holds only ghost cells read.
//!
//! The status words: the first (the first unhealthy cell) as an index of the whole lattice, the
//! counts of lost covers summed (at rank 0 when resumed), and the rest, a step's scratch (the
//! covered cells' lists, cleared at every coupled step), 0 in every checkpoint, one rank's too.

use super::communicator::Communicator;
use super::decomposition::Decomposition;
use super::BlockLattice;
use crate::checkpoint::Loaded;
use crate::lbm::gpu::RawState;
use scene::checkpoint::Schedule;

/// The lattice's status words, and those kept from step to step (health, lost covers); the
/// others are a step's scratch.
const STATUS_WORDS: usize = 16;
const KEPT_WORDS: usize = 4;
/// Status word 0 of a healthy lattice.
const HEALTHY: u32 = u32::MAX;

impl BlockLattice {
    /// At rank 0, the whole lattice's state as one process holds it, every rank's own cells put
    /// together in the whole lattice's order; None at the other ranks (each sends its block).
    pub fn whole_state(&self, comm: &dyn Communicator) -> Option<RawState> {
        let mut state = self.lattice.raw_state();
        let b = self.lattice.storage().bytes();
        let d = &self.decomposition;
        let mut status = words(&state.status);
        status[0] = global_cell(d, status[0]);
        if comm.size() == 1 {
            state.status = status_bytes(&clear_scratch(status));
            return Some(state);
        }
        let mut mine = own_populations(d, &state.populations, b);
        mine.extend(status_bytes(&status));
        let pieces = comm.gather(&mine);
        (comm.rank() == 0).then(|| RawState {
            populations: put_together(d, &pieces, b),
            status: status_bytes(&combined(&pieces)),
            time: state.time,
            face_scale: state.face_scale,
        })
    }
}

/// Every rank's block put in the state of the checkpoint `resumed` (rank 0's; None at the other
/// ranks, and where the run does not resume): rank 0 reads it whole and sends each rank its block
/// with its ghost layers. Called by every rank, once each has made its block; an error at every
/// rank where rank 0 could not read the checkpoint (its own there).
pub fn resume_blocks(
    lattice: &mut BlockLattice,
    comm: &dyn Communicator,
    resumed: Option<&Loaded>,
) -> Result<(), String> {
    let b = lattice.lattice.storage().bytes();
    let cells: usize = lattice.decomposition.n.iter().product();
    restore_whole(lattice, comm, resumed.map(|l| l.raw_state(cells * b)))
}

/// Every rank's block put in the whole lattice's state `whole` as rank 0 read it (None at the
/// other ranks, and where the run does not resume), as [`resume_blocks`].
pub(super) fn restore_whole(
    lattice: &mut BlockLattice,
    comm: &dyn Communicator,
    whole: Option<Result<RawState, String>>,
) -> Result<(), String> {
    let d = lattice.decomposition.clone();
    let b = lattice.lattice.storage().bytes();
    if comm.size() == 1 {
        if let Some(state) = whole {
            lattice.lattice.restore_raw(&state?);
        }
        return Ok(());
    }
    let (time, face_scale) = match clock_of_rank_0(comm, &whole) {
        Clock::NotResumed => return Ok(()),
        Clock::Failed => {
            let theirs = "rank 0 could not read the checkpoint (its error above)".to_string();
            return Err(whole.and_then(Result::err).unwrap_or(theirs));
        }
        Clock::At(time, face_scale) => (time, face_scale),
    };
    let pieces = match &whole {
        Some(Ok(state)) => (0..d.ranks())
            .map(|r| block_of(&d.of_rank(r), state, b))
            .collect(),
        _ => Vec::new(),
    };
    let mine = comm.scatter(pieces);
    let (populations, status) = mine.split_at(mine.len() - 4 * STATUS_WORDS);
    let per_direction = populations.len() / 19;
    lattice.lattice.restore_raw(&RawState {
        populations: populations.chunks(per_direction).map(<[u8]>::to_vec).collect(),
        status: status.to_vec(),
        time,
        face_scale,
    });
    Ok(())
}

/// Whether a checkpoint is due after `step` by `schedule`, the ranks agreed: by the wall clock,
/// rank 0's (the ranks' clocks differ).
pub fn checkpoint_due(comm: &dyn Communicator, schedule: &Schedule, step: u64) -> bool {
    let due = schedule.due(step);
    if comm.size() == 1 || !schedule.by_wall_clock() {
        return due;
    }
    comm.broadcast(vec![u8::from(due)])[0] == 1
}

/// What rank 0 says of the checkpoint it resumes from.
enum Clock {
    NotResumed,
    Failed,
    /// Its step and the faces' share of velocity.
    At(u64, f64),
}

/// Rank 0's word, at every rank: whether the run resumes, and from which step (`whole`: the
/// checkpoint's state as rank 0 read it).
fn clock_of_rank_0(comm: &dyn Communicator, whole: &Option<Result<RawState, String>>) -> Clock {
    let said = match whole {
        None => vec![0],
        Some(Err(_)) => vec![1],
        Some(Ok(s)) => [
            vec![2],
            s.time.to_le_bytes().to_vec(),
            s.face_scale.to_le_bytes().to_vec(),
        ]
        .concat(),
    };
    let said = comm.broadcast(said);
    let number = |at: usize| said[at..at + 8].try_into().expect("8 bytes");
    match said[0] {
        0 => Clock::NotResumed,
        1 => Clock::Failed,
        _ => Clock::At(u64::from_le_bytes(number(1)), f64::from_le_bytes(number(9))),
    }
}

impl Decomposition {
    /// The block of rank `rank` of the same cut.
    fn of_rank(&self, rank: usize) -> Decomposition {
        Decomposition::new(self.n, self.periodic(), self.blocks, rank)
    }

    /// The coordinates in the block's lattice of its cell `k` (ghost layers included).
    fn local_coords(&self, k: usize) -> [usize; 3] {
        let n = self.local_n();
        [k % n[0], (k / n[0]) % n[1], k / (n[0] * n[1])]
    }

    /// The index in the whole lattice of the cell `x` (its coordinates there).
    fn whole_index(&self, x: [usize; 3]) -> usize {
        x[0] + self.n[0] * (x[1] + self.n[1] * x[2])
    }
}

/// The populations of the block `d`'s own cells (each direction's, x fastest) of its lattice's
/// `populations` (`b` bytes a population).
fn own_populations(d: &Decomposition, populations: &[Vec<u8>], b: usize) -> Vec<u8> {
    let own = d.own_cells();
    let mut bytes = Vec::with_capacity(19 * own.len() * b + 4 * STATUS_WORDS);
    for p in populations {
        own.iter()
            .for_each(|&(l, _)| bytes.extend_from_slice(&p[l * b..(l + 1) * b]));
    }
    bytes
}

/// The whole lattice's populations (per direction) from every rank's own cells (`pieces`, rank
/// order, as [`own_populations`] sends them, their status words after them).
fn put_together(d: &Decomposition, pieces: &[Vec<u8>], b: usize) -> Vec<Vec<u8>> {
    let cells: usize = d.n.iter().product();
    let mut whole = vec![vec![0u8; cells * b]; 19];
    for (rank, piece) in pieces.iter().enumerate() {
        let own = d.of_rank(rank).own_cells();
        for (i, direction) in whole.iter_mut().enumerate() {
            let from = &piece[i * own.len() * b..(i + 1) * own.len() * b];
            for (j, &(_, g)) in own.iter().enumerate() {
                direction[g * b..(g + 1) * b].copy_from_slice(&from[j * b..(j + 1) * b]);
            }
        }
    }
    whole
}

/// The block `d`'s lattice, its ghost layers included, from the whole lattice's `state`: each
/// cell's populations (per direction) those of the cell of the whole lattice it stands for, then
/// its status words.
fn block_of(d: &Decomposition, state: &RawState, b: usize) -> Vec<u8> {
    let cells: usize = d.local_n().iter().product();
    let mut bytes = Vec::with_capacity(19 * cells * b + 4 * STATUS_WORDS);
    let whole: Vec<usize> = (0..cells)
        .map(|k| d.whole_index(d.global(d.local_coords(k))))
        .collect();
    for p in &state.populations {
        whole
            .iter()
            .for_each(|&g| bytes.extend_from_slice(&p[g * b..(g + 1) * b]));
    }
    bytes.extend(status_bytes(&block_status(d, &words(&state.status))));
    bytes
}

/// The status words of the block `d` from the whole lattice's `whole`: the unhealthy cell at the
/// rank that holds it (as an index of its lattice), the lost covers' counts at rank 0.
fn block_status(d: &Decomposition, whole: &[u32; STATUS_WORDS]) -> [u32; STATUS_WORDS] {
    let mut status = [0u32; STATUS_WORDS];
    if d.coords == [0; 3] {
        status[1..KEPT_WORDS].copy_from_slice(&whole[1..KEPT_WORDS]);
    }
    status[0] = HEALTHY;
    if whole[0] != HEALTHY {
        let c = whole[0] as usize;
        let x = [c % d.n[0], (c / d.n[0]) % d.n[1], c / (d.n[0] * d.n[1])];
        if let Some(i) = d.own_index(x) {
            let own = d.own_cells();
            status[0] = own[i].0 as u32;
        }
    }
    status
}

/// The status words combined: the first unhealthy cell of every rank's, the counts summed, the
/// scratch 0 (`pieces` as [`BlockLattice::whole_state`] gathers them, the status words last).
fn combined(pieces: &[Vec<u8>]) -> [u32; STATUS_WORDS] {
    let mut status = [0u32; STATUS_WORDS];
    status[0] = HEALTHY;
    for piece in pieces {
        let w = words(&piece[piece.len() - 4 * STATUS_WORDS..]);
        status[0] = status[0].min(w[0]);
        for i in 1..KEPT_WORDS {
            status[i] = status[i].wrapping_add(w[i]);
        }
    }
    status
}

/// Status word 0 of the block `d` (the first unhealthy cell in its lattice, or none) as an index
/// of the whole lattice.
fn global_cell(d: &Decomposition, word: u32) -> u32 {
    if word == HEALTHY {
        return HEALTHY;
    }
    d.whole_index(d.global(d.local_coords(word as usize))) as u32
}

/// The status words kept, the scratch 0.
fn clear_scratch(mut status: [u32; STATUS_WORDS]) -> [u32; STATUS_WORDS] {
    status[KEPT_WORDS..].fill(0);
    status
}

fn words(bytes: &[u8]) -> [u32; STATUS_WORDS] {
    std::array::from_fn(|i| u32::from_le_bytes(bytes[4 * i..4 * i + 4].try_into().expect("4 bytes")))
}

fn status_bytes(words: &[u32; STATUS_WORDS]) -> Vec<u8> {
    words.iter().flat_map(|w| w.to_le_bytes()).collect()
}
