//! Ranks as threads of one process ([`ThreadRanks`]): the decomposed lattice without MPI, for the
//! tests (every cut against the single lattice) and for `lbm-server bench --thread-ranks N` (ranks
//! sharing one device, each with its own handle on it: what the exchange costs there).

use super::communicator::{host_name, Communicator, Expected, Message};
use std::collections::{HashMap, VecDeque};
use std::sync::{Arc, Condvar, Mutex};

/// Messages in flight between the threads: (from, to, tag) -> queue.
#[derive(Default)]
struct Post {
    boxes: Mutex<HashMap<(usize, usize, i32), VecDeque<Vec<u8>>>>,
    arrived: Condvar,
}

/// One rank of a run whose ranks are threads.
pub struct ThreadRanks {
    rank: usize,
    size: usize,
    post: Arc<Post>,
}

const GATHER: i32 = 100;
const MIN: i32 = 101;
const BROADCAST: i32 = 102;
const SCATTER: i32 = 103;

impl ThreadRanks {
    /// The `size` ranks of one run, in rank order, each to be moved into its own thread.
    pub fn world(size: usize) -> Vec<ThreadRanks> {
        let post = Arc::new(Post::default());
        (0..size)
            .map(|rank| ThreadRanks {
                rank,
                size,
                post: post.clone(),
            })
            .collect()
    }

    fn send(&self, to: usize, tag: i32, bytes: Vec<u8>) {
        let mut boxes = self.post.boxes.lock().unwrap();
        boxes.entry((self.rank, to, tag)).or_default().push_back(bytes);
        self.post.arrived.notify_all();
    }

    fn receive(&self, from: usize, tag: i32) -> Vec<u8> {
        let mut boxes = self.post.boxes.lock().unwrap();
        loop {
            if let Some(m) = boxes
                .get_mut(&(from, self.rank, tag))
                .and_then(VecDeque::pop_front)
            {
                return m;
            }
            boxes = self.post.arrived.wait(boxes).unwrap();
        }
    }
}

impl Communicator for ThreadRanks {
    fn rank(&self) -> usize {
        self.rank
    }
    fn size(&self) -> usize {
        self.size
    }
    fn local_rank(&self) -> usize {
        self.rank
    }
    fn host(&self) -> String {
        format!("{} (thread)", host_name())
    }
    fn exchange(&self, sends: &[Message], expected: &[Expected]) -> Vec<Vec<u32>> {
        for m in sends {
            self.send(m.peer, m.tag, bytemuck::cast_slice(m.words).to_vec());
        }
        expected
            .iter()
            .map(|e| {
                let v: Vec<u32> = bytemuck::pod_collect_to_vec(&self.receive(e.peer, e.tag));
                assert_eq!(v.len(), e.len, "message length");
                v
            })
            .collect()
    }
    fn gather(&self, bytes: &[u8]) -> Vec<Vec<u8>> {
        self.send(0, GATHER, bytes.to_vec());
        if self.rank != 0 {
            return Vec::new();
        }
        (0..self.size).map(|r| self.receive(r, GATHER)).collect()
    }
    fn min(&self, value: u64) -> u64 {
        (0..self.size).for_each(|r| self.send(r, MIN, value.to_le_bytes().to_vec()));
        (0..self.size)
            .map(|r| u64::from_le_bytes(self.receive(r, MIN).try_into().unwrap()))
            .min()
            .unwrap()
    }
    fn broadcast(&self, bytes: Vec<u8>) -> Vec<u8> {
        if self.rank != 0 {
            return self.receive(0, BROADCAST);
        }
        (1..self.size).for_each(|r| self.send(r, BROADCAST, bytes.clone()));
        bytes
    }
    fn scatter(&self, mut pieces: Vec<Vec<u8>>) -> Vec<u8> {
        if self.rank != 0 {
            return self.receive(0, SCATTER);
        }
        let first = std::mem::take(&mut pieces[0]);
        pieces
            .into_iter()
            .enumerate()
            .skip(1)
            .for_each(|(r, p)| self.send(r, SCATTER, p));
        first
    }
}
