//! Free flight: the exact step of a sphere that touches nothing, stopping short of every contact
//! and film.

use super::*;

/// A sphere with drag, a held force and torque and their rates (the coupled run's sub-step drag,
/// the reference's acceleration off the free one as after a step with contacts): one exact step
/// of free flight lands where 10^5 velocity-Verlet steps do (within 5x their own first-order lag:
/// 7.9e-8 m/s, 3.7e-11 m, 6.3e-6 rad/s); without drag, on the parabola.
#[test]
fn free_flight_moves_a_sphere_as_fine_steps_do() {
    let g = V3::new(0.0, 0.0, -9.81);
    let l = law(
        NormalLaw::Hertz,
        TangentialLaw::None,
        Switches::LIGGGHTS,
        Linear::default(),
    );
    let span = 1e-3;
    let start = |drag: bool| {
        let mut b = Body::sphere(
            0,
            V3::new(0.01, 0.02, 0.03),
            V3::new(0.01, -0.02, 0.005),
            V3::new(3.0, 0.0, -1.0),
            R,
            RHO,
            0,
        );
        let held = V3::new(2e-4, 0.0, 1e-3);
        let spin = V3::new(0.0, 1e-7, 0.0);
        if drag {
            b.drag = b.m / 4e-4;
            b.spin_drag = 0.4 * b.drag * R * R;
            b.f_ext_rate = b.drag * ((held + V3::new(0.0, 5e-4, -2e-3)) / b.m + g);
            b.t_ext_rate = b.spin_drag * (spin + V3::new(-2e-7, 0.0, 0.0)) / b.inertia;
        }
        b.f_ext = held + b.drag * b.v;
        b.t_ext = spin + b.spin_drag * b.w;
        World::new(vec![b], vec![], l, &[material(0.9, 0.5)], g, span / 1e5, 0.5 * R)
    };
    for drag in [true, false] {
        let (mut exact, mut stepped) = (start(drag), start(drag));
        assert_eq!(exact.advance_span(span, 1), 1, "nothing to touch");
        stepped.advance(100_000);
        let (a, b) = (exact.bodies[0], stepped.bodies[0]);
        let what = format!("drag {drag}");
        assert_near(a.v, b.v, 4e-7, &what);
        assert_near(a.x, b.x, 2e-10, &what);
        assert_near(a.w, b.w, 3e-5, &what);
        assert_near(a.f_ext, b.f_ext, 1e-9 * b.f_ext.norm(), &what);
        assert!((exact.time - stepped.time).abs() < 1e-9 * span);
        if !drag {
            let s = start(false).bodies[0];
            let parabola = s.x + s.v * span + 0.5 * (s.f_ext / s.m + g) * span * span;
            assert!((a.x - parabola).norm() < 1e-15, "{} against {parabola}", a.x);
        }
    }
}

/// Fluid steps of `span`: in one step of free flight when `free` and nothing can touch, else in
/// `k` DEM steps. After each free flight the smallest gap (pair, at its nearest image along x when
/// `period` > 0, and to the walls) is still above the films' cut-off. Returns the steps flown and
/// the smallest gap seen (negative: an overlap).
fn fluid_steps(w: &mut World, span: f64, k: u64, steps: u64, free: bool, period: f64) -> (u64, f64) {
    let gap = |w: &World| {
        let mut d = w.bodies[0].x - w.bodies.last().unwrap().x;
        if period > 0.0 {
            d.x -= period * (d.x / period).round();
        }
        let pair = if w.bodies.len() > 1 {
            d.norm() - 2.0 * R
        } else {
            f64::INFINITY
        };
        w.bodies.iter().map(|b| b.x.z - R).fold(pair, f64::min)
    };
    let (mut flown, mut closest) = (0, f64::INFINITY);
    for _ in 0..steps {
        if !free {
            w.advance(k);
        } else if w.advance_span(span, k) == w.bodies.len() {
            flown += 1;
            assert!(gap(w) > FILM_CUTOFF, "flew into the films' reach: gap {}", gap(w));
        }
        closest = closest.min(gap(w));
    }
    (flown, closest)
}

/// A sphere falling at 0.3 m/s, 4 mm above the floor, in squeeze films; DEM steps of `dt`.
fn falling_onto_the_floor(dt: f64) -> World {
    let b = Body::sphere(
        0,
        V3::new(0.01, 0.01, 0.006),
        V3::new(0.0, 0.0, -0.3),
        V3::zeros(),
        R,
        RHO,
        0,
    );
    film_world(vec![b], vec![floor()], V3::new(0.0, 0.0, -9.81), dt)
}

/// Two spheres 4 mm apart meeting head-on at 0.8 m/s in squeeze films, across the face x = 0 of
/// a `period` long along x (inside when 0); DEM steps of `dt`.
fn meeting_head_on(period: f64, dt: f64) -> World {
    let at = if period > 0.0 { 0.0 } else { 0.015 };
    let a = Body::sphere(
        0,
        V3::new(at - 2.0 * R - 2e-3, 0.01, 0.01),
        V3::new(0.4, 0.0, 0.0),
        V3::zeros(),
        R,
        RHO,
        0,
    );
    let b = Body::sphere(
        1,
        V3::new(at + 2.0 * R + 2e-3, 0.01, 0.01),
        V3::new(-0.4, 0.0, 0.0),
        V3::zeros(),
        R,
        RHO,
        0,
    );
    let box_ = crate::dem::neighbor::Periodic {
        lo: V3::zeros(),
        len: [period, 0.0, 0.0],
    };
    let wrapped = vec![a, b]
        .into_iter()
        .map(|b| Body {
            x: box_.wrap(b.x),
            ..b
        })
        .collect();
    let mut w = film_world(wrapped, vec![], V3::zeros(), dt);
    if period > 0.0 {
        w.set_periodic(Some(box_), 0.0).unwrap();
    }
    w
}

/// A sphere falling onto the floor, stopped by its squeeze film, and two spheres meeting head-on
/// through theirs (inside, and across a periodic face): with free flight the fluid steps far from
/// anything are flown in one step each, and the films and contacts start in DEM steps as without
/// it: the same closest approach (an overlap for the pairs) and the same speeds after it.
#[test]
fn free_flight_stops_before_every_contact_and_film() {
    let (span, k) = (2e-4, 200);
    let dt = span / k as f64;
    let drop = || falling_onto_the_floor(dt);
    let pair = |period: f64| meeting_head_on(period, dt);
    type Case<'a> = (&'static str, Box<dyn Fn() -> World + 'a>, f64);
    let cases: [Case<'_>; 3] = [
        ("floor", Box::new(drop), 0.0),
        ("pair", Box::new(move || pair(0.0)), 0.0),
        ("pair across x = 0", Box::new(move || pair(0.03)), 0.03),
    ];
    for (name, world, period) in cases {
        let (mut free, mut fixed) = (world(), world());
        let (flown, overlap) = fluid_steps(&mut free, span, k, 150, true, period);
        let (none, overlap_fixed) = fluid_steps(&mut fixed, span, k, 150, false, period);
        assert_eq!(none, 0);
        assert!(flown >= 10, "{name}: {flown} steps flown");
        assert!(
            overlap_fixed > 1e-7,
            "{name}: the contact happens ({overlap_fixed} m)"
        );
        assert!(
            (overlap - overlap_fixed).abs() < 1e-3 * overlap_fixed,
            "{name}: largest overlap {overlap} m, without free flight {overlap_fixed} m"
        );
        for (a, b) in free.bodies.iter().zip(&fixed.bodies) {
            assert!(
                (a.v - b.v).norm() < 1e-3 * 0.3,
                "{name}: after the impact v {} against {}",
                a.v,
                b.v
            );
        }
    }
}
