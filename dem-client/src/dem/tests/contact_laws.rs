//! Contact laws against closed forms: energy conservation, the linear spring-dashpot's
//! restitution and contact time, the normal force's clamp, the Coulomb slider.

use super::*;
use crate::dem::timestep::{hertz_contact_time, linear_contact_time, linear_restitution};

/// Steps per contact time of the energy test. Measured relative energy errors (head-on, 1 m/s):
/// Hertz 7.9e-5 at t_c/50, 1.2e-5 at /100, 8e-7 at /200, 1e-7 at /500; linear 2.0e-5, 8e-7,
/// 3e-7, 3e-8. The error comes from the steps that straddle the start and end of the contact.
const STEPS_PER_CONTACT_FOR_ENERGY: f64 = 500.0;

#[test]
fn frictionless_elastic_collision_conserves_energy() {
    for normal in [NormalLaw::Hertz, NormalLaw::Linear] {
        let l = law(
            normal,
            TangentialLaw::None,
            Switches::LIGGGHTS,
            stiff(2000.0, Some(0.0)),
        );
        let m = material(1.0, 0.0);
        let m_eff = 0.5 * mass();
        let t_c = match normal {
            NormalLaw::Hertz => hertz_contact_time(
                m_eff,
                0.5 * R,
                crate::dem::contact::PairMaterial::mix(&m, &m).y_star,
                1.0,
            ),
            NormalLaw::Linear => linear_contact_time(2000.0, 0.0, m_eff),
        };
        let mut w = head_on(l, m, 1.0, t_c / STEPS_PER_CONTACT_FOR_ENERGY);
        let before = w.kinetic_energy();
        collide(&mut w);
        let after = w.kinetic_energy();
        assert!(
            ((after - before) / before).abs() < 1e-6,
            "{normal:?}: {before} -> {after}, relative {:e}",
            (after - before) / before
        );
    }
}

#[test]
fn linear_spring_dashpot_matches_closed_form_restitution_and_contact_time() {
    let (k, gamma) = (5000.0, 0.02);
    let m_eff = 0.5 * mass();
    let t_c = linear_contact_time(k, gamma, m_eff);
    let e = linear_restitution(k, gamma, m_eff);
    let l = law(
        NormalLaw::Linear,
        TangentialLaw::None,
        Switches::LIGGGHTS,
        stiff(k, Some(gamma)),
    );
    let mut w = head_on(l, material(0.5, 0.0), 1.0, t_c / 2000.0);
    let (v_after, t) = collide(&mut w);
    assert!((v_after - e).abs() < 1e-3 * e, "e {v_after} vs closed form {e}");
    assert!((t - t_c).abs() < 2e-3 * t_c, "t_c {t} vs closed form {t_c}");
}

#[test]
fn linear_law_from_restitution_and_contact_time_hits_both() {
    for e in [0.3, 0.7, 0.95] {
        let t_c = 1e-4;
        let linear = Linear {
            contact_time: Some(t_c),
            ..Linear::default()
        };
        let l = law(NormalLaw::Linear, TangentialLaw::None, Switches::LIGGGHTS, linear);
        let mut w = head_on(l, material(e, 0.0), 0.5, t_c / 2000.0);
        let (v, t) = collide(&mut w);
        assert!((v / 0.5 - e).abs() < 1e-3 * e, "e {} vs {e}", v / 0.5);
        assert!((t - t_c).abs() < 2e-3 * t_c, "t_c {t} vs {t_c}");
    }
}

#[test]
fn clamping_the_normal_force_raises_the_restitution() {
    let run = |clamp: bool| {
        let switches = Switches {
            clamp_normal: clamp,
            ..Switches::LIGGGHTS
        };
        let l = law(
            NormalLaw::Linear,
            TangentialLaw::None,
            switches,
            stiff(5000.0, Some(0.3)),
        );
        let mut w = head_on(l, material(0.5, 0.0), 1.0, 1e-7);
        collide(&mut w).0
    };
    let (free, clamped) = (run(false), run(true));
    let m_eff = 0.5 * mass();
    assert!(
        (free - linear_restitution(5000.0, 0.3, m_eff)).abs() < 2e-3,
        "{free}"
    );
    assert!(clamped > free + 0.01, "clamped {clamped} vs unclamped {free}");
}

/// Coulomb limit in the total spring: the stored displacement is cut back to mu F_n / k_t.
#[test]
fn tangential_slider_caps_the_force_at_mu_fn() {
    use crate::dem::contact::{tangential_force, Coefficients};
    let l = law(
        NormalLaw::Linear,
        TangentialLaw::History,
        Switches::LIGGGHTS,
        Linear::default(),
    );
    let k = Coefficients {
        f_elastic: 10.0,
        gamma_n: 0.0,
        k_t: 1000.0,
        gamma_t: 0.5,
    };
    let mut xi = V3::zeros();
    let f = tangential_force(&l, &k, 5.0, V3::z(), V3::new(1.0, 0.0, 0.0), &mut xi, 1e-3);
    assert!(
        (f - V3::new(-1.0 - 0.5, 0.0, 0.0)).norm() < 1e-12,
        "stick: spring + dashpot {f}"
    );
    let f = tangential_force(&l, &k, 5.0, V3::z(), V3::new(10.0, 0.0, 0.0), &mut xi, 1e-3);
    assert!((f.norm() - 5.0).abs() < 1e-12 && f.x < 0.0, "slip: {f}");
    assert!((xi.x - 5.0 / 1000.0).abs() < 1e-15, "history cut back: {xi}");
}
