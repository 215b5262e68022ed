//! A held sphere near tau = 1/2: whether an operator holds the flow, and where it first fails.

use super::coupled_lattice;
use super::sphere::{drag_coefficient, stream_box, stream_of, HeldSphere};
use crate::lbm::geometry::{Face, Setup};
use crate::lbm::gpu::{equilibrium_field, Gpu, Unhealthy};
use std::sync::Arc;

/// How a held sphere's run near tau = 1/2 ended ([`sphere_stability`]).
#[derive(Debug, Clone, Copy)]
pub struct Stability {
    pub tau: f64,
    /// Steps run: the whole horizon, or up to the health check that failed.
    pub steps: u64,
    /// The first cell that failed the health check (|rho - 1| > 0.5, |u| > 0.4 or not finite),
    /// if one did by `steps`.
    pub unhealthy: Option<Unhealthy>,
    /// C_d over the last pass of the stream through the box: mean, lowest, highest (the wake
    /// may shed); None if it blew up.
    pub cd: Option<[f64; 3]>,
    /// The mean of u_x over the box at the last check, against u0 (the periodic box's stream
    /// slows as the sphere takes its momentum).
    pub stream: f64,
}

/// The faces around a held sphere ([`sphere_stability`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Faces {
    /// [`held_sphere`](super::held_sphere)'s: velocity inlet, pressure outlet, side faces moving
    /// with the stream.
    Open,
    /// Periodic on all six faces: no boundary but the sphere; the stream, not driven, slows.
    Periodic,
}

/// Steps between the health checks of [`sphere_stability`] (each reads every cell back).
pub const STABILITY_CHECK: u64 = 10;

/// The held sphere of `case` ([`held_sphere`](super::held_sphere)'s stream, sphere and box, with
/// these `faces`) run for `passes` passes of the stream through the box whether or not its drag
/// settles (above Re ~ 210 a sphere's wake is unsteady), with the lattice's health checked every
/// `check` steps ([`STABILITY_CHECK`] where that is the question): whether this operator at this
/// tau holds the flow, where it first fails if not, and the drag over the last pass where it holds.
pub fn sphere_stability(
    gpu: &Arc<Gpu>,
    case: &HeldSphere,
    faces: Faces,
    passes: f64,
    check: u64,
) -> Stability {
    let (u0, tau) = stream_of(case);
    let (d, width, length) = (case.diameter, case.width, case.length);
    let size = [length, width, width];
    let stream = [u0, 0.0, 0.0];
    let mut lattice = match faces {
        Faces::Open => stream_box(gpu, size, tau, case.operator, case.imb, stream),
        Faces::Periodic => {
            let setup = Setup::new(size, [Face::Periodic; 6], tau, case.operator);
            let mut lattice = coupled_lattice(gpu, &setup, case.imb);
            lattice.set_populations(&equilibrium_field(&setup, |_| (1.0, stream)));
            lattice
        }
    };
    let sphere = case.particle();
    let pass = (length as f64 / u0).ceil() as u64;
    let horizon = ((passes * pass as f64) as u64).div_ceil(check) * check;
    let last_pass = horizon.saturating_sub(pass);
    let (mut sum, mut low, mut high, mut n) = (0.0, f64::INFINITY, f64::NEG_INFINITY, 0u64);
    let (mut steps, mut stream) = (0, 1.0);
    while steps < horizon {
        for _ in 0..check {
            let force = lattice
                .step_coupled(&[sphere])
                .map_or(f64::NAN, |l| l[0].force[0]);
            steps += 1;
            if steps > last_pass {
                let cd = drag_coefficient(force, u0, d);
                (sum, low, high, n) = (sum + cd, low.min(cd), high.max(cd), n + 1);
            }
        }
        let (fields, unhealthy) = lattice.fields();
        if unhealthy.is_some() {
            return Stability {
                tau,
                steps,
                unhealthy,
                cd: None,
                stream,
            };
        }
        stream = fields.iter().map(|c| c[1] as f64).sum::<f64>() / fields.len() as f64 / u0;
    }
    let cd = sum.is_finite().then_some([sum / n as f64, low, high]);
    Stability {
        tau,
        steps,
        unhealthy: None,
        cd,
        stream,
    }
}
