//! The halo exchange between the blocks of a decomposed lattice, in every step, of only the
//! populations that cross each block face (5 per face in D3Q19): after the whole step
//! ([`Halo::exchange`]), or overlapped with the update of the block's interior
//! ([`Halo::step_overlapped`]).
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
//! The overlap: the slots the exchange reads and writes are, after an even step, those of the
//! cells next to each cut face and of its ghost layer; after an odd step, those of the ghost layer
//! that the cells next to the face stream into, and those of the cells next to the face that the
//! ghost layer streams into. Within a step every slot is read and written by one cell's update
//! alone (the AA pattern), and a cell two layers or more from every cut face (the interior) reads
//! and writes none of those slots, in either parity. So the step updates the shell (each cut
//! face's ghost layer and the layer next to it) first, packs, and the interior's update may run
//! before or after the unpack lands; the next step's shell comes after both.
//!
//! A coupled step splits only its fluid kernels so (`lbm/imb/by_region.rs`): the passes over the
//! particles and the covered cells keep their places around them, skipped covered cells collide
//! before the shell (its slots final before the pack), fused ones in the fluid kernels of their
//! region, the redo's `store_covered` of the shell's covered cells right after the shell's update
//! and of the others after the interior's.
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
    /// The cut faces, grouped by axis (built once), in the order of the exchange (x, y, z).
    cuts: Vec<Vec<HaloFace>>,
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
        let bytes_per_step = faces.iter().map(|f| f.inward.words() * 4).sum();
        Halo {
            kernels,
            cuts: by_axis(faces),
            bytes_per_step,
            time: Duration::ZERO,
        }
    }

    /// Exchanges the halo after a step, the whole step done first (exposed): `lattice.time` odd
    /// (an even step done) sends the cells next to each face into the neighbour's ghost layer,
    /// even (an odd step done) the ghost layer into the neighbour's cells.
    pub fn exchange(&mut self, lattice: &GpuLattice, comm: &dyn Communicator) {
        // The step done first (the pack would wait for it): the time counted is the exchange's.
        lattice.finish();
        let started = Instant::now();
        let after_even = lattice.time % 2 == 1;
        for faces in &self.cuts {
            let (send, receive) = sides(faces, after_even);
            let packed = lattice.pack_halo(&self.kernels, &send);
            let received = comm.exchange(&messages(faces, &packed), &expected(faces, &receive));
            lattice.unpack_halo(&self.kernels, &unpacked(&receive, &received));
        }
        self.time += started.elapsed();
    }

    /// One step of `lattice` with the exchange overlapped with the interior's update: the shell
    /// (region 0: [`Halo::regions`]) first; then per cut axis the pack of its faces, the next
    /// part of the interior submitted behind it, and while the device updates that part the pack
    /// read back, sent and received, and unpacked. Each slot the exchange reads or writes is one
    /// the shell's cells alone read and write in the step (the module's account), so the interior
    /// may be updated before or after the unpack; the next step's shell comes after it.
    pub fn step_overlapped(&mut self, lattice: &mut GpuLattice, comm: &dyn Communicator) {
        let after_even = lattice.time.is_multiple_of(2);
        lattice.step_region(0);
        for (part, faces) in self.cuts.iter().enumerate() {
            let (send, receive) = sides(faces, after_even);
            let packed = lattice.submit_pack(&self.kernels, &send);
            lattice.step_region(1 + part);
            // The host's time in the exchange: from here (the device on the interior).
            let started = Instant::now();
            let packed = lattice.read_packed(&send, packed);
            let received = comm.exchange(&messages(faces, &packed), &expected(faces, &receive));
            lattice.unpack_halo(&self.kernels, &unpacked(&receive, &received));
            self.time += started.elapsed();
        }
        lattice.end_split_step();
    }

    /// The box of cells `lo` to `hi` (excluded) of the block `d` of `n` cells (ghost layers
    /// included) outside its shell: the shell is every cell within two layers of a face with a
    /// ghost layer (the ghost layer and the layer next to it, whose slots the exchange reads and
    /// writes). [`Halo::regions`] draws the regions by it, and the redo's store of the shell's
    /// covered cells goes by it (`ImbBlock::interior_*`, imb_covered.wgsl `in_shell`).
    pub fn interior(d: &Decomposition, n: [usize; 3]) -> ([usize; 3], [usize; 3]) {
        let layers = |f: usize| if d.neighbour(f).is_some() { 2 } else { 0 };
        (
            std::array::from_fn(|a| layers(2 * a)),
            std::array::from_fn(|a| n[a] - layers(2 * a + 1)),
        )
    }

    /// The regions of a step split for the overlapped exchange, and each cell's, in the block `d` of
    /// `n` cells (ghost layers included): 0, the shell, the cells of each cut face's ghost layer
    /// and of the layer next to it (those whose slots the exchange reads or writes); then the
    /// interior cut into as many parts as there are cut axes (whole, in memory order), the part
    /// `p` updated while the exchange across the `p`-th axis runs.
    pub fn regions(d: &Decomposition, n: [usize; 3]) -> (usize, Vec<u8>) {
        let (lo, hi) = Halo::interior(d, n);
        let in_shell = |x: [usize; 3]| (0..3).any(|a| x[a] < lo[a] || x[a] >= hi[a]);
        let cells = n.iter().product::<usize>();
        let shell: Vec<bool> = (0..cells)
            .map(|k| in_shell([k % n[0], (k / n[0]) % n[1], k / (n[0] * n[1])]))
            .collect();
        let axes = cut_axes(d);
        let interior = shell.iter().filter(|s| !**s).count().max(1);
        let mut seen = 0;
        let region_of = shell
            .iter()
            .map(|&s| {
                if s {
                    return 0;
                }
                seen += 1;
                (1 + (seen - 1) * axes.len() / interior) as u8
            })
            .collect();
        (1 + axes.len(), region_of)
    }
}

/// The axes the block `d` is cut across, in the order of the exchange (x, y, z).
fn cut_axes(d: &Decomposition) -> Vec<usize> {
    let mut axes: Vec<usize> = (0..6)
        .filter(|&f| d.neighbour(f).is_some())
        .map(|f| f / 2)
        .collect();
    axes.dedup();
    axes
}

/// `faces`, in face order, grouped by axis: the faces across each cut axis, in the order of the
/// exchange (x, y, z), as [`cut_axes`] lists the axes.
fn by_axis(faces: Vec<HaloFace>) -> Vec<Vec<HaloFace>> {
    let mut cuts: Vec<Vec<HaloFace>> = Vec::new();
    for f in faces {
        match cuts.last_mut() {
            Some(cut) if cut[0].face / 2 == f.face / 2 => cut.push(f),
            _ => cuts.push(vec![f]),
        }
    }
    cuts
}

/// The layers each of `faces` (across one axis) sends and receives after an even step
/// (`after_even`) or an odd one.
fn sides(faces: &[HaloFace], after_even: bool) -> (Vec<&HaloLayer>, Vec<&HaloLayer>) {
    faces
        .iter()
        .map(|f| {
            if after_even {
                (&f.inward, &f.outward)
            } else {
                (&f.outward, &f.inward)
            }
        })
        .unzip()
}

/// The message of each of `faces` with its `packed` words.
fn messages<'a>(faces: &[HaloFace], packed: &'a [Vec<u32>]) -> Vec<Message<'a>> {
    faces
        .iter()
        .zip(packed)
        .map(|(f, words)| Message {
            peer: f.peer,
            tag: f.face as i32,
            words,
        })
        .collect()
}

/// The message awaited across each of `faces` into its layer of `receive`: the message across
/// face f arrives across the neighbour's opposite face, f ^ 1.
fn expected(faces: &[HaloFace], receive: &[&HaloLayer]) -> Vec<Expected> {
    faces
        .iter()
        .zip(receive)
        .map(|(f, layer)| Expected {
            peer: f.peer,
            tag: (f.face ^ 1) as i32,
            len: layer.words(),
        })
        .collect()
}

/// Each layer of `receive` with its words `received`.
fn unpacked<'a>(receive: &[&'a HaloLayer], received: &'a [Vec<u32>]) -> Vec<(&'a HaloLayer, &'a [u32])> {
    receive
        .iter()
        .copied()
        .zip(received.iter().map(|v| &v[..]))
        .collect()
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
