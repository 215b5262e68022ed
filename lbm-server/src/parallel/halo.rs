//! The halo exchange between the blocks of a decomposed lattice, after every step, of only the
//! populations that cross each block face (5 per face in D3Q19).
//!
//! The AA pattern stores the populations in place (lbm.wgsl). After an even step each cell holds
//! its own post-collision populations, reversed, in its own slots; the next (odd) step of a cell
//! next to a face reads, from the ghost cell across it, the populations that stream from it into
//! the block. So after an even step each rank sends, of its cells next to each cut face, the
//! populations that point away from that face (into the block), which the neighbour writes into
//! its ghost layer there. After an odd step each cell's populations lie in its neighbours' slots:
//! what a ghost cell streamed into the block was computed from garbage, and the neighbour, whose
//! own cell that is, computed it right and wrote it into its own ghost layer. So after an odd step
//! each rank sends, of its ghost layer at each cut face, the populations that point out across
//! it, which the neighbour writes into its cells next to that face. Every other slot a ghost cell
//! touches is read by ghost cells alone.
//!
//! A population whose link leaves the fluid on the other side (into a solid cell, or across a
//! wall of the whole lattice) is left out: the cell bounced it back into its own slot itself,
//! and no ghost cell's value may overwrite it.
//!
//! Edges and corners: axis by axis (x, then y, then z), each layer spanning the other axes' ghost
//! layers, so that what crosses an edge or corner reaches the diagonal neighbour in two or three
//! hops, each hop after the one before it has been written.

use super::communicator::{Communicator, Expected, Message};
use super::decomposition::Decomposition;
use crate::lbm::d3q19::{opposite, C};
use crate::lbm::geometry::{Link, Setup};
use crate::lbm::gpu::{GpuLattice, HaloKernels, HaloLayer};
use std::time::{Duration, Instant};

/// The halo of one rank's block: per cut face, the cells next to it (the populations pointing into
/// the block) and its ghost layer (those pointing out across it).
pub struct Halo {
    kernels: HaloKernels,
    faces: Vec<HaloFace>,
    /// Bytes sent per step, and the time spent exchanging (from the step's end on the device).
    pub bytes_per_step: usize,
    pub time: Duration,
}

struct HaloFace {
    face: usize,
    peer: usize,
    inward: HaloLayer,
    outward: HaloLayer,
}

impl Halo {
    /// The halo of `lattice`, the block `d` of the lattice `whole`.
    pub fn new(lattice: &GpuLattice, d: &Decomposition, whole: &Setup) -> Halo {
        let kernels = lattice.halo_kernels();
        let n = d.local_n();
        // Population i of cell k crosses between fluid cells: k and k - c_i are fluid.
        let crosses = |k: usize, i: usize| {
            let x = [k % n[0], (k / n[0]) % n[1], k / (n[0] * n[1])];
            let g = whole.index(d.global(x));
            !whole.solid[g] && matches!(whole.link(g, C[opposite(i)]), Link::Cell(_))
        };
        let layer = |a: usize, at: usize, sign: i32| layer(n, a, at, sign, &crosses);
        let faces: Vec<HaloFace> = (0..6)
            .filter_map(|face| {
                let peer = d.neighbour(face)?;
                let (a, hi) = (face / 2, face % 2 == 1);
                let ghost_at = if hi { n[a] - 1 } else { 0 };
                let next_at = if hi { n[a] - 2 } else { 1 };
                let toward = if hi { 1 } else { -1 };
                Some(HaloFace {
                    face,
                    peer,
                    inward: lattice.halo_layer(&kernels, &layer(a, next_at, -toward)),
                    outward: lattice.halo_layer(&kernels, &layer(a, ghost_at, toward)),
                })
            })
            .collect();
        let bytes_per_step = faces.iter().map(|f| f.inward.len() * 4).sum();
        Halo {
            kernels,
            faces,
            bytes_per_step,
            time: Duration::ZERO,
        }
    }

    /// Exchanges the halo after a step: `lattice.time` odd (an even step done) sends the cells
    /// next to each face into the neighbour's ghost layer, even (an odd step done) the ghost layer
    /// into the neighbour's cells.
    pub fn exchange(&mut self, lattice: &GpuLattice, comm: &dyn Communicator) {
        // The step done first (the pack would wait for it): the time counted is the exchange's.
        lattice.finish();
        let started = Instant::now();
        let after_even = lattice.time % 2 == 1;
        for axis in 0..3 {
            let faces: Vec<&HaloFace> = self.faces.iter().filter(|f| f.face / 2 == axis).collect();
            if faces.is_empty() {
                continue;
            }
            let (send, receive): (Vec<&HaloLayer>, Vec<&HaloLayer>) = faces
                .iter()
                .map(|f| {
                    if after_even {
                        (&f.inward, &f.outward)
                    } else {
                        (&f.outward, &f.inward)
                    }
                })
                .unzip();
            let packed = lattice.pack_halo(&self.kernels, &send);
            let messages: Vec<Message> = faces
                .iter()
                .zip(&packed)
                .map(|(f, values)| Message {
                    peer: f.peer,
                    tag: f.face as i32,
                    values,
                })
                .collect();
            // The message across face f arrives across the neighbour's opposite face, f ^ 1.
            let expected: Vec<Expected> = faces
                .iter()
                .zip(&receive)
                .map(|(f, layer)| Expected {
                    peer: f.peer,
                    tag: (f.face ^ 1) as i32,
                    len: layer.len(),
                })
                .collect();
            let received = comm.exchange(&messages, &expected);
            let unpack: Vec<(&HaloLayer, &[f32])> = receive
                .iter()
                .copied()
                .zip(received.iter().map(|v| &v[..]))
                .collect();
            lattice.unpack_halo(&self.kernels, &unpack);
        }
        self.time += started.elapsed();
    }
}

/// The populations of the layer of cells at coordinate `at` along axis `a` of a block lattice of
/// `n` cells, spanning the other axes whole (their ghost layers too), whose velocity along `a` is
/// `sign` and that `crosses` between fluid cells: (cell, direction), z, y, x and then the
/// direction in increasing order, as the neighbour lists its layer across the same face.
fn layer(
    n: [usize; 3],
    a: usize,
    at: usize,
    sign: i32,
    crosses: &dyn Fn(usize, usize) -> bool,
) -> Vec<[u32; 2]> {
    let directions: Vec<usize> = (0..19).filter(|&i| C[i][a] == sign).collect();
    let mut range: [std::ops::Range<usize>; 3] = std::array::from_fn(|b| 0..n[b]);
    range[a] = at..at + 1;
    let mut entries = Vec::new();
    for z in range[2].clone() {
        for y in range[1].clone() {
            for x in range[0].clone() {
                let k = x + n[0] * (y + n[1] * z);
                let crossing = directions.iter().filter(|&&i| crosses(k, i));
                entries.extend(crossing.map(|&i| [k as u32, i as u32]));
            }
        }
    }
    entries
}
