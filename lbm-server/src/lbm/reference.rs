//! A plain f64 reference of one full lattice-Boltzmann step (collision, streaming, boundaries),
//! used by the tests to check every GPU kernel.

use super::geometry::{bounce, collide, Cell, Link, Setup};
use super::lattice::{opposite, C};

/// One step: populations (shifted, natural layout) at t -> at t + 1.
pub fn step(setup: &Setup, f: &[Cell]) -> Vec<Cell> {
    let mut next = f.to_vec();
    for cell in (0..setup.cells()).filter(|&c| !setup.solid[c]) {
        let (post, rho, u) = collide(setup, &f[cell]);
        for i in 0..19 {
            match setup.link(cell, C[i]) {
                Link::Cell(t) => next[t][i] = post[i],
                Link::Boundary(face) => next[cell][opposite(i)] = bounce(face, i, post[i], rho, u),
            }
        }
    }
    next
}
