//! The DEM's tests, by subject: the contact laws against closed forms (`contact_laws`), sphere-wall
//! contacts and friction (`walls`), worlds set up from scenes (`scenes`), the fluid's drag within a
//! step (`drag`), the squeeze films of lubrication against Reynolds' law (`films`), periodic axes
//! (`periodic`), free flight (`free_flight`) and its islands (`islands`), the neighbour lists
//! (`lists`) and the compact contact passes (`compact`). Here: the spheres, materials, laws and
//! worlds they share.

use crate::dem::contact::{ContactLaw, Linear, Switches};
use crate::dem::lubrication::SqueezeFilm;
use crate::dem::world::{Body, Shape, Wall, World};
use crate::dem::V3;
use scene::dem::{Material, NormalLaw, RollingLaw, TangentialLaw};

mod compact;
mod contact_laws;
mod drag;
mod films;
mod free_flight;
mod islands;
mod lists;
mod periodic;
mod scenes;
mod walls;

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
    w.set_lubrication(Some(SqueezeFilm {
        viscosity: FILM_MU,
        cutoff: FILM_CUTOFF,
    }));
    w
}

/// `a` within `tol` of `b` (Euclidean), else a failure naming `what`.
fn assert_near(a: V3, b: V3, tol: f64, what: &str) {
    assert!((a - b).norm() < tol, "{what}: {a} against {b}");
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

/// A sphere of radius `R` and density `RHO`, not spinning.
fn ball(id: u64, x: [f64; 3], v: [f64; 3]) -> Body {
    Body::sphere(id, V3::from(x), V3::from(v), V3::zeros(), R, RHO, 0)
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
