//! The squeeze films of lubrication against Reynolds' law.

use super::*;
use crate::dem::lubrication::MIN_GAP_FRACTION;

/// The gaps at which the film tests compare times [m].
const FILM_MARKS: [f64; 3] = [0.2e-3, 0.1e-3, 0.05e-3];

/// Reference: a film of K = 6 pi mu R*^2 closing under a constant force F on a reduced mass m*,
/// m* h'' = -F - K (1/h - 1/h_c) h', from (h0, h0'), by RK4 at 1e-7 s; the times at `FILM_MARKS`.
/// (Without inertia it would be t = K/F (ln(h0/h) - (h0 - h)/h_c): the sphere's inertia shortens
/// these times by 1.1 / 0.45 / 0.27%.)
fn film_closing_reference(m: f64, k: f64, force: f64, h0: f64, v0: f64) -> Vec<f64> {
    let accel = |h: f64, v: f64| -(force + k * (1.0 / h - 1.0 / FILM_CUTOFF) * v) / m;
    let (dt, mut t, mut h, mut v) = (1e-7, 0.0, h0, v0);
    let mut times = Vec::new();
    for mark in FILM_MARKS {
        while h > mark {
            let (k1h, k1v) = (v, accel(h, v));
            let (k2h, k2v) = (v + 0.5 * dt * k1v, accel(h + 0.5 * dt * k1h, v + 0.5 * dt * k1v));
            let (k3h, k3v) = (v + 0.5 * dt * k2v, accel(h + 0.5 * dt * k2h, v + 0.5 * dt * k2v));
            let (k4h, k4v) = (v + dt * k3v, accel(h + dt * k3h, v + dt * k3v));
            h += dt / 6.0 * (k1h + 2.0 * k2h + 2.0 * k3h + k4h);
            v += dt / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
            t += dt;
        }
        times.push(t);
    }
    times
}

/// Steps `world` until `gap` falls below each of `FILM_MARKS`; relative errors of those times
/// against `reference`.
fn film_closing_errors(world: &mut World, reference: &[f64], gap: impl Fn(&World) -> f64) -> Vec<f64> {
    FILM_MARKS
        .iter()
        .zip(reference)
        .map(|(&h, &t)| {
            while gap(world) > h {
                world.step();
            }
            (world.time - t) / t
        })
        .collect()
}

/// A sphere sinking onto a floor through the squeeze film (the DEM's sub-step lubrication)
/// follows Reynolds' law: the times to close the gap from 0.4 mm to 0.2, 0.1 and 0.05 mm.
#[test]
fn a_sphere_sinks_onto_a_wall_through_the_squeeze_film_as_reynolds_law_says() {
    let g = 9.81;
    let k = 6.0 * std::f64::consts::PI * FILM_MU * R * R;
    let h0 = 0.4e-3;
    let mut body = Body::sphere(
        0,
        V3::new(0.0, 0.0, R + h0),
        V3::zeros(),
        V3::zeros(),
        R,
        FILM_RHO,
        0,
    );
    let weight = body.m * g;
    body.v.z = -weight / (k * (1.0 / h0 - 1.0 / FILM_CUTOFF));
    let reference = film_closing_reference(body.m, k, weight, h0, body.v.z);
    let floor = floor();
    let mut w = film_world(vec![body], vec![floor], V3::new(0.0, 0.0, -g), 1e-5);
    let errors = film_closing_errors(&mut w, &reference, |w| w.bodies[0].x.z - R);
    assert!(
        errors.iter().all(|e| e.abs() < 2e-3),
        "relative time errors {errors:?}"
    );
    assert_eq!(w.contact_count(), 0, "the film keeps the sphere off the floor");
}

/// Two spheres pushed together by equal and opposite forces close their film as a sphere of
/// R* = R/2 and m* = m/2 onto a wall would, and their momentum stays zero.
#[test]
fn two_spheres_pushed_together_close_their_film_as_reynolds_law_says() {
    let r_eff = 0.5 * R;
    let k = 6.0 * std::f64::consts::PI * FILM_MU * r_eff * r_eff;
    let h0 = 0.4e-3;
    let sphere =
        |id: u64, x: f64| Body::sphere(id, V3::new(x, 0.0, 0.0), V3::zeros(), V3::zeros(), R, FILM_RHO, 0);
    let (mut a, mut b) = (sphere(0, -R - 0.5 * h0), sphere(1, R + 0.5 * h0));
    let push = 2e-4;
    let closing = push / (k * (1.0 / h0 - 1.0 / FILM_CUTOFF));
    (a.f_ext, b.f_ext) = (V3::new(push, 0.0, 0.0), V3::new(-push, 0.0, 0.0));
    (a.v.x, b.v.x) = (0.5 * closing, -0.5 * closing);
    let reference = film_closing_reference(0.5 * a.m, k, push, h0, -closing);
    let mut w = film_world(vec![a, b], vec![], V3::zeros(), 1e-5);
    let errors = film_closing_errors(&mut w, &reference, |w| {
        w.bodies[1].x.x - w.bodies[0].x.x - 2.0 * R
    });
    assert!(
        errors.iter().all(|e| e.abs() < 2e-3),
        "relative time errors {errors:?}"
    );
    let momentum = w.bodies[0].m * w.bodies[0].v + w.bodies[1].m * w.bodies[1].v;
    assert!(
        momentum.norm() < 1e-12 * w.bodies[0].m * closing,
        "momentum {momentum:?}"
    );
}

/// A sphere moving across a slot between two walls, both films at their stiffest: at the film step
/// limit the speed decays every step and never changes sign.
#[test]
fn two_stiff_films_on_one_sphere_damp_it_without_overshoot() {
    let lub = SqueezeFilm {
        viscosity: FILM_MU,
        cutoff: FILM_CUTOFF,
    };
    let h = 0.5 * MIN_GAP_FRACTION * R;
    let body = Body::sphere(
        0,
        V3::new(0.0, 0.0, R + h),
        V3::new(0.0, 0.0, 1e-3),
        V3::zeros(),
        R,
        FILM_RHO,
        0,
    );
    let wall = |z: f64, n: f64| Wall {
        shape: Shape::Plane {
            point: V3::new(0.0, 0.0, z),
            normal: V3::new(0.0, 0.0, n),
        },
        material: 0,
    };
    let dt = lub.step_limit(R, body.m);
    let walls = vec![wall(0.0, 1.0), wall(2.0 * (R + h), -1.0)];
    let mut w = film_world(vec![body], walls, V3::zeros(), dt);
    let mut v = w.bodies[0].v.z;
    for step in 0..20 {
        w.step();
        let now = w.bodies[0].v.z;
        // Each step removes 2 lambda = 1/3 of the speed (explicit damping).
        assert!(now > 0.0 && now < 0.7 * v, "step {step}: {v} -> {now}");
        v = now;
    }
}
