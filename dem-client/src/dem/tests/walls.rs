//! Sphere-wall contacts: Hertz contact times and restitutions under each preset, rolling by
//! friction.

use super::*;
use crate::dem::contact::beta_thornton;
use crate::dem::timestep::hertz_contact_time;

/// A sphere dropped on a plane at speed v: (rebound speed, contact time).
fn drop_on_wall(l: ContactLaw, m: Material, v: f64, steps_per_tc: f64) -> (f64, f64) {
    let (body, wall) = (ball(0, [0.0, 0.0, R + 1e-6], [0.0, 0.0, -v]), floor());
    let y = crate::dem::contact::PairMaterial::mix(&m, &m).y_star;
    let t_c = hertz_contact_time(mass(), l.switches.wall_radius_factor * R, y, v);
    let mut w = World::new(
        vec![body],
        vec![wall],
        l,
        &[m],
        V3::zeros(),
        t_c / steps_per_tc,
        0.5 * R,
    );
    let (_, t) = collide(&mut w);
    (w.bodies[0].v.z, t)
}

#[test]
fn hertz_contact_time_matches_closed_form_on_a_wall() {
    for switches in [Switches::LIGGGHTS, Switches::YADE] {
        let l = law(NormalLaw::Hertz, TangentialLaw::None, switches, Linear::default());
        let m = material(1.0, 0.0);
        let y = crate::dem::contact::PairMaterial::mix(&m, &m).y_star;
        let t_c = hertz_contact_time(mass(), switches.wall_radius_factor * R, y, 0.8);
        let (v, t) = drop_on_wall(l, m, 0.8, 2000.0);
        assert!((v - 0.8).abs() < 1e-6, "elastic rebound {v}");
        assert!(
            (t - t_c).abs() < 2e-3 * t_c,
            "{switches:?}: t_c {t} vs closed form {t_c}"
        );
    }
}

#[test]
fn yade_wall_contact_lasts_longer_by_two_to_the_fifth() {
    let m = material(1.0, 0.0);
    let (_, t_l) = drop_on_wall(
        law(
            NormalLaw::Hertz,
            TangentialLaw::None,
            Switches::LIGGGHTS,
            Linear::default(),
        ),
        m.clone(),
        1.0,
        1000.0,
    );
    let (_, t_y) = drop_on_wall(
        law(
            NormalLaw::Hertz,
            TangentialLaw::None,
            Switches::YADE,
            Linear::default(),
        ),
        m,
        1.0,
        1000.0,
    );
    assert!((t_y / t_l - 2f64.powf(0.2)).abs() < 5e-3, "{}", t_y / t_l);
}

#[test]
fn thornton_damping_gives_the_requested_restitution_for_clamped_hertz() {
    for e in [0.3, 0.5, 0.8, 0.95] {
        let l = law(
            NormalLaw::Hertz,
            TangentialLaw::None,
            Switches::YADE,
            Linear::default(),
        );
        let (v, _) = drop_on_wall(l, material(e, 0.0), 1.0, 2000.0);
        assert!((v - e).abs() < 0.01 * e, "e {v} vs requested {e}");
    }
    assert_eq!(beta_thornton(1.0), 0.0);
}

#[test]
fn liggghts_hertz_restitution_is_independent_of_impact_speed() {
    let l = law(
        NormalLaw::Hertz,
        TangentialLaw::None,
        Switches::LIGGGHTS,
        Linear::default(),
    );
    let (slow, _) = drop_on_wall(l, material(0.6, 0.0), 0.2, 1000.0);
    let (fast, _) = drop_on_wall(l, material(0.6, 0.0), 2.0, 1000.0);
    assert!(
        (slow / 0.2 - fast / 2.0).abs() < 2e-3,
        "{} vs {}",
        slow / 0.2,
        fast / 2.0
    );
}

/// A sphere sliding without spin on a plane under gravity ends up rolling at 5/7 of its speed.
#[test]
fn sliding_sphere_rolls_at_five_sevenths() {
    for switches in [Switches::LIGGGHTS, Switches::YADE] {
        let l = law(
            NormalLaw::Hertz,
            TangentialLaw::History,
            switches,
            Linear::default(),
        );
        let m = material(0.5, 0.4);
        let (body, wall) = (ball(0, [0.0, 0.0, R * 0.9999], [0.5, 0.0, 0.0]), floor());
        let mut w = World::new(
            vec![body],
            vec![wall],
            l,
            &[m],
            V3::new(0.0, 0.0, -9.81),
            2e-6,
            0.5 * R,
        );
        for _ in 0..200_000 {
            w.step();
        }
        let b = w.bodies[0];
        assert!(
            (b.v.x - 0.5 * 5.0 / 7.0).abs() < 0.01 * 0.5,
            "{switches:?}: v {}",
            b.v.x
        );
        assert!(
            (b.w.y * R - b.v.x).abs() < 0.01 * b.v.x,
            "rolls: w r {} vs v {}",
            b.w.y * R,
            b.v.x
        );
    }
}
