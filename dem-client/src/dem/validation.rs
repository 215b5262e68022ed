//! Cross-code validation: the cases of `validation/dem/reference/*.json` (LIGGGHTS 3.8.0 and
//! YADE 2023.02a runs with their exact inputs) replayed with the matching preset; restitution,
//! contact time and post-collision velocities must agree within 0.5%.

use super::contact::{ContactLaw, Linear, Switches};
use super::world::{Body, Shape, Wall, World};
use super::V3;
use scene::dem::{Material, NormalLaw, RollingLaw, TangentialLaw};
use serde_json::Value;
use std::path::PathBuf;

const TOLERANCE: f64 = 0.005;

fn reference_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../validation/dem/reference")
}

fn load(name: &str) -> Value {
    let path = reference_dir().join(name);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap()
}

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

fn vec3(v: &Value) -> V3 {
    V3::new(num(&v[0]), num(&v[1]), num(&v[2]))
}

/// The law of a reference case: the preset of its code, linear or Hertz.
fn law(case: &Value) -> (ContactLaw, Material) {
    let p = &case["params"];
    let switches = match case["code"].as_str().unwrap() {
        "liggghts" => Switches::LIGGGHTS,
        "yade" => Switches::YADE,
        other => panic!("unknown code {other}"),
    };
    let m = &p["material"];
    let material = Material {
        young_modulus: num(&m["youngs_modulus_Pa"]),
        poisson_ratio: num(&m["poisson_ratio"]),
        restitution: num(&m["restitution"]),
        friction: num(&m["friction"]),
        ..Material::default()
    };
    let (normal, linear) = match case["model"].as_str().unwrap() {
        "hertz" => (NormalLaw::Hertz, Linear::default()),
        "linear" => {
            let l = &p["linear"];
            let linear = Linear {
                normal_stiffness: Some(num(&l["kn_N_m"])),
                normal_damping: Some(num(&l["cn_N_s_m"])),
                tangential_stiffness: Some(num(&l["kt_N_m"])),
                tangential_damping: Some(num(&l["ct_N_s_m"])),
                contact_time: None,
            };
            (NormalLaw::Linear, linear)
        }
        other => panic!("unknown model {other}"),
    };
    let law = ContactLaw {
        normal,
        tangential: TangentialLaw::History,
        rolling: RollingLaw::None,
        linear,
        switches,
    };
    (law, material)
}

/// Runs to t_end; returns the world and the time in contact (steps with a contact x dt).
fn replay(mut world: World, t_end: f64) -> (World, f64) {
    let steps = (t_end / world.dt).round() as u64;
    let mut touching = 0u64;
    for _ in 0..steps {
        world.step();
        if world.contact_count() > 0 {
            touching += 1;
        }
    }
    let t = touching as f64 * world.dt;
    (world, t)
}

fn close(what: &str, mine: f64, reference: f64) {
    let rel = (mine - reference).abs() / reference.abs();
    eprintln!("deviation {what}: {:.4}%", 100.0 * rel);
    assert!(
        rel <= TOLERANCE,
        "{what}: {mine} vs reference {reference} ({:.3}% off)",
        100.0 * rel
    );
}

fn close3(what: &str, mine: V3, reference: V3) {
    let rel = (mine - reference).norm() / reference.norm();
    eprintln!("deviation {what}: {:.4}%", 100.0 * rel);
    assert!(
        rel <= TOLERANCE,
        "{what}: {mine:?} vs reference {reference:?} ({:.3}% off)",
        100.0 * rel
    );
}

fn drop_case(name: &str) {
    let case = load(name);
    let p = &case["params"];
    let (law, material) = law(&case);
    let r = num(&p["radius_m"]);
    let body = Body::sphere(
        0,
        vec3(&p["initial_position_m"]),
        vec3(&p["initial_velocity_m_s"]),
        vec3(&p["initial_angular_velocity_rad_s"]),
        r,
        num(&p["density_kg_m3"]),
        0,
    );
    let wall = Wall {
        shape: Shape::Plane {
            point: V3::zeros(),
            normal: V3::z(),
        },
        material: 0,
    };
    let world = World::new(
        vec![body],
        vec![wall],
        law,
        &[material],
        vec3(&p["gravity_m_s2"]),
        num(&p["dt_s"]),
        0.5 * r,
    );
    let (world, t_c) = replay(world, num(&p["t_end_s"]));
    let v0 = vec3(&p["initial_velocity_m_s"]).z;
    let b = &world.bodies[0];
    close(
        &format!("{name} restitution"),
        -b.v.z / v0,
        num(&case["restitution"]),
    );
    close(
        &format!("{name} contact time"),
        t_c,
        num(&case["contact_duration_steps_s"]),
    );
    close3(
        &format!("{name} final velocity"),
        b.v,
        vec3(&case["final_velocity_m_s"]),
    );
}

fn oblique_case(name: &str) {
    let case = load(name);
    let p = &case["params"];
    let (law, material) = law(&case);
    let bodies: Vec<Body> = (0..2)
        .map(|k| {
            Body::sphere(
                k as u64,
                vec3(&p["initial_position_m"][k]),
                vec3(&p["initial_velocity_m_s"][k]),
                vec3(&p["initial_angular_velocity_rad_s"][k]),
                num(&p["radius_m"][k]),
                num(&p["density_kg_m3"]),
                0,
            )
        })
        .collect();
    let skin = 0.5 * bodies[0].r;
    let world = World::new(
        bodies,
        vec![],
        law,
        &[material],
        vec3(&p["gravity_m_s2"]),
        num(&p["dt_s"]),
        skin,
    );
    let dv0 = world.bodies[1].v - world.bodies[0].v;
    let (world, t_c) = replay(world, num(&p["t_end_s"]));
    let (a, b) = (&world.bodies[0], &world.bodies[1]);
    let e = -(b.v - a.v).x / dv0.x;
    close(
        &format!("{name} normal restitution"),
        e,
        num(&case["normal_restitution"]),
    );
    close(
        &format!("{name} contact time"),
        t_c,
        num(&case["contact_duration_steps_s"]),
    );
    let post = &case["post"];
    close3(&format!("{name} v1"), a.v, vec3(&post["v1"]));
    close3(&format!("{name} v2"), b.v, vec3(&post["v2"]));
    close3(&format!("{name} w1"), a.w, vec3(&post["w1"]));
    close3(&format!("{name} w2"), b.w, vec3(&post["w2"]));
}

#[test]
fn drop_linear_liggghts() {
    drop_case("drop_linear_liggghts.json");
}
#[test]
fn drop_linear_yade() {
    drop_case("drop_linear_yade.json");
}
#[test]
fn drop_hertz_liggghts() {
    drop_case("drop_hertz_liggghts.json");
}
#[test]
fn drop_hertz_yade() {
    drop_case("drop_hertz_yade.json");
}
#[test]
fn oblique_linear_30_liggghts() {
    oblique_case("oblique_linear_30_liggghts.json");
}
#[test]
fn oblique_linear_60_liggghts() {
    oblique_case("oblique_linear_60_liggghts.json");
}
#[test]
fn oblique_hertz_30_liggghts() {
    oblique_case("oblique_hertz_30_liggghts.json");
}
#[test]
fn oblique_hertz_60_liggghts() {
    oblique_case("oblique_hertz_60_liggghts.json");
}
#[test]
fn oblique_linear_30_yade() {
    oblique_case("oblique_linear_30_yade.json");
}
#[test]
fn oblique_linear_60_yade() {
    oblique_case("oblique_linear_60_yade.json");
}
#[test]
fn oblique_hertz_30_yade() {
    oblique_case("oblique_hertz_30_yade.json");
}
#[test]
fn oblique_hertz_60_yade() {
    oblique_case("oblique_hertz_60_yade.json");
}
