//! What the ranks say to one another ([`Communicator`]): halo messages, results gathered on rank
//! 0 in rank order, rank 0's bytes sent to every rank (the same, or each its own), and agreement
//! on a number. One process is a
//! communicator of one rank ([`OneRank`]); MPI's world another (`mpi_world.rs`, `--features mpi`).

/// A message of populations (their stored bits, in words: `lbm::gpu::halo`) to the rank `peer`,
/// tagged `tag` (read by MPI's world alone).
#[cfg_attr(not(feature = "mpi"), allow(dead_code))]
pub struct Message<'a> {
    pub peer: usize,
    pub tag: i32,
    pub words: &'a [u32],
}

/// A message awaited from rank `peer`, tagged `tag`, of `len` words (read by MPI's world alone).
#[cfg_attr(not(feature = "mpi"), allow(dead_code))]
pub struct Expected {
    pub peer: usize,
    pub tag: i32,
    pub len: usize,
}

/// The ranks of a run.
pub trait Communicator {
    fn rank(&self) -> usize;
    fn size(&self) -> usize;
    /// This rank's position among the ranks of its node (its GPU: `Gpu::for_local_rank`).
    fn local_rank(&self) -> usize;
    /// The name of this rank's host.
    fn host(&self) -> String;
    /// Sends `sends` and receives `expected`, all started at once (non-blocking), and waits for
    /// all of them; the received words in the order of `expected`.
    fn exchange(&self, sends: &[Message], expected: &[Expected]) -> Vec<Vec<u32>>;
    /// Every rank's `bytes` at rank 0, in rank order (empty elsewhere).
    fn gather(&self, bytes: &[u8]) -> Vec<Vec<u8>>;
    /// The smallest of the ranks' `value`s, at every rank.
    fn min(&self, value: u64) -> u64;
    /// Rank 0's `bytes` at every rank (the others' `bytes` are not read).
    fn broadcast(&self, bytes: Vec<u8>) -> Vec<u8>;
    /// Rank 0's `pieces[r]` at rank r (the others' `pieces` are not read).
    fn scatter(&self, pieces: Vec<Vec<u8>>) -> Vec<u8>;
}

/// When this process was asked to stop (Ctrl-C, SIGTERM: [`interrupted`]).
static INTERRUPTED: std::sync::OnceLock<std::time::Instant> = std::sync::OnceLock::new();

/// This process was asked to stop (Ctrl-C, SIGTERM; mpirun passes them on to every rank): the
/// ranks stop in order at their next agreement, and a rank whose peers do not answer within
/// [`STOP_DEADLINE`] of it ends them all.
pub fn interrupted() {
    let _ = INTERRUPTED.set(std::time::Instant::now());
}

/// How long a rank asked to stop waits for its peers before it ends every rank (MPI_Abort): a
/// peer killed or stuck would otherwise hold it.
#[cfg_attr(not(feature = "mpi"), allow(dead_code))]
pub const STOP_DEADLINE: std::time::Duration = std::time::Duration::from_secs(1);

/// Whether this process was asked to stop.
#[cfg_attr(not(feature = "mpi"), allow(dead_code))]
pub fn was_interrupted() -> bool {
    INTERRUPTED.get().is_some()
}

/// Whether this process was asked to stop more than [`STOP_DEADLINE`] ago.
#[cfg_attr(not(feature = "mpi"), allow(dead_code))]
pub fn past_stop_deadline() -> bool {
    INTERRUPTED.get().is_some_and(|t| t.elapsed() > STOP_DEADLINE)
}

/// Every rank waits here for rank 0 (no deadline): where a run's end leaves rank 0 more to do
/// than the others (its DEM ended, summary.json, its shared-memory files removed), they end only
/// once it is done, since a launcher (mpirun) kills every rank as soon as one exits with a code
/// other than 0, and would cut rank 0 short.
pub fn wait_for_rank_0(comm: &dyn Communicator) {
    if comm.size() > 1 {
        // A byte: MPI refuses a broadcast of none.
        comm.broadcast(vec![0]);
    }
}

/// The ranks agree: true where every rank's `ok` is.
pub fn all(comm: &dyn Communicator, ok: bool) -> bool {
    comm.min(u64::from(ok)) == 1
}

/// Rank 0's `value` at every rank (on one rank `value`).
pub fn rank0s(comm: &dyn Communicator, value: f64) -> f64 {
    if comm.size() == 1 {
        return value;
    }
    let bytes = comm.broadcast(value.to_le_bytes().to_vec());
    f64::from_le_bytes(bytes[..8].try_into().expect("8 bytes"))
}

/// A run in one process.
pub struct OneRank;

impl Communicator for OneRank {
    fn rank(&self) -> usize {
        0
    }

    fn size(&self) -> usize {
        1
    }

    fn local_rank(&self) -> usize {
        0
    }

    fn host(&self) -> String {
        host_name()
    }

    fn exchange(&self, sends: &[Message], expected: &[Expected]) -> Vec<Vec<u32>> {
        assert!(
            sends.is_empty() && expected.is_empty(),
            "one rank has no neighbour to exchange with"
        );
        Vec::new()
    }

    fn gather(&self, bytes: &[u8]) -> Vec<Vec<u8>> {
        vec![bytes.to_vec()]
    }

    fn min(&self, value: u64) -> u64 {
        value
    }

    fn broadcast(&self, bytes: Vec<u8>) -> Vec<u8> {
        bytes
    }

    fn scatter(&self, mut pieces: Vec<Vec<u8>>) -> Vec<u8> {
        pieces.swap_remove(0)
    }
}

/// This host's name (uname).
pub fn host_name() -> String {
    let mut name = [0u8; 256];
    // SAFETY: gethostname writes at most `len` bytes into the buffer.
    let ok = unsafe { libc::gethostname(name.as_mut_ptr().cast(), name.len()) } == 0;
    let end = name.iter().position(|&b| b == 0).unwrap_or(name.len());
    if ok {
        String::from_utf8_lossy(&name[..end]).into_owned()
    } else {
        "unknown".into()
    }
}

/// The ranks a launcher (mpirun, srun) started this process among, from its environment: Open
/// MPI's OMPI_COMM_WORLD_SIZE, or the PMI_SIZE of MPICH, Intel MPI and Slurm's PMI.
pub fn launched_ranks() -> Option<usize> {
    ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE"]
        .iter()
        .find_map(|v| std::env::var(v).ok()?.trim().parse().ok())
}

/// This process's position among the ranks of its node, from the launcher's environment.
#[cfg(feature = "mpi")]
pub fn launched_local_rank() -> Option<usize> {
    ["OMPI_COMM_WORLD_LOCAL_RANK", "MPI_LOCALRANKID", "SLURM_LOCALID"]
        .iter()
        .find_map(|v| std::env::var(v).ok()?.trim().parse().ok())
}
