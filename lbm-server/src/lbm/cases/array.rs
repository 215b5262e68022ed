//! The drag of a simple cubic array of spheres in Stokes flow against Zick & Homsy (1982) and
//! Sangani & Acrivos (1982): held, drawn larger (the radius deficit), moving through the lattice.

use super::{coupled_lattice, plane_flux, relaxation_steps};
use crate::lbm::geometry::{Face, Operator, Setup};
use crate::lbm::gpu::Gpu;
use crate::lbm::imb::{ImbOptions, SolidParticle};
use crate::lbm::storage::Storage;
use std::sync::Arc;

/// Drag on a fixed sphere in a periodic cube (a simple cubic array), against Zick & Homsy (1982).
#[derive(Debug, Clone, Copy)]
pub struct ArrayDrag {
    pub radius: f64,
    /// K = F / (6 pi mu a U) with F the total force on the sphere (see [`zick_homsy`]).
    pub k: f64,
    /// The same from the driving alone: F = f n^3 (the force balance of the unit cell).
    pub k_balance: f64,
    pub steps: u64,
    /// U: the mean velocity of the fluid relative to the sphere.
    pub speed: f64,
}

/// Stokes flow through a simple cubic array: one sphere of radius r (lattice units) fixed in a
/// periodic n^3 box, flow driven by a body force f on the fluid; K = F / (6 pi mu a U).
///
/// Zick & Homsy's F is the total force on a sphere of an array driven by a mean pressure gradient
/// G, which balances the unit cell: F = G n^3. A body force f = G on the fluid gives the same
/// flow, but the sphere then misses the mean gradient's share G V_s: the momentum exchange
/// measures F - G V_s (= f (1 - phi) n^3 in steady state). So F = exchange + f V_s.
pub fn zick_homsy(gpu: &Arc<Gpu>, n: usize, radius: f64, tau: f64, operator: Operator) -> ArrayDrag {
    zick_homsy_with(gpu, n, radius, tau, operator, ImbOptions::default())
}

/// [`zick_homsy`] with given coupling options.
pub fn zick_homsy_with(
    gpu: &Arc<Gpu>,
    n: usize,
    radius: f64,
    tau: f64,
    operator: Operator,
    options: ImbOptions,
) -> ArrayDrag {
    array_drag(gpu, n, [radius, radius], tau, operator, options)
}

/// How much larger (`delta`, cells) the immersed boundary must draw a sphere for the array to
/// have Zick & Homsy's drag: the boundary's hydrodynamic radius falls short of the nominal one by
/// an amount that grows with tau (validation/lbm/REPORT.md, "drag against tau").
#[derive(Debug, Clone, Copy)]
pub struct RadiusDeficit {
    pub delta: f64,
    /// K drawn at the nominal radius, and at the nominal radius + delta (both normalised with
    /// the nominal radius).
    pub k_nominal: f64,
    pub k_drawn: f64,
    pub steps: u64,
}

/// [`RadiusDeficit`] of a sphere of nominal `radius` in an n^3 array at this tau: the drag at
/// delta = 0 and 0.25 cells, delta from the secant through them, and the drag drawn with it.
pub fn radius_deficit(
    gpu: &Arc<Gpu>,
    n: usize,
    radius: f64,
    k_ref: f64,
    tau: f64,
    operator: Operator,
) -> RadiusDeficit {
    let options = ImbOptions::default();
    let k_at = |delta: f64| array_drag(gpu, n, [radius + delta, radius], tau, operator, options);
    let (nominal, probe) = (k_at(0.0), k_at(0.25));
    let delta = 0.25 * (k_ref - nominal.k) / (probe.k - nominal.k);
    let drawn = k_at(delta);
    RadiusDeficit {
        delta,
        k_nominal: nominal.k,
        k_drawn: drawn.k,
        steps: nominal.steps,
    }
}

/// The array of [`zick_homsy_with`] with the sphere drawn at `[drawn, nominal]` radius: the
/// lattice covers the drawn one, K and the pressure-gradient share are the nominal one's.
fn array_drag(
    gpu: &Arc<Gpu>,
    n: usize,
    radii: [f64; 2],
    tau: f64,
    operator: Operator,
    options: ImbOptions,
) -> ArrayDrag {
    moving_array_drag(gpu, n, radii, tau, operator, options, 0.0)
}

/// [`array_drag`] with the sphere moving at `velocity` (cells per step, along x) through the
/// periodic lattice, its cells covered and uncovered as it goes; the same body force drives the
/// fluid. Stokes flow depends only on the velocity relative to the sphere, so a boundary that
/// acts the same moving and at rest gives the same K. The loads and the relative velocity are
/// averaged over the last 4 cells of travel (the drag of a moving sphere wavers with its place
/// against the lattice); the relative velocity is the flux through the plane farthest from the
/// sphere less its velocity.
pub fn moving_array_drag(
    gpu: &Arc<Gpu>,
    n: usize,
    radii: [f64; 2],
    tau: f64,
    operator: Operator,
    options: ImbOptions,
    velocity: f64,
) -> ArrayDrag {
    let setup = array_setup(n, tau, operator, STOKES_FORCE, Storage::Fp32);
    drag_in(gpu, &setup, radii, options, velocity)
}

/// A force small enough for Stokes flow (Re << 1) in the arrays' boxes.
pub const STOKES_FORCE: f64 = 1e-6;

/// [`zick_homsy`] driven by the body force `force` (the flow's speed scales with it), with the
/// populations in `storage`.
pub fn zick_homsy_stored(
    gpu: &Arc<Gpu>,
    n: usize,
    radius: f64,
    tau: f64,
    operator: Operator,
    force: f64,
    storage: Storage,
) -> ArrayDrag {
    let setup = array_setup(n, tau, operator, force, storage);
    drag_in(gpu, &setup, [radius, radius], ImbOptions::default(), 0.0)
}

/// The periodic n^3 box of the arrays, driven along x by `force`.
fn array_setup(n: usize, tau: f64, operator: Operator, force: f64, storage: Storage) -> Setup {
    let mut setup = Setup::new([n, n, n], [Face::Periodic; 6], tau, operator);
    setup.force = [force, 0.0, 0.0];
    setup.storage = storage;
    setup
}

/// The array of [`moving_array_drag`] on the lattice `setup` (its box, force and storage).
fn drag_in(
    gpu: &Arc<Gpu>,
    setup: &Setup,
    [drawn, radius]: [f64; 2],
    options: ImbOptions,
    velocity: f64,
) -> ArrayDrag {
    let n = setup.n[0];
    let nu = setup.viscosity();
    let f = setup.force[0];
    let centre = n as f64 / 2.0;
    let sphere_at = |step: u64| SolidParticle {
        position: [
            (centre + velocity * step as f64).rem_euclid(n as f64),
            centre,
            centre,
        ],
        radius: drawn,
        velocity: [velocity, 0.0, 0.0],
        ..Default::default()
    };
    let mut lattice = coupled_lattice(gpu, setup, options);
    let steps = relaxation_steps(n as f64, nu, 12.0);
    // The last 4 cells of travel, the flux sampled 16 times over them (at rest: the last step).
    let (window, samples) = if velocity == 0.0 {
        (1, 1)
    } else {
        ((4.0 / velocity.abs()).round() as u64, 16)
    };
    let stride = (window / samples).max(1);
    let (mut exchange, mut relative) = (0.0, 0.0);
    for step in 0..steps {
        let sphere = sphere_at(step);
        let load = lattice.step_coupled(&[sphere]).expect("coupled step")[0].force[0];
        let left = steps - step - 1;
        if left < window {
            exchange += load / window as f64;
            if left.is_multiple_of(stride) && left / stride < samples {
                let x_far = (sphere.position[0] + centre).floor() as usize % n;
                relative += (plane_flux(&lattice.fields().0, n, x_far) - velocity) / samples as f64;
            }
        }
    }
    let (_, bad) = lattice.fields();
    assert!(bad.is_none(), "unhealthy: {bad:?}");
    let stokes = 6.0 * std::f64::consts::PI * nu * radius * relative;
    let sphere_volume = 4.0 / 3.0 * std::f64::consts::PI * radius.powi(3);
    ArrayDrag {
        radius,
        k: (exchange + f * sphere_volume) / stokes,
        k_balance: f * (n * n * n) as f64 / stokes,
        steps,
        speed: relative,
    }
}

/// Zick & Homsy (1982), Table 2: (solid fraction, K), from ../shared/reference/zick-homsy-1982.csv.
pub const ZICK_HOMSY: [(f64, f64); 3] = [(0.027, 2.008), (0.125, 4.292), (0.343, 15.4)];

/// Sangani & Acrivos (1982): K of a dilute simple cubic array of spheres at solid fraction c,
/// their expansion in c^(1/3) (within 0.1% of Zick & Homsy's 2.008 and 4.292 at 0.027 and 0.125).
pub fn sangani_acrivos(c: f64) -> f64 {
    let s = c.cbrt();
    1.0 / (1.0 - 1.7601 * s + c - 1.5593 * c * c + 3.9799 * s.powi(8) - 3.0734 * s.powi(10))
}

/// Radius giving solid fraction phi in an n^3 box.
pub fn radius_for(phi: f64, n: usize) -> f64 {
    (phi * (n * n * n) as f64 * 3.0 / (4.0 * std::f64::consts::PI)).cbrt()
}
