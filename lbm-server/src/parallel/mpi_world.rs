//! MPI's world as the run's [`Communicator`] (`--features mpi`): point-to-point messages started
//! together (Isend / Irecv) for the halos, gathers in rank order and an all-reduce.

use super::communicator::{host_name, launched_local_rank, Communicator, Expected, Message};
use mpi::collective::SystemOperation;
use mpi::topology::{Communicator as _, SimpleCommunicator};
use mpi::traits::{CommunicatorCollectives, Destination, Root, Source};

/// MPI, initialised for the run (finalised when dropped).
pub struct MpiWorld {
    _universe: mpi::environment::Universe,
    world: SimpleCommunicator,
}

/// The tag of the gathers' messages (the halos' tags are the faces, 0-5).
const GATHER_TAG: i32 = 100;

impl MpiWorld {
    /// Initialises MPI (once per process).
    pub fn start() -> Result<MpiWorld, String> {
        let universe = mpi::initialize().ok_or("MPI was already initialised")?;
        let world = universe.world();
        Ok(MpiWorld {
            _universe: universe,
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

    fn host(&self) -> String {
        host_name()
    }

    fn exchange(&self, sends: &[Message], expected: &[Expected]) -> Vec<Vec<f32>> {
        let mut received: Vec<Vec<f32>> = expected.iter().map(|e| vec![0f32; e.len]).collect();
        mpi::request::scope(|scope| {
            let mut receives = Vec::new();
            for (e, buffer) in expected.iter().zip(received.iter_mut()) {
                let from = self.world.process_at_rank(e.peer as i32);
                receives.push(from.immediate_receive_into_with_tag(scope, &mut buffer[..], e.tag));
            }
            let mut sent = Vec::new();
            for m in sends {
                let to = self.world.process_at_rank(m.peer as i32);
                sent.push(to.immediate_send_with_tag(scope, m.values, m.tag));
            }
            for r in receives {
                r.wait();
            }
            for s in sent {
                s.wait();
            }
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
        self.world
            .all_reduce_into(&value, &mut out, SystemOperation::min());
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
}
