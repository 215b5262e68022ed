//! Contact laws against closed forms, energy conservation, friction, the time-step rule, and the
//! squeeze films of lubrication against Reynolds' law.

use super::contact::{beta_thornton, ContactLaw, Linear, Switches};
use super::lubrication::{Lubrication, MIN_GAP_FRACTION};
use super::timestep::{hertz_contact_time, linear_contact_time, linear_restitution};
use super::world::everyone::{self, Way};
use super::world::{Body, Shape, Wall, World};
use super::V3;
use scene::dem::{Material, NormalLaw, RollingLaw, TangentialLaw};

const RHO: f64 = 2500.0;
const R: f64 = 0.002;

fn material(e: f64, mu: f64) -> Material {
    Material {
        restitution: e,
        friction: mu,
        ..Material::default()
    }
}

fn law(normal: NormalLaw, tangential: TangentialLaw, switches: Switches, linear: Linear) -> ContactLaw {
    ContactLaw {
        normal,
        tangential,
        rolling: RollingLaw::None,
        linear,
        switches,
    }
}

fn stiff(k: f64, gamma: Option<f64>) -> Linear {
    Linear {
        normal_stiffness: Some(k),
        normal_damping: gamma,
        ..Linear::default()
    }
}

/// Two equal spheres approaching head-on at relative speed `v` (no gravity).
fn head_on(law: ContactLaw, m: Material, v: f64, dt: f64) -> World {
    let a = Body::sphere(
        0,
        V3::new(-R - 1e-5, 0.0, 0.0),
        V3::new(0.5 * v, 0.0, 0.0),
        V3::zeros(),
        R,
        RHO,
        0,
    );
    let b = Body::sphere(
        1,
        V3::new(R + 1e-5, 0.0, 0.0),
        V3::new(-0.5 * v, 0.0, 0.0),
        V3::zeros(),
        R,
        RHO,
        0,
    );
    World::new(vec![a, b], vec![], law, &[m], V3::zeros(), dt, 0.5 * R)
}

/// Steps until the contact is over; returns (relative separation speed after, contact time).
fn collide(world: &mut World) -> (f64, f64) {
    let mut touching_steps = 0u64;
    let mut was = false;
    for _ in 0..10_000_000 {
        world.step();
        let now = world.contact_count() > 0;
        if now {
            touching_steps += 1;
        }
        if was && !now {
            break;
        }
        was = now;
    }
    let dv = match world.bodies.len() {
        1 => world.bodies[0].v,
        _ => world.bodies[1].v - world.bodies[0].v,
    };
    (dv.x, touching_steps as f64 * world.dt)
}

fn mass() -> f64 {
    RHO * 4.0 / 3.0 * std::f64::consts::PI * R.powi(3)
}

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
                super::contact::PairMaterial::mix(&m, &m).y_star,
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

/// A sphere dropped on a plane at speed v: (rebound speed, contact time).
fn drop_on_wall(l: ContactLaw, m: Material, v: f64, steps_per_tc: f64) -> (f64, f64) {
    let body = Body::sphere(
        0,
        V3::new(0.0, 0.0, R + 1e-6),
        V3::new(0.0, 0.0, -v),
        V3::zeros(),
        R,
        RHO,
        0,
    );
    let wall = Wall {
        shape: Shape::Plane {
            point: V3::zeros(),
            normal: V3::z(),
        },
        material: 0,
    };
    let y = super::contact::PairMaterial::mix(&m, &m).y_star;
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
        let y = super::contact::PairMaterial::mix(&m, &m).y_star;
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
        let body = Body::sphere(
            0,
            V3::new(0.0, 0.0, R * 0.9999),
            V3::new(0.5, 0.0, 0.0),
            V3::zeros(),
            R,
            RHO,
            0,
        );
        let wall = Wall {
            shape: Shape::Plane {
                point: V3::zeros(),
                normal: V3::z(),
            },
            material: 0,
        };
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

/// Coulomb limit in the total spring: the stored displacement is cut back to mu F_n / k_t.
#[test]
fn tangential_slider_caps_the_force_at_mu_fn() {
    use super::contact::{tangential_force, Coefficients};
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

#[test]
fn a_dense_pour_settles_inside_its_box() {
    let text = r#"name = "pour"
[domain]
min = [0.0, 0.0, 0.0]
max = [0.04, 0.04, 0.08]
[fluid]
density = 1.2
dynamic_viscosity = 1.8e-5
[time]
dt = 1.0e-3
steps = 300
[particles]
density = 2500.0
[[dem.material]]
name = "glass"
restitution = 0.5
friction = 0.5
[[dem.insert]]
origin = [0.004, 0.004, 0.004]
count = [7, 7, 8]
spacing = 0.005
radius = [0.0015, 0.002]
jitter = 0.0004
"#;
    let scene = scene::Scene::parse(text, "pour.toml").unwrap();
    let mut setup = super::setup(&scene, "pour.toml").unwrap();
    let w = &mut setup.world;
    let (k, dt) = super::timestep::substeps(scene.time.dt, setup.dt_max);
    w.dt = dt;
    let potential: f64 = w.bodies.iter().map(|b| b.m * 9.81 * b.x.z).sum();
    for _ in 0..300 * k {
        w.step();
    }
    assert!(
        w.kinetic_energy() < 1e-5 * potential,
        "settled: {} J of {potential} J",
        w.kinetic_energy()
    );
    assert!(
        w.contact_count() > w.bodies.len(),
        "a packed bed: {} contacts",
        w.contact_count()
    );
    for b in &w.bodies {
        assert!(b.x.z > b.r * 0.9 && b.x.z < 0.08, "inside the box: {:?}", b.x);
    }
}

#[test]
fn a_time_step_above_the_stability_limit_is_refused() {
    let text = r#"name = "t"
[domain]
min = [0.0, 0.0, 0.0]
max = [0.1, 0.1, 0.1]
[fluid]
density = 1.2
dynamic_viscosity = 1.8e-5
[time]
dt = 1.0e-3
steps = 3
[particles]
density = 2500.0
[[particles.sphere]]
position = [0.05, 0.05, 0.05]
radius = 0.002
[dem]
dt = 1.0e-3
"#;
    let scene = scene::Scene::parse(text, "t.toml").unwrap();
    let e = super::setup(&scene, "t.toml").err().unwrap().to_string();
    assert!(
        e.starts_with("t.toml: dem.dt = 0.001 s: is above the stability limit t_c / 10"),
        "{e}"
    );
}

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

/// Viscosity, cut-off and density of the squeeze-film tests: a 2 mm sphere in a fluid of 1 Pa s.
const FILM_MU: f64 = 1.0;
const FILM_CUTOFF: f64 = 0.5e-3;
const FILM_RHO: f64 = 1000.0;

fn film_world(bodies: Vec<Body>, walls: Vec<Wall>, gravity: V3, dt: f64) -> World {
    let l = law(
        NormalLaw::Hertz,
        TangentialLaw::None,
        Switches::LIGGGHTS,
        Linear::default(),
    );
    let mut w = World::new(bodies, walls, l, &[material(0.9, 0.0)], gravity, dt, 0.5 * R);
    w.set_lubrication(Some(Lubrication {
        viscosity: FILM_MU,
        cutoff: FILM_CUTOFF,
    }));
    w
}

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
    let lub = Lubrication {
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

/// Two spheres meeting obliquely across the periodic face x = 0 of a 30 mm box collide as they
/// do inside it: after the contact the same velocities and spins (to round-off) and positions one
/// period apart where they crossed, all inside the box; for the general pair loop (YADE's Hertz)
/// and the batched one (LIGGGHTS's). Without the period the pair never meets.
#[test]
fn spheres_collide_across_a_periodic_face_as_inside() {
    use super::neighbor::Periodic;
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
        // The pair centred at `centre` (wrapped into the box when `wrapped`), in a world periodic
        // along x when `periodic`.
        let run = |centre: f64, wrapped: bool, periodic: bool| {
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

/// `a` within `tol` of `b` (Euclidean), else a failure naming `what`.
fn assert_near(a: V3, b: V3, tol: f64, what: &str) {
    assert!((a - b).norm() < tol, "{what}: {a} against {b}");
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
    let short = super::neighbor::Periodic {
        lo: V3::zeros(),
        len: [0.0, 0.009, 0.0],
    };
    let err = w.set_periodic(Some(short), 0.0).unwrap_err();
    assert!(err.contains("periodic y axis is 0.009 m"), "{err}");
}

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

/// A sphere falling onto the floor, stopped by its squeeze film, and two spheres meeting head-on
/// through theirs (inside, and across a periodic face): with free flight the fluid steps far from
/// anything are flown in one step each, and the films and contacts start in DEM steps as without
/// it: the same closest approach (an overlap for the pairs) and the same speeds after it.
#[test]
fn free_flight_stops_before_every_contact_and_film() {
    let floor = floor();
    let (span, k) = (2e-4, 200);
    let drop = || {
        let b = Body::sphere(
            0,
            V3::new(0.01, 0.01, 0.006),
            V3::new(0.0, 0.0, -0.3),
            V3::zeros(),
            R,
            RHO,
            0,
        );
        film_world(vec![b], vec![floor], V3::new(0.0, 0.0, -9.81), span / k as f64)
    };
    let pair = |period: f64| {
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
        let box_ = super::neighbor::Periodic {
            lo: V3::zeros(),
            len: [period, 0.0, 0.0],
        };
        let mut w = film_world(
            vec![a, b]
                .into_iter()
                .map(|b| Body {
                    x: box_.wrap(b.x),
                    ..b
                })
                .collect(),
            vec![],
            V3::zeros(),
            span / k as f64,
        );
        if period > 0.0 {
            w.set_periodic(Some(box_), 0.0).unwrap();
        }
        w
    };
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

/// The plane z = 0, spheres above it.
fn floor() -> Wall {
    Wall {
        shape: Shape::Plane {
            point: V3::zeros(),
            normal: V3::z(),
        },
        material: 0,
    }
}

/// A sphere of the test sets of free flight: radius `R`, density `RHO`, not spinning.
fn ball(id: u64, x: [f64; 3], v: [f64; 3]) -> Body {
    Body::sphere(id, V3::from(x), V3::from(v), V3::zeros(), R, RHO, 0)
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
        let box_ = super::neighbor::Periodic {
            lo: V3::zeros(),
            len: [period, 0.0, 0.0],
        };
        // The nearest image along x.
        let image = |d: V3| {
            let shift = if period > 0.0 {
                period * (d.x / period).round()
            } else {
                0.0
            };
            V3::new(d.x - shift, d.y, d.z)
        };
        let world = || {
            let at = if period > 0.0 { 0.0 } else { 0.04 };
            let mut bodies = vec![
                ball(0, [0.01, 0.01, 0.006], [0.0, 0.0, -0.3]),
                ball(1, [at - 2.0 * R - 3e-3, 0.01, 0.03], [0.4, 0.0, 0.0]),
                ball(2, [at + 2.0 * R + 3e-3, 0.01, 0.03], [-0.4, 0.0, 0.0]),
            ];
            bodies
                .extend((0..6).map(|m| ball(3 + m, [0.075 + 0.01 * m as f64, 0.03, 0.04], [0.0, 0.0, 0.1])));
            let bodies = bodies
                .into_iter()
                .map(|b| Body {
                    x: box_.wrap(b.x),
                    ..b
                })
                .collect();
            let mut w = film_world(bodies, vec![floor()], V3::new(0.0, 0.0, -9.81), span / k as f64);
            if period > 0.0 {
                w.set_periodic(Some(box_), 0.0).unwrap();
            }
            w
        };
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

/// Two spheres pressed together and sliding past each other with friction (their tangential
/// spring loaded); then a sphere is inserted (a neighbour-list build) after the two changed places
/// in the list: the spring's history follows them (found by their ids, its sign turned with their
/// order), and they go on as when they kept their places.
#[test]
fn a_contact_history_follows_its_spheres_through_a_rebuild_when_they_change_places() {
    let world = || {
        let mut bodies = vec![
            ball(0, [0.01, 0.01, 0.01], [0.0, 0.01, 0.0]),
            ball(1, [0.01 + 2.0 * R - 2e-6, 0.01, 0.01], [0.0, -0.01, 0.0]),
        ];
        bodies[0].f_ext = V3::new(2e-3, 0.0, 0.0);
        bodies[1].f_ext = V3::new(-2e-3, 0.0, 0.0);
        let l = law(
            NormalLaw::Hertz,
            TangentialLaw::History,
            Switches::LIGGGHTS,
            Linear::default(),
        );
        World::new(
            bodies,
            vec![],
            l,
            &[material(0.5, 0.5)],
            V3::zeros(),
            1e-6,
            0.5 * R,
        )
    };
    let (mut kept, mut swapped) = (world(), world());
    for w in [&mut kept, &mut swapped] {
        w.advance(300);
    }
    swapped.bodies.swap(0, 1);
    let far = ball(2, [0.05, 0.05, 0.05], [0.0; 3]);
    kept.insert(far);
    swapped.insert(far);
    kept.advance(300);
    swapped.advance(300);
    for (a, b) in [(0, 1), (1, 0)] {
        let (p, q) = (kept.bodies[a], swapped.bodies[b]);
        assert_eq!(p.id, q.id);
        assert_near(p.v, q.v, 1e-12, "velocity");
        assert_near(p.w, q.w, 1e-9, "spin");
        assert_near(p.f, q.f, 1e-12, "contact force");
    }
    assert!(
        kept.bodies[0].w.norm() > 1.0,
        "the spring turns them: {}",
        kept.bodies[0].w
    );
}

/// A bed of `n`^3 spheres (radius `R`, density `RHO`) on a cubic lattice 10 um apart on the floor
/// of a closed box, each given a different small velocity, every fifth pressed into its
/// neighbour: wet (`film_world`: Hertz without friction, in squeeze films: most listed pairs are
/// films, a few touch) or dry with `ContactLaw::LIGGGHTS_HERTZ` (whose pairs take the batched law).
fn bed(n: usize, wet: bool) -> World {
    let spacing = 2.0 * R + 10e-6;
    let side = n as f64 * spacing;
    let mut bodies = Vec::new();
    for k in 0..n * n * n {
        let (i, j, l) = (k % n, (k / n) % n, k / (n * n));
        // Every fifth sphere 5 um into its neighbour along x.
        let nudge = if k % 5 == 0 && i + 1 < n { 15e-6 } else { 0.0 };
        let x = [
            (i as f64 + 0.5) * spacing + nudge,
            (j as f64 + 0.5) * spacing,
            R + 5e-6 + l as f64 * spacing,
        ];
        let v = [
            0.002 * ((k * 7 % 11) as f64 - 5.0),
            0.002 * ((k * 5 % 13) as f64 - 6.0),
            -0.01,
        ];
        bodies.push(ball(k as u64, x, v));
    }
    let wall = |point: V3, normal: V3| Wall {
        shape: Shape::Plane { point, normal },
        material: 0,
    };
    let walls = vec![
        floor(),
        wall(V3::zeros(), V3::x()),
        wall(V3::new(side, 0.0, 0.0), -V3::x()),
        wall(V3::zeros(), V3::y()),
        wall(V3::new(0.0, side, 0.0), -V3::y()),
    ];
    let g = V3::new(0.0, 0.0, -9.81);
    if wet {
        return film_world(bodies, walls, g, 1e-5);
    }
    let glass = material(0.5, 0.5);
    World::new(
        bodies,
        walls,
        ContactLaw::LIGGGHTS_HERTZ,
        &[glass],
        g,
        1e-6,
        0.5 * R,
    )
}

/// A world large enough for the compact contact passes (a copy of the spheres' motion for the
/// pair pass; the gather adding only the touching pairs where few touch) steps to the same bits
/// as the same world through the bodies, adding every pair: wet and dry (the batched law).
#[test]
fn a_large_world_steps_the_same_from_its_compact_arrays() {
    let n = 16;
    assert!(n * n * n >= super::world::COMPACT_FROM, "the bed is large enough");
    for wet in [true, false] {
        let mut compact = bed(n, wet);
        let mut plain = bed(n, wet);
        plain.compact_from = usize::MAX;
        let mut few_touch = false;
        for _ in 0..20 {
            compact.advance(10);
            plain.advance(10);
            assert_eq!(compact.contact_count(), plain.contact_count(), "wet {wet}");
            let touching = compact.contact_count();
            few_touch |= touching > 0 && 2 * touching < compact.pair_count();
            for (a, b) in compact.bodies.iter().zip(&plain.bodies) {
                let (a, b, id) = ((a.x, a.v, a.w, a.f, a.t), (b.x, b.v, b.w, b.f, b.t), a.id);
                assert_eq!(a, b, "sphere {id}, wet {wet}");
            }
        }
        let (touching, pairs) = (compact.contact_count(), compact.pair_count());
        assert!(
            few_touch,
            "wet {wet}: the gather never skipped: {touching} contacts, {pairs} pairs"
        );
    }
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
