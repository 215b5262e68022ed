//! MPI's world as the run's [`Communicator`] (`--features mpi`): point-to-point messages started
//! together (Isend / Irecv) for the halos, gathers and scatters in rank order and an all-reduce
//! (Iallreduce); the non-blocking ones waited for with a deadline once the process is asked to
//! stop.

use super::communicator::{
    host_name, launched_local_rank, past_stop_deadline, was_interrupted, Communicator, Expected, Message,
    STOP_DEADLINE,
};
use mpi::collective::SystemOperation;
use mpi::request::{Request, Scope};
use mpi::topology::{Communicator as _, SimpleCommunicator};
use mpi::traits::{CommunicatorCollectives, Destination, Root, Source};

/// MPI, initialised for the run (finalised when dropped, unless the process was asked to stop).
pub struct MpiWorld {
    universe: Option<mpi::environment::Universe>,
    world: SimpleCommunicator,
}

impl Drop for MpiWorld {
    /// A process asked to stop (Ctrl-C, SIGTERM) ends without MPI_Finalize: mpirun, ending the
    /// job, would hold it there until it kills it.
    fn drop(&mut self) {
        if was_interrupted() {
            std::mem::forget(self.universe.take());
        }
    }
}

/// The tags of the gathers' and scatters' messages (the halos' tags are the faces, 0-5).
const GATHER_TAG: i32 = 100;
const SCATTER_TAG: i32 = 101;

impl MpiWorld {
    /// Initialises MPI (once per process).
    pub fn start() -> Result<MpiWorld, String> {
        let universe = mpi::initialize().ok_or("MPI was already initialised")?;
        let world = universe.world();
        Ok(MpiWorld {
            universe: Some(universe),
            world,
        })
    }
}

impl Communicator for MpiWorld {
    fn rank(&self) -> usize {
        self.world.rank() as usize
    }

    fn size(&self) -> usize {
        self.world.size() as usize
    }

    fn local_rank(&self) -> usize {
        launched_local_rank().unwrap_or(self.rank())
    }

    /// MPI's processor name (the host's name where MPI gives none).
    fn host(&self) -> String {
        mpi::environment::processor_name().unwrap_or_else(|_| host_name())
    }

    fn exchange(&self, sends: &[Message], expected: &[Expected]) -> Vec<Vec<u32>> {
        let mut received: Vec<Vec<u32>> = expected.iter().map(|e| vec![0u32; e.len]).collect();
        mpi::request::scope(|scope| {
            let mut receives = Vec::new();
            for (e, buffer) in expected.iter().zip(received.iter_mut()) {
                let from = self.world.process_at_rank(e.peer as i32);
                receives.push(from.immediate_receive_into_with_tag(scope, &mut buffer[..], e.tag));
            }
            for m in sends {
                let to = self.world.process_at_rank(m.peer as i32);
                receives.push(to.immediate_send_with_tag(scope, m.words, m.tag));
            }
            let peers: Vec<usize> = expected.iter().map(|e| e.peer).collect();
            self.wait_all(receives, &format!("the halo of rank(s) {peers:?}"));
        });
        received
    }

    fn gather(&self, bytes: &[u8]) -> Vec<Vec<u8>> {
        if self.rank() != 0 {
            self.world.process_at_rank(0).send_with_tag(bytes, GATHER_TAG);
            return Vec::new();
        }
        let mut all = vec![bytes.to_vec()];
        for r in 1..self.size() {
            let (data, _) = self
                .world
                .process_at_rank(r as i32)
                .receive_vec_with_tag::<u8>(GATHER_TAG);
            all.push(data);
        }
        all
    }

    fn min(&self, value: u64) -> u64 {
        let mut out = 0u64;
        mpi::request::scope(|scope| {
            let op = SystemOperation::min();
            let all = self.world.immediate_all_reduce_into(scope, &value, &mut out, op);
            self.wait_all(vec![all], "the other ranks' agreement");
        });
        out
    }

    fn broadcast(&self, mut bytes: Vec<u8>) -> Vec<u8> {
        let root = self.world.process_at_rank(0);
        let mut len = bytes.len() as u64;
        root.broadcast_into(&mut len);
        bytes.resize(len as usize, 0);
        root.broadcast_into(&mut bytes[..]);
        bytes
    }

    fn scatter(&self, mut pieces: Vec<Vec<u8>>) -> Vec<u8> {
        if self.rank() != 0 {
            let from = self.world.process_at_rank(0);
            return from.receive_vec_with_tag::<u8>(SCATTER_TAG).0;
        }
        for (r, piece) in pieces.iter().enumerate().skip(1) {
            let to = self.world.process_at_rank(r as i32);
            to.send_with_tag(&piece[..], SCATTER_TAG);
        }
        pieces.swap_remove(0)
    }
}

impl MpiWorld {
    /// Waits for `requests` to complete. Where this process was asked to stop (Ctrl-C, SIGTERM)
    /// and `what` has not come [`STOP_DEADLINE`] later, a peer is gone (killed) or stuck: this
    /// rank says so and ends every rank (MPI_Abort, exit 130) rather than wait for ever.
    fn wait_all<'a, D: ?Sized, S: Scope<'a>>(&self, requests: Vec<Request<'a, D, S>>, what: &str) {
        let mut pending = requests;
        while !pending.is_empty() {
            pending = pending.into_iter().filter_map(|r| r.test().err()).collect();
            if !pending.is_empty() && past_stop_deadline() {
                protocol::say!(
                    "lbm-server: error: rank {}: asked to stop, and {what} had not come {} s later (a \
                     rank killed or stuck): ending every rank",
                    self.rank(),
                    STOP_DEADLINE.as_secs_f64()
                );
                self.world.abort(130);
            }
        }
    }
}
