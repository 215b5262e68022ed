//! The cells by class: the flags of each cell's links, and the list of cells the fluid kernels
//! take, by class and in four-cell quads.

use crate::lbm::d3q19::C;
use crate::lbm::geometry::{Face, Link, Setup};

/// Bit i set when link i of the cell leaves the fluid.
const SOLID_FLAG: u32 = 1 << 19;
/// The cell lies on a periodic face: its neighbours need wrapping.
const WRAPS_FLAG: u32 = 1 << 20;
/// The cell lies in a ghost layer (`Setup::ghost_faces`): left out of the health check.
const GHOST_FLAG: u32 = 1 << 21;

/// One word per cell: the links that leave the fluid, solid, periodic-face and ghost bits.
pub fn cell_flags(setup: &Setup) -> Vec<u32> {
    (0..setup.cells())
        .map(|k| {
            if setup.solid[k] {
                return SOLID_FLAG;
            }
            let links: u32 = (0..19)
                .filter(|&i| matches!(setup.link(k, C[i]), Link::Boundary(..)))
                .map(|i| 1u32 << i)
                .sum();
            let x = setup.coords(k);
            let on_periodic_face = (0..3).any(|a| {
                (x[a] == 0 && setup.faces[2 * a] == Face::Periodic)
                    || (x[a] + 1 == setup.n[a] && setup.faces[2 * a + 1] == Face::Periodic)
            });
            let ghost = if setup.is_ghost(x) { GHOST_FLAG } else { 0 };
            links | ghost | if on_periodic_face { WRAPS_FLAG } else { 0 }
        })
        .collect()
}

/// The fluid cells by class, and the quads. Classes: interior (no link leaves the fluid or wraps:
/// fixed neighbour offsets), wrapping (no link leaves the fluid, some cross a periodic face),
/// boundary (some link leaves the fluid). Quads: q such that cells 4q..4q+3 are all interior or
/// wrapping, whose even step moves four cells per vector access; interior quads, of four interior
/// cells, do so in the odd step too when nx is a multiple of 4 (with or without particles).
pub struct CellList {
    /// Interior cells (those of interior quads first, then those of other quads), wrapping cells
    /// (those of quads last), boundary cells, each group in increasing order, then the quads, then
    /// the interior quads.
    pub list: Vec<u32>,
    /// Interior, wrapping, boundary cells.
    pub sizes: [u32; 3],
    /// Interior and wrapping cells that belong to a quad.
    pub in_quads: [u32; 2],
    /// Interior cells that belong to an interior quad.
    pub in_interior_quads: u32,
    pub quads: u32,
    pub interior_quads: u32,
}

impl CellList {
    /// The cells of the odd step through the periodic wrap (first, count): the wrapping cells and,
    /// when there are interior quads, the interior cells outside them too (one dispatch fewer).
    pub fn wrapped(&self) -> (u32, u32) {
        let [interior, wrapping, _] = self.sizes;
        if self.interior_quads > 0 {
            (
                self.in_interior_quads,
                interior + wrapping - self.in_interior_quads,
            )
        } else {
            (interior, wrapping)
        }
    }

    /// The cell list, with the quads when `quads` (without, every interior and wrapping cell goes
    /// through `stream_collide_fluid`).
    pub fn new(setup: &Setup, quads: bool) -> CellList {
        Self::within(setup, quads, &|_| true)
    }

    /// The cell list of the cells `keep` keeps alone (a region of the step: `region.rs`), each
    /// quad's four cells kept together or left to the other kernels.
    pub fn within(setup: &Setup, quads: bool, keep: &dyn Fn(usize) -> bool) -> CellList {
        let classes: Vec<u32> = cell_flags(setup)
            .into_iter()
            .enumerate()
            .map(|(k, flag)| if keep(k) { class(flag) } else { LEFT_OUT })
            .collect();
        let cells = classes.len();
        let (quads, interior_quads) = find_quads(setup, &classes, quads);
        let membership = membership(cells, &quads, &interior_quads);
        let (classes, membership) = (&classes, &membership);
        let select = |c: u32, m: u8| {
            (0..cells)
                .filter(move |&k| classes[k] == c && membership[k] == m)
                .map(|k| k as u32)
        };
        let mut list: Vec<u32> = select(0, 2).collect();
        let in_interior_quads = list.len() as u32;
        list.extend(select(0, 1));
        let interior_in_quads = list.len() as u32;
        list.extend(select(0, 0));
        let interior = list.len() as u32;
        list.extend(select(1, 0));
        let before = list.len() as u32;
        list.extend(select(1, 1));
        let wrapping_in_quads = list.len() as u32 - before;
        let wrapping = list.len() as u32 - interior;
        list.extend(select(2, 0));
        let boundary = list.len() as u32 - interior - wrapping;
        list.extend(&quads);
        list.extend(&interior_quads);
        CellList {
            list,
            sizes: [interior, wrapping, boundary],
            in_quads: [interior_in_quads, wrapping_in_quads],
            in_interior_quads,
            quads: quads.len() as u32,
            interior_quads: interior_quads.len() as u32,
        }
    }
}

/// The class of a solid cell, or of one the list leaves out: in no class.
const LEFT_OUT: u32 = 3;

/// A cell's class from its flags: 0 interior, 1 wrapping, 2 boundary, 3 solid.
fn class(flag: u32) -> u32 {
    if flag & SOLID_FLAG != 0 {
        LEFT_OUT
    } else if flag & 0x7ffff != 0 {
        2
    } else if flag & WRAPS_FLAG != 0 {
        1
    } else {
        0
    }
}

/// The quads (when `quads`: four cells of class at most 1, interior or wrapping) and the interior
/// quads among them (four interior cells, when nx is a multiple of 4), from the cells' classes.
fn find_quads(setup: &Setup, classes: &[u32], quads: bool) -> (Vec<u32>, Vec<u32>) {
    let all = |q: usize, most: u32| (4 * q..4 * q + 4).all(|k| classes[k] <= most);
    let quads: Vec<u32> = (0..classes.len() / 4)
        .filter(|&q| quads && all(q, 1))
        .map(|q| q as u32)
        .collect();
    let interior_quads: Vec<u32> = quads
        .iter()
        .copied()
        .filter(|&q| setup.n[0].is_multiple_of(4) && all(q as usize, 0))
        .collect();
    (quads, interior_quads)
}

/// Per cell: 0 in no quad, 1 in a quad, 2 in an interior quad.
fn membership(cells: usize, quads: &[u32], interior_quads: &[u32]) -> Vec<u8> {
    let mut membership = vec![0u8; cells];
    for (quads, value) in [(quads, 1), (interior_quads, 2)] {
        for q in quads {
            membership[4 * *q as usize..4 * *q as usize + 4].fill(value);
        }
    }
    membership
}
