//! A plain f64 reference of one full lattice-Boltzmann step (collision, streaming, boundaries),
//! used by the tests to check every GPU kernel.

use super::geometry::{Cell, Face, Link, Operator, Setup};
use super::lattice::{self, opposite, C, W};
use super::mrt;

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

/// The population f_ibar that comes back to a cell whose post-collision f*_i left through `face`.
pub fn bounce(face: Face, i: usize, f_star: f64, rho: f64, u: [f64; 3]) -> f64 {
    match face {
        Face::Wall | Face::Periodic => f_star,
        Face::MovingWall(uw) | Face::VelocityInlet(uw) => f_star - 6.0 * W[i] * rho * lattice::dot(i, uw),
        Face::PressureOutlet(rho_w) => {
            let cu = lattice::dot(i, u);
            let uu = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
            -f_star + 2.0 * W[i] * (rho_w * (1.0 + 4.5 * cu * cu - 1.5 * uu) - 1.0)
        }
    }
}

/// Density and velocity (with the half-force correction of Guo forcing).
pub fn moments(f: &Cell, force: [f64; 3]) -> (f64, [f64; 3]) {
    let rho = 1.0 + f.iter().sum::<f64>();
    let u = std::array::from_fn(|a| {
        let j: f64 = (0..19).map(|i| f[i] * C[i][a] as f64).sum();
        (j + 0.5 * force[a]) / rho
    });
    (rho, u)
}

/// Post-collision populations of one cell, with its density and velocity.
pub fn collide(setup: &Setup, f: &Cell) -> (Cell, f64, [f64; 3]) {
    let (rho, u) = moments(f, setup.force);
    let neq: Cell = std::array::from_fn(|i| f[i] - lattice::equilibrium_shifted(i, rho, u));
    let s: Cell = std::array::from_fn(|i| lattice::guo_source(i, u, setup.force));
    let out = match setup.operator {
        Operator::Bgk => {
            let w = 1.0 / setup.tau;
            std::array::from_fn(|i| f[i] - w * neq[i] + (1.0 - w / 2.0) * s[i])
        }
        Operator::Trt { .. } => {
            let (wp, wm) = (1.0 / setup.tau, setup.omega_minus());
            std::array::from_fn(|i| {
                let o = opposite(i);
                let (np, nm) = ((neq[i] + neq[o]) / 2.0, (neq[i] - neq[o]) / 2.0);
                let (sp, sm) = ((s[i] + s[o]) / 2.0, (s[i] - s[o]) / 2.0);
                f[i] - wp * np - wm * nm + (1.0 - wp / 2.0) * sp + (1.0 - wm / 2.0) * sm
            })
        }
        Operator::Mrt { rates } => {
            let (a, b) = mrt::collision_matrices(&rates);
            std::array::from_fn(|i| {
                let relax: f64 = (0..19).map(|j| a[i][j] * neq[j]).sum();
                let source: f64 = (0..19).map(|j| b[i][j] * s[j]).sum();
                f[i] - relax + source
            })
        }
    };
    (out, rho, u)
}
