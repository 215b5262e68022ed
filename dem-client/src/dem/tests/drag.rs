//! The fluid's linear drag within a held fluid step.

use super::*;

/// A sphere with a linear drag (the coupled run's drag within a fluid step), falling from rest
/// under gravity with no other force: v(t) = -g tau (1 - exp(-t / tau)), tau = m / drag, to first
/// order in dt / tau (the drag is explicit in the kick), and exactly -g tau at the end (the kick's
/// fixed point).
#[test]
fn a_linear_drag_relaxes_the_velocity_to_its_terminal_value() {
    let (g, tau) = (9.81, 1e-3);
    let falling = |steps_per_tau: u64| {
        let mut body = Body::sphere(0, V3::zeros(), V3::zeros(), V3::zeros(), R, RHO, 0);
        body.drag = body.m / tau;
        let l = law(
            NormalLaw::Hertz,
            TangentialLaw::None,
            Switches::LIGGGHTS,
            Linear::default(),
        );
        let m = material(0.9, 0.5);
        let dt = tau / steps_per_tau as f64;
        let mut w = World::new(vec![body], vec![], l, &[m], V3::new(0.0, 0.0, -g), dt, 0.5 * R);
        w.advance(steps_per_tau);
        let after_tau = w.bodies[0].v.z;
        w.advance(30 * steps_per_tau);
        (after_tau, w.bodies[0].v.z)
    };
    let exact = -g * tau * (1.0 - (-1.0f64).exp());
    let (coarse, terminal) = falling(100);
    let (fine, _) = falling(200);
    let (e_coarse, e_fine) = ((coarse - exact).abs(), (fine - exact).abs());
    assert!(e_coarse < 0.01 * g * tau, "v(tau) = {coarse}, exact {exact}");
    assert!(
        e_fine < 0.6 * e_coarse,
        "first order: errors {e_coarse} at dt = tau/100, {e_fine} at tau/200"
    );
    assert!(
        (terminal + g * tau).abs() < 1e-9 * g * tau,
        "terminal {terminal}, exact {}",
        -g * tau
    );
}

/// The drag's reference velocity moving with the held acceleration (the coupled run's sub-step
/// drag, f_ext = drag v_n, f_ext_rate = drag g): a free sphere falls as if there were no drag, to
/// first order in dt / (m / drag) (the reference lags by part of a step: 4.5e-4 relative here).
#[test]
fn a_drag_whose_reference_follows_the_free_fall_leaves_it_unchanged() {
    let g = V3::new(0.0, 0.0, -9.81);
    let mut body = Body::sphere(0, V3::zeros(), V3::new(0.0, 0.0, -0.01), V3::zeros(), R, RHO, 0);
    body.drag = body.m / 1e-3;
    body.f_ext = body.drag * body.v;
    body.f_ext_rate = body.drag * g;
    let l = law(
        NormalLaw::Hertz,
        TangentialLaw::None,
        Switches::LIGGGHTS,
        Linear::default(),
    );
    let mut w = World::new(vec![body], vec![], l, &[material(0.9, 0.5)], g, 1e-5, 0.5 * R);
    w.advance(1000);
    let free = -0.01 + g.z * 1000.0 * 1e-5;
    let v = w.bodies[0].v.z;
    assert!((v - free).abs() < 1e-3 * free.abs(), "v {v}, free fall {free}");
}
