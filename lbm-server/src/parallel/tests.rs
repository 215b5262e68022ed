//! A decomposed lattice against the same lattice on one rank, bit for bit: ranks as threads of
//! one process ([`ThreadRanks`]), on one device, so that these run without MPI.

use super::communicator::{Communicator, Expected, Message};
use super::{BlockLattice, Decomposition};
use crate::lbm::geometry::{Face, Operator, Setup};
use crate::lbm::gpu::{Gpu, GpuLattice, Health};
use crate::lbm::mrt::Rates;
use std::collections::{HashMap, VecDeque};
use std::sync::{Arc, Condvar, Mutex};

/// Messages in flight between the threads: (from, to, tag) -> queue.
#[derive(Default)]
struct Post {
    boxes: Mutex<HashMap<(usize, usize, i32), VecDeque<Vec<u8>>>>,
    arrived: Condvar,
}

/// One rank of a run whose ranks are threads.
pub(super) struct ThreadRanks {
    rank: usize,
    size: usize,
    post: Arc<Post>,
}

const GATHER: i32 = 100;
const MIN: i32 = 101;
const BROADCAST: i32 = 102;

impl ThreadRanks {
    /// The `size` ranks of one run, in rank order, each to be moved into its own thread.
    pub(super) fn world(size: usize) -> Vec<ThreadRanks> {
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
        "thread".into()
    }
    fn exchange(&self, sends: &[Message], expected: &[Expected]) -> Vec<Vec<f32>> {
        for m in sends {
            self.send(m.peer, m.tag, bytemuck::cast_slice(m.values).to_vec());
        }
        expected
            .iter()
            .map(|e| {
                let v: Vec<f32> = bytemuck::pod_collect_to_vec(&self.receive(e.peer, e.tag));
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
}

/// Runs `steps` steps of `setup` from rest on one lattice, and cut into `blocks` on threads;
/// checks the fields after each of the last two steps (both AA parities) bit for bit.
fn check(setup: Setup, blocks: [usize; 3], steps: u64) {
    let gpu = Arc::new(Gpu::new().expect("a wgpu adapter (lavapipe in CI)"));
    let mut one = GpuLattice::new(gpu.clone(), setup.clone(), Health::default(), None).unwrap();
    let mut expected = Vec::new();
    one.step(steps - 1);
    expected.push(one.fields().0);
    one.step(1);
    expected.push(one.fields().0);
    let ranks: usize = blocks.iter().product();
    let post = Arc::new(Post::default());
    let periodic: [bool; 3] = std::array::from_fn(|a| setup.periodic(a));
    let got: Vec<Vec<Vec<[f32; 4]>>> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..ranks)
            .map(|rank| {
                let (gpu, setup, post) = (gpu.clone(), setup.clone(), post.clone());
                s.spawn(move || {
                    let comm = ThreadRanks {
                        rank,
                        size: ranks,
                        post,
                    };
                    let d = Decomposition::new(setup.n, periodic, blocks, rank);
                    let mut block = BlockLattice::new(gpu, setup, Health::default(), d).unwrap();
                    block.step(steps - 1, &comm);
                    let first = block.fields(&comm).0;
                    block.step(1, &comm);
                    vec![first, block.fields(&comm).0]
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    for (parity, (want, have)) in expected.iter().zip(&got[0]).enumerate() {
        let differ: Vec<usize> = (0..want.len()).filter(|&k| want[k] != have[k]).collect();
        assert!(
            differ.is_empty(),
            "blocks {blocks:?}, step {}: {} cells differ, first {:?}: {:?} vs {:?}",
            steps - 1 + parity as u64,
            differ.len(),
            setup.coords(differ[0]),
            want[differ[0]],
            have[differ[0]]
        );
    }
}

/// Walls, a moving wall, solid cells (some on the cuts), a body force, TRT.
pub(super) fn walled() -> Setup {
    crate::lbm::tests::trt_walls_and_solids([8, 6, 8])
}

/// Periodic, a body force, MRT.
pub(super) fn periodic() -> Setup {
    let rates = Rates::dhumieres(1.0 / 0.8);
    let mut setup = Setup::new([8, 6, 8], [Face::Periodic; 6], 0.8, Operator::Mrt { rates });
    setup.force = [2e-4, 1e-4, -1e-4];
    setup
}

#[test]
fn a_walled_lattice_cut_along_one_axis_is_the_single_lattice_bit_for_bit() {
    check(walled(), [1, 1, 2], 6);
    check(walled(), [2, 1, 1], 6);
}

#[test]
fn a_periodic_lattice_cut_along_one_axis_is_the_single_lattice_bit_for_bit() {
    check(periodic(), [1, 2, 1], 6);
}

#[test]
fn lattices_cut_along_two_and_three_axes_are_the_single_lattice_bit_for_bit() {
    check(walled(), [2, 3, 1], 6);
    check(periodic(), [2, 2, 2], 5);
}
