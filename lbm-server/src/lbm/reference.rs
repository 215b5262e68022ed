//! A plain f64 reference of one full lattice-Boltzmann step (collision, streaming, boundaries),
//! used by the tests to check every GPU kernel.

use super::d3q19::{self, opposite, C, W};
use super::geometry::{Cell, Face, Link, Operator, Setup};
use super::imb::{box_edge, into_lattice, ImbOptions, Load, SolidCollision, SolidParticle};
use super::mrt;

/// One step: populations (shifted, natural layout) at t -> at t + 1.
pub fn step(setup: &Setup, f: &[Cell]) -> Vec<Cell> {
    step_with_particles(setup, f, &[], ImbOptions::default()).0
}

/// One step with particles coupled by the immersed moving boundary: the populations at t + 1 and
/// each particle's force and torque (same solid fractions, weighting and order as imb.wgsl).
pub fn step_with_particles(
    setup: &Setup,
    f: &[Cell],
    particles: &[SolidParticle],
    options: ImbOptions,
) -> (Vec<Cell>, Vec<Load>) {
    let particles: Vec<SolidParticle> = particles.iter().map(|p| into_lattice(setup, p)).collect();
    let particles = &particles[..];
    let covers = cover(setup, particles, options.slots as usize);
    let mut loads = vec![Load::default(); particles.len()];
    let mut next = f.to_vec();
    for cell in (0..setup.cells()).filter(|&c| !setup.solid[c]) {
        let (mut post, rho, u) = collide(setup, &f[cell]);
        if !covers[cell].is_empty() {
            post = immersed_boundary(
                setup,
                &f[cell],
                &post,
                rho,
                u,
                &covers[cell],
                particles,
                options,
                &mut loads,
            );
        }
        // Streaming (eq. 1): f_i(x + c_i, t + 1), or back into the cell through a boundary.
        for i in 0..19 {
            match setup.link(cell, C[i]) {
                Link::Cell(t) => next[t][i] = post[i],
                Link::Boundary(face, index) => {
                    next[cell][opposite(i)] = bounce(face, index, i, post[i], rho, u)
                }
            }
        }
    }
    (next, loads)
}

/// The population f_ibar that comes back to a cell whose post-collision f*_i left through `face`
/// (face `index`: x_min, x_max, ... z_max).
pub fn bounce(face: Face, index: usize, i: usize, f_star: f64, rho: f64, u: [f64; 3]) -> f64 {
    match face {
        Face::Wall | Face::Periodic => f_star,
        Face::MovingWall(uw) | Face::VelocityInlet(uw) => f_star - 6.0 * W[i] * rho * d3q19::dot(i, uw),
        Face::PressureOutlet(rho_w) => d3q19::equilibrium_shifted(opposite(i), rho_w, outflow(index, u)),
    }
}

/// The velocity of a pressure outlet's equilibrium: the cell's, less any part into the fluid
/// through face `index` (no backflow).
pub fn outflow(index: usize, u: [f64; 3]) -> [f64; 3] {
    let axis = index / 2;
    let outward = if index % 2 == 1 { 1.0 } else { -1.0 };
    let mut out = u;
    if u[axis] * outward < 0.0 {
        out[axis] = 0.0;
    }
    out
}

/// Density (seed eq. 5) and velocity (eq. 6), with the half-force correction of Guo forcing.
pub fn moments(f: &Cell, force: [f64; 3]) -> (f64, [f64; 3]) {
    let rho = 1.0 + f.iter().sum::<f64>();
    let u = std::array::from_fn(|a| {
        let j: f64 = (0..19).map(|i| f[i] * C[i][a] as f64).sum();
        (j + 0.5 * force[a]) / rho
    });
    (rho, u)
}

/// Post-collision populations of one cell (seed eq. 1: f_i - omega (f_i - f_eq_i) + G_i, with the
/// equilibrium of eq. 3; BGK's omega = 1/tau, tau from the viscosity by eq. 4), with its density
/// and velocity.
pub fn collide(setup: &Setup, f: &Cell) -> (Cell, f64, [f64; 3]) {
    let (rho, u) = moments(f, setup.force);
    let neq: Cell = std::array::from_fn(|i| f[i] - d3q19::equilibrium_shifted(i, rho, u));
    let source = forcing(setup, u);
    let relaxed: Cell = match setup.operator {
        Operator::Bgk => {
            let w = 1.0 / setup.tau;
            std::array::from_fn(|i| f[i] - w * neq[i])
        }
        Operator::Trt { .. } => {
            let (wp, wm) = (1.0 / setup.tau, setup.omega_minus());
            std::array::from_fn(|i| {
                let o = opposite(i);
                let (np, nm) = ((neq[i] + neq[o]) / 2.0, (neq[i] - neq[o]) / 2.0);
                f[i] - wp * np - wm * nm
            })
        }
        Operator::Mrt { rates } => {
            let (a, _) = mrt::collision_matrices(&rates);
            std::array::from_fn(|i| f[i] - (0..19).map(|j| a[i][j] * neq[j]).sum::<f64>())
        }
    };
    (std::array::from_fn(|i| relaxed[i] + source[i]), rho, u)
}

/// The body force's part of the collision at velocity u (seed eq. 1's G_i): Guo's source through
/// the operator's relaxation factors (lbm.wgsl `forcing`).
pub fn forcing(setup: &Setup, u: [f64; 3]) -> Cell {
    let s: Cell = std::array::from_fn(|i| d3q19::guo_source(i, u, setup.force));
    match setup.operator {
        Operator::Bgk => {
            let w = 1.0 / setup.tau;
            s.map(|s| (1.0 - w / 2.0) * s)
        }
        Operator::Trt { .. } => {
            let (wp, wm) = (1.0 / setup.tau, setup.omega_minus());
            std::array::from_fn(|i| {
                let o = opposite(i);
                let (sp, sm) = ((s[i] + s[o]) / 2.0, (s[i] - s[o]) / 2.0);
                (1.0 - wp / 2.0) * sp + (1.0 - wm / 2.0) * sm
            })
        }
        Operator::Mrt { rates } => {
            let (_, b) = mrt::collision_matrices(&rates);
            std::array::from_fn(|i| (0..19).map(|j| b[i][j] * s[j]).sum())
        }
    }
}

/// Fraction of the cell centred at `x` inside the sphere (the solid fraction that eq. 7's B
/// weighs), as imb.wgsl: the fraction of a unit cell
/// below a face-aligned plane at the centre's distance from the surface, on a radius shortened by
/// 1/(12 r) (docs/imb.md).
pub fn solid_fraction(x: [f64; 3], centre: [f64; 3], r: f64) -> f64 {
    let d = (0..3).map(|a| (x[a] - centre[a]).powi(2)).sum::<f64>().sqrt();
    (r - 1.0 / (12.0 * r) + 0.5 - d).clamp(0.0, 1.0)
}

/// A particle covering a cell: its index, the solid fraction, and the cell's centre in the
/// particle's box (one period away from the cell's own where the box wraps).
type Cover = (usize, f64, [f64; 3]);

/// Per cell: the particles covering it, at most `slots` of them: the largest solid fractions in
/// 1/255ths, the lower index first among equals (imb.wgsl `slot_key`).
fn cover(setup: &Setup, particles: &[SolidParticle], slots: usize) -> Vec<Vec<Cover>> {
    let mut covers = vec![Vec::new(); setup.cells()];
    for (j, p) in particles.iter().enumerate() {
        for (cell, x) in box_cells(setup, p) {
            let eps = solid_fraction(x, p.position, p.radius);
            if eps > 0.0 && !setup.solid[cell] {
                covers[cell].push((j, eps, x));
            }
        }
    }
    let rank = |&(j, eps, _): &Cover| (std::cmp::Reverse((eps * 255.0).ceil() as u32), j);
    for c in covers.iter_mut().filter(|c| c.len() > slots) {
        c.sort_by_key(rank);
        c.truncate(slots);
    }
    covers
}

/// The cells of a particle's bounding box inside the domain (wrapped along the periodic axes), in
/// the order of imb.wgsl, with their centres in the box (unwrapped).
pub(super) fn box_cells<'a>(
    setup: &'a Setup,
    p: &SolidParticle,
) -> impl Iterator<Item = (usize, [f64; 3])> + 'a {
    let m = box_edge(p.radius) as i64;
    let origin = p.position.map(|x| (x as f32 - p.radius as f32).floor() as i64);
    (0..m * m * m).filter_map(move |t| {
        let q = [
            origin[0] + t % m,
            origin[1] + (t / m) % m,
            origin[2] + t / (m * m),
        ];
        let n = setup.n.map(|v| v as i64);
        let inside = (0..3).all(|a| setup.periodic(a) || (q[a] >= 0 && q[a] < n[a]));
        let cell = std::array::from_fn(|a| q[a].rem_euclid(n[a]) as usize);
        inside.then(|| (setup.index(cell), q.map(|v| v as f64 + 0.5)))
    })
}

/// The collision of a covered cell (seed eq. 7; imb_solid_term.wgsl `immersed_boundary`): the fluid part of
/// `post` weighted by 1 - sum B, and each particle's B Omega added (`solid_collision`), with its
/// load.
#[allow(clippy::too_many_arguments)]
fn immersed_boundary(
    setup: &Setup,
    f: &Cell,
    post: &Cell,
    rho: f64,
    u: [f64; 3],
    covers: &[Cover],
    particles: &[SolidParticle],
    options: ImbOptions,
    loads: &mut [Load],
) -> Cell {
    let b = weights(setup, covers, options);
    let b_total: f64 = b.iter().sum();
    let mut out: Cell = std::array::from_fn(|i| f[i] - (1.0 - b_total) * (f[i] - post[i]));
    let source = forcing(setup, u);
    for (&(j, _, x), b) in covers.iter().zip(&b) {
        let p = &particles[j];
        let arm: [f64; 3] = std::array::from_fn(|a| x[a] - p.position[a]);
        let us = solid_velocity(p, arm);
        let mut momentum = [0.0; 3];
        for i in 0..19 {
            let omega = b * solid_collision(i, f, post, &source, rho, u, us, options.solid_collision);
            out[i] += omega;
            for a in 0..3 {
                momentum[a] += omega * C[i][a] as f64;
            }
        }
        add_load(&mut loads[j], arm, momentum);
    }
    out
}

/// Each covering particle's weight B (seed eq. 7's beta_n) from its solid fraction, the total
/// fraction capped at 1: the seed's B = eps, or Noble & Torczynski's B(eps, tau) (imb.wgsl
/// `weighting`).
fn weights(setup: &Setup, covers: &[Cover], options: ImbOptions) -> Vec<f64> {
    let eps_total: f64 = covers.iter().map(|c| c.1).sum();
    let scale = if eps_total > 1.0 { 1.0 / eps_total } else { 1.0 };
    let t = setup.tau - 0.5;
    let weight = |eps: f64| {
        if options.seed_weighting {
            eps
        } else {
            eps * t / ((1.0 - eps) + t)
        }
    };
    covers.iter().map(|c| weight(c.1 * scale)).collect()
}

/// The solid's velocity at `arm` from the particle's centre (seed eq. 9, at the cell centre rather
/// than half a link on): v_p + omega_p x arm.
fn solid_velocity(p: &SolidParticle, arm: [f64; 3]) -> [f64; 3] {
    let w = p.angular_velocity;
    let spin = [
        w[1] * arm[2] - w[2] * arm[1],
        w[2] * arm[0] - w[0] * arm[2],
        w[0] * arm[1] - w[1] * arm[0],
    ];
    std::array::from_fn(|a| p.velocity[a] + spin[a])
}

/// The solid term Omega_i of direction i at the solid's velocity `us`: Noble & Torczynski's
/// (seed eq. 8) f_ibar - f_i + f_eq_i(rho, u_s) - f_eq_ibar(rho, u), or superposition's
/// f_eq_i(rho, u_s) - f_eq_i(rho, u) + post_i - S_i - f_i (S: `source`).
#[allow(clippy::too_many_arguments)]
fn solid_collision(
    i: usize,
    f: &Cell,
    post: &Cell,
    source: &Cell,
    rho: f64,
    u: [f64; 3],
    us: [f64; 3],
    collision: SolidCollision,
) -> f64 {
    let o = opposite(i);
    match collision {
        SolidCollision::NobleTorczynski => {
            f[o] - f[i] + d3q19::equilibrium_shifted(i, rho, us) - d3q19::equilibrium_shifted(o, rho, u)
        }
        SolidCollision::Superposition => {
            d3q19::equilibrium_shifted(i, rho, us) - d3q19::equilibrium_shifted(i, rho, u) + post[i]
                - source[i]
                - f[i]
        }
    }
}

/// Adds to a particle's load the cell's terms of the force (seed eq. 10) and torque (eq. 11) at
/// `arm` from its centre: the momentum its solid term gave the fluid, `momentum` = B sum_i
/// Omega_i c_i, taken from the particle (force -momentum, torque arm x force).
fn add_load(load: &mut Load, arm: [f64; 3], momentum: [f64; 3]) {
    let force = momentum.map(|m| -m);
    let torque = [
        arm[1] * force[2] - arm[2] * force[1],
        arm[2] * force[0] - arm[0] * force[2],
        arm[0] * force[1] - arm[1] * force[0],
    ];
    for a in 0..3 {
        load.force[a] += force[a];
        load.torque[a] += torque[a];
    }
}
