//! Periodic axes: pairs that meet across a face, a period refused.

use super::*;
use crate::dem::neighbor::Periodic;

/// Two spheres meeting obliquely, centred at `centre` (wrapped into `box_` when `wrapped`), in a
/// world of `contact` periodic along `box_` when `periodic`: both after 30,000 steps of 1 us, and
/// how many contacts the steps saw.
fn oblique_pair(
    contact: ContactLaw,
    box_: Periodic,
    centre: f64,
    wrapped: bool,
    periodic: bool,
) -> (Body, Body, usize) {
    let a = Body::sphere(
        0,
        V3::new(centre - 2.5 * R, 0.010, 0.010),
        V3::new(0.4, 0.05, 0.0),
        V3::zeros(),
        R,
        RHO,
        0,
    );
    let b = Body::sphere(
        1,
        V3::new(centre + 2.5 * R, 0.0112, 0.010),
        V3::new(-0.4, 0.0, 0.02),
        V3::zeros(),
        R,
        RHO,
        0,
    );
    let wrap = |x: V3| box_.wrap(x);
    let (a, b) = if wrapped {
        (Body { x: wrap(a.x), ..a }, Body { x: wrap(b.x), ..b })
    } else {
        (a, b)
    };
    let mut w = World::new(
        vec![a, b],
        vec![],
        contact,
        &[material(0.7, 0.5)],
        V3::zeros(),
        1e-6,
        0.5 * R,
    );
    if periodic {
        w.set_periodic(Some(box_), 0.0).unwrap();
    }
    let mut touched = 0;
    for _ in 0..30_000 {
        w.step();
        touched += w.contact_count();
    }
    (w.bodies[0], w.bodies[1], touched)
}

/// Two spheres meeting obliquely across the periodic face x = 0 of a 30 mm box collide as they
/// do inside it: after the contact the same velocities and spins (to round-off) and positions one
/// period apart where they crossed, all inside the box; for the general pair loop (YADE's Hertz)
/// and the batched one (LIGGGHTS's). Without the period the pair never meets.
#[test]
fn spheres_collide_across_a_periodic_face_as_inside() {
    let l = 0.03;
    let box_ = Periodic {
        lo: V3::zeros(),
        len: [l, 0.0, 0.0],
    };
    let yade = law(
        NormalLaw::Hertz,
        TangentialLaw::History,
        Switches::YADE,
        Linear::default(),
    );
    for contact in [yade, ContactLaw::LIGGGHTS_HERTZ] {
        let run = |centre: f64, wrapped: bool, periodic: bool| {
            oblique_pair(contact, box_, centre, wrapped, periodic)
        };
        let (a_in, b_in, touched) = run(0.015, false, false);
        assert!(touched > 0, "{contact:?}: the spheres collide inside");
        let (a_x, b_x, touched_x) = run(0.0, true, true);
        assert!(touched_x > 0, "{contact:?}: they collide across the face");
        for (inside, across) in [(a_in, a_x), (b_in, b_x)] {
            let what = format!("{contact:?}");
            assert_near(inside.v, across.v, 1e-9, &what);
            assert_near(inside.w, across.w, 1e-6, &what);
            let shifted = box_.wrap(inside.x - V3::new(0.015, 0.0, 0.0));
            assert_near(shifted, across.x, 1e-9, &what);
            assert!(
                across.x.x >= 0.0 && across.x.x < l,
                "inside the box: {}",
                across.x
            );
        }
        let (_, _, apart) = run(0.0, true, false);
        assert_eq!(apart, 0, "{contact:?}: without the period they never meet");
    }
}

#[test]
fn a_periodic_axis_shorter_than_twice_the_pair_reach_is_refused() {
    let a = Body::sphere(0, V3::new(0.005, 0.0, 0.0), V3::zeros(), V3::zeros(), R, RHO, 0);
    let mut w = World::new(
        vec![a],
        vec![],
        ContactLaw::LIGGGHTS_HERTZ,
        &[material(0.7, 0.5)],
        V3::zeros(),
        1e-6,
        0.5 * R,
    );
    let short = Periodic {
        lo: V3::zeros(),
        len: [0.0, 0.009, 0.0],
    };
    let err = w.set_periodic(Some(short), 0.0).unwrap_err();
    assert!(err.contains("periodic y axis is 0.009 m"), "{err}");
}
