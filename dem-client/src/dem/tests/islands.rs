//! Islands of free flight: the spheres that can touch something take the DEM steps while the
//! others fly, with the same results as without free flight.

use super::*;
use crate::dem::neighbor::Periodic;
use crate::dem::world::everyone::{self, Way};

/// The world of `an_island_takes_the_dem_steps_while_the_other_spheres_fly`, periodic along x
/// by `box_` where its length is not 0: a sphere falling onto the floor, two meeting head-on above
/// it (across the face x = 0 when periodic), six falling far from anything; DEM steps of `dt`.
fn three_groups(box_: Periodic, dt: f64) -> World {
    let period = box_.len[0];
    let at = if period > 0.0 { 0.0 } else { 0.04 };
    let mut bodies = vec![
        ball(0, [0.01, 0.01, 0.006], [0.0, 0.0, -0.3]),
        ball(1, [at - 2.0 * R - 3e-3, 0.01, 0.03], [0.4, 0.0, 0.0]),
        ball(2, [at + 2.0 * R + 3e-3, 0.01, 0.03], [-0.4, 0.0, 0.0]),
    ];
    bodies.extend((0..6).map(|m| ball(3 + m, [0.075 + 0.01 * m as f64, 0.03, 0.04], [0.0, 0.0, 0.1])));
    let bodies = bodies
        .into_iter()
        .map(|b| Body {
            x: box_.wrap(b.x),
            ..b
        })
        .collect();
    let mut w = film_world(bodies, vec![floor()], V3::new(0.0, 0.0, -9.81), dt);
    if period > 0.0 {
        w.set_periodic(Some(box_), 0.0).unwrap();
    }
    w
}

/// The nearest image of the separation `d` along x, the axis periodic with `period` (none when
/// 0).
fn nearest_image(d: V3, period: f64) -> V3 {
    let shift = if period > 0.0 {
        period * (d.x / period).round()
    } else {
        0.0
    };
    V3::new(d.x - shift, d.y, d.z)
}

/// Three groups in one world: a sphere falling onto the floor through its squeeze film, two
/// spheres meeting head-on through theirs above it (inside, and across a periodic face), six
/// spheres falling far from anything. With free flight the group that can touch something takes
/// the DEM steps while the others fly (the fluid steps with an island), and every sphere ends as
/// without free flight: the same closest approach to the floor and between the pair, the same
/// speeds after the impacts.
#[test]
fn an_island_takes_the_dem_steps_while_the_other_spheres_fly() {
    let (span, k) = (2e-4, 200);
    for period in [0.0, 0.06] {
        let box_ = Periodic {
            lo: V3::zeros(),
            len: [period, 0.0, 0.0],
        };
        let image = |d: V3| nearest_image(d, period);
        let world = || three_groups(box_, span / k as f64);
        let gaps = |w: &World| {
            let pair = image(w.bodies[1].x - w.bodies[2].x).norm() - 2.0 * R;
            (w.bodies[0].x.z - R, pair)
        };
        let (mut free, mut fixed) = (world(), world());
        let (mut all, mut some) = (0, 0);
        let (mut closest, mut closest_fixed) =
            ((f64::INFINITY, f64::INFINITY), (f64::INFINITY, f64::INFINITY));
        for _ in 0..150 {
            let flown = free.advance_span(span, k);
            all += usize::from(flown == free.bodies.len());
            some += usize::from(flown > 0 && flown < free.bodies.len());
            fixed.advance(k);
            let (a, b) = (gaps(&free), gaps(&fixed));
            closest = (closest.0.min(a.0), closest.1.min(a.1));
            closest_fixed = (closest_fixed.0.min(b.0), closest_fixed.1.min(b.1));
        }
        let case = format!("period {period}");
        assert!(
            all >= 10 && some >= 50,
            "{case}: {all} steps flown, {some} with an island"
        );
        // The films stop both approaches short of contact.
        assert!(
            [closest_fixed.0, closest_fixed.1]
                .iter()
                .all(|g| *g > 0.0 && *g < FILM_CUTOFF),
            "{case}: {closest_fixed:?}"
        );
        for (what, a, b) in [
            ("floor", closest.0, closest_fixed.0),
            ("pair", closest.1, closest_fixed.1),
        ] {
            assert!(
                (a - b).abs() < 1e-3 * b.abs(),
                "{case}, {what}: closest gap {a} m, without free flight {b} m"
            );
        }
        for (a, b) in free.bodies.iter().zip(&fixed.bodies) {
            assert!(
                (a.v - b.v).norm() < 1e-3 * 0.3 && image(a.x - b.x).norm() < 1e-6,
                "{case}, sphere {}: v {} x {} against {} {}",
                a.id,
                a.v,
                a.x,
                b.v,
                b.x
            );
        }
    }
}

/// A sphere C hits a sphere A at rest, B rests beyond A. Far from B (0.76 mm, more than an
/// island sphere's reach skin / 4 = 0.75 mm), B flies while C and A take the DEM steps: when C is
/// slow enough that A moves less than that reach, the island's result stands (C and A exactly as
/// without free flight); when A is thrown further, into B, the fluid step is taken again with
/// every sphere sub-stepped (B is hit exactly as without free flight). Nearer (0.55 mm), B is in
/// the island and is hit there. The four spheres far away fly when an island stands.
#[test]
fn an_island_sphere_thrown_beyond_its_reach_makes_every_sphere_take_the_dem_steps() {
    let (span, k) = (2.4e-3, 2400);
    let world = |v: f64, gap: f64| {
        let mut bodies = vec![
            ball(0, [0.01, 0.01, 0.01], [v, 0.0, 0.0]),
            ball(1, [0.01 + 2.0 * R, 0.01, 0.01], [0.0; 3]),
            ball(2, [0.01 + 4.0 * R + gap, 0.01, 0.01], [0.0; 3]),
        ];
        bodies.extend((0..4).map(|m| ball(3 + m, [0.03 + 0.01 * m as f64, 0.03, 0.03], [0.0, 0.1, 0.0])));
        let l = law(
            NormalLaw::Hertz,
            TangentialLaw::None,
            Switches::LIGGGHTS,
            Linear::default(),
        );
        World::new(
            bodies,
            vec![],
            l,
            &[material(0.9, 0.0)],
            V3::zeros(),
            span / k as f64,
            1.5 * R,
        )
    };
    // (C's speed, gap from A to B, B hit, spheres flown, spheres as without free flight)
    let cases = [
        (0.2, 0.76e-3, false, 5, 0..2),
        (0.3, 0.55e-3, true, 4, 0..3),
        (0.4, 0.76e-3, true, 0, 0..7),
    ];
    for (v, gap, hit, flies, same) in cases {
        let (mut free, mut fixed) = (world(v, gap), world(v, gap));
        let flown = free.advance_span(span, k);
        fixed.advance(k);
        let moved = (fixed.bodies[1].x - world(v, gap).bodies[1].x).norm();
        let what = format!("v {v}, gap {gap}: A moved {moved} m");
        assert_eq!(fixed.bodies[2].v.norm() > 0.0, hit, "{what}");
        assert_eq!(flown, flies, "{what}");
        for m in same {
            assert_eq!(free.bodies[m], fixed.bodies[m], "{what}, sphere {m}");
        }
    }
}

/// Every sphere in one island (no sphere flies): two spheres closing a gap of 0.85 mm at 0.1 m/s
/// each, so that they come within the films' cut-off (0.5 mm) while each moves 0.2 mm, less than
/// its reach (skin / 4 = 0.25 mm); and two pairs at rest in their films, listed 1.2 mm from each
/// other, beyond the cut-off plus two reaches (1 mm): those two pairs across are left out of the
/// island's world. Each fluid step the island stands and every sphere ends exactly as when every
/// sphere takes the DEM steps with the whole lists (fails when the closing pair is left out too).
#[test]
fn an_island_of_every_sphere_leaves_out_only_the_pairs_that_cannot_meet() {
    let (span, k) = (2e-3, 400);
    let world = || {
        let bodies = vec![
            ball(0, [0.01, 0.01, 0.01], [0.1, 0.0, 0.0]),
            ball(1, [0.01 + 2.0 * R + 0.85e-3, 0.01, 0.01], [-0.1, 0.0, 0.0]),
            ball(2, [0.01, 0.02, 0.01], [0.0; 3]),
            ball(3, [0.01 + 2.0 * R + 0.3e-3, 0.02, 0.01], [0.0; 3]),
            ball(4, [0.01, 0.02 + 2.0 * R + 1.2e-3, 0.01], [0.0; 3]),
            ball(
                5,
                [0.01 + 2.0 * R + 0.3e-3, 0.02 + 2.0 * R + 1.2e-3, 0.01],
                [0.0; 3],
            ),
        ];
        film_world(bodies, vec![], V3::zeros(), span / k as f64)
    };
    let (mut free, mut fixed) = (world(), world());
    free.everyone.fixed = Some(Way::Island);
    let gap = |w: &World| (w.bodies[0].x - w.bodies[1].x).norm() - 2.0 * R;
    for step in 0..3 {
        assert_eq!(free.advance_span(span, k), 0, "step {step}");
        fixed.advance(k);
        assert_eq!((free.islands, free.dropped_islands), (step + 1, 0), "step {step}");
        for (a, b) in free.bodies.iter().zip(&fixed.bodies) {
            assert_eq!(a, b, "step {step}, sphere {}", a.id);
        }
        if step == 0 {
            assert!(
                gap(&fixed) < FILM_CUTOFF,
                "the pair closes into its film: {}",
                gap(&fixed)
            );
        }
    }
}

/// Spheres in lasting contact take the DEM steps as an island over many fluid steps while the
/// others fly: one sliding on the floor, two on the floor pressed together and sliding past each
/// other (friction with history: the tangential springs of the floor and of the pair carry
/// over from one fluid step to the next). They end exactly as without free flight.
#[test]
fn contact_histories_carry_over_between_the_fluid_steps_of_an_island() {
    let floor = floor();
    let (span, k) = (2e-4, 200);
    let world = || {
        let mut bodies = vec![
            ball(0, [0.01, 0.01, R], [0.05, 0.0, 0.0]),
            ball(1, [0.03, 0.01, R], [0.0, 0.02, 0.0]),
            ball(2, [0.03 + 2.0 * R - 1e-6, 0.01, R], [0.0, -0.02, 0.0]),
        ];
        bodies[1].f_ext = V3::new(1e-3, 0.0, 0.0);
        bodies[2].f_ext = V3::new(-1e-3, 0.0, 0.0);
        bodies.extend((0..5).map(|m| ball(3 + m, [0.06 + 0.01 * m as f64, 0.03, 0.05], [0.0; 3])));
        let l = law(
            NormalLaw::Hertz,
            TangentialLaw::History,
            Switches::LIGGGHTS,
            Linear::default(),
        );
        let g = V3::new(0.0, 0.0, -9.81);
        World::new(
            bodies,
            vec![floor],
            l,
            &[material(0.5, 0.5)],
            g,
            span / k as f64,
            0.5 * R,
        )
    };
    let (mut free, mut fixed) = (world(), world());
    for step in 0..40 {
        assert_eq!(free.advance_span(span, k), 5, "step {step}");
        fixed.advance(k);
    }
    for m in 0..3 {
        assert_eq!(free.bodies[m], fixed.bodies[m], "sphere {m}");
    }
    assert!(
        fixed.bodies[1].w.norm() > 1.0,
        "the pair rolls: {}",
        fixed.bodies[1].w
    );
}

/// A fluid step whose island is every sphere gives the same bits through the island's world, as
/// the whole world's DEM steps, and timed between the two (`world::everyone`): a bed wet and dry,
/// through two trials (the kept way run to the next).
#[test]
fn a_fluid_step_whose_island_is_every_sphere_goes_either_way_with_the_same_bits() {
    let steps = everyone::TRIAL + everyone::KEEP + everyone::TRIAL;
    for wet in [true, false] {
        let mut plain = bed(6, wet);
        let mut ways = [Some(Way::Island), Some(Way::Whole), None].map(|way| {
            let mut w = bed(6, wet);
            w.everyone.fixed = way;
            w
        });
        let span = 4.0 * plain.dt;
        for step in 0..steps {
            plain.advance(4);
            for w in &mut ways {
                assert_eq!(w.advance_span(span, 4), 0, "step {step}: nothing flies");
                let same = w.bodies.iter().zip(&plain.bodies).all(|(a, b)| a == b);
                assert!(same, "step {step}, wet {wet}, way {:?}", w.everyone.fixed);
            }
        }
        assert_eq!(
            ways[0].islands, steps as u64,
            "wet {wet}: every step through the island"
        );
        assert_eq!(ways[1].islands, 0, "wet {wet}: none through the island");
        assert_eq!(ways[2].everyone.trials, 2, "wet {wet}");
    }
}
