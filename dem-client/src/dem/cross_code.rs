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

/// Bed height H = 2 sum(r^3 z) / sum(r^3) (cases.py `bed_measures`).
fn bed_height(bodies: &[Body]) -> f64 {
    let v: f64 = bodies.iter().map(|b| b.r.powi(3)).sum();
    2.0 * bodies.iter().map(|b| b.r.powi(3) * b.x.z).sum::<f64>() / v
}

/// Solid fraction of the cell-centred grid of spacing h in `region` (cases.py `packing_fraction`).
fn packing_fraction(bodies: &[Body], region: [[f64; 2]; 3], h: f64) -> f64 {
    let n: [usize; 3] = std::array::from_fn(|a| ((region[a][1] - region[a][0]) / h).round() as usize);
    let step: [f64; 3] = std::array::from_fn(|a| (region[a][1] - region[a][0]) / n[a] as f64);
    let centre = |a: usize, i: usize| region[a][0] + (i as f64 + 0.5) * step[a];
    let mut occupied = vec![false; n[0] * n[1] * n[2]];
    for b in bodies {
        // Grid indices whose centres lie within [x - r, x + r] (empty when none does).
        let range = |a: usize| {
            let lo = ((b.x[a] - b.r - region[a][0]) / step[a] - 0.5).ceil().max(0.0) as usize;
            let hi = ((b.x[a] + b.r - region[a][0]) / step[a] - 0.5).floor() + 1.0;
            lo..(hi.clamp(0.0, n[a] as f64) as usize)
        };
        if (0..3).any(|a| b.x[a] + b.r < region[a][0] || b.x[a] - b.r > region[a][1]) {
            continue;
        }
        for i in range(0) {
            for j in range(1) {
                for k in range(2) {
                    let d = V3::new(centre(0, i), centre(1, j), centre(2, k)) - b.x;
                    if d.norm_squared() < b.r * b.r {
                        occupied[(i * n[1] + j) * n[2] + k] = true;
                    }
                }
            }
        }
    }
    occupied.iter().filter(|o| **o).count() as f64 / occupied.len() as f64
}

/// Case 3, the 2000-sphere pour (`validation/scenes/dem_pour.toml`, the inputs of
/// `reference/pour_liggghts.json`): bed height within 0.5% of LIGGGHTS's mean over its three runs,
/// packing fraction within its run-to-run spread (2 standard deviations, at least 0.5%).
/// About 25 s of CPU in release: `cargo test --release -p dem-client -- --ignored pour`.
#[test]
#[ignore]
fn pour_liggghts() {
    let case = load("pour_liggghts.json");
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../validation/scenes/dem_pour.toml");
    let scene = scene::Scene::load(&path).unwrap();
    let mut setup = super::setup(&scene, &path.display().to_string()).unwrap();
    let p = &case["params"];
    assert_eq!(setup.dt_max, num(&p["dt_s"]));
    let steps = (num(&p["t_end_s"]) / setup.dt_max).round() as u64;
    setup.world.dt = setup.dt_max;
    setup.world.advance(steps);
    let bodies = &setup.world.bodies;
    let h = bed_height(bodies);
    let mean = |v: &Value| {
        let v = v.as_array().unwrap();
        v.iter().map(num).sum::<f64>() / v.len() as f64
    };
    close("pour bed height", h, mean(&case["bed_height_m_runs"]));
    let d = 2.0 * num(&p["radius_mean_m"]);
    let region = [
        [2.0 * d, 0.04 - 2.0 * d],
        [2.0 * d, 0.04 - 2.0 * d],
        [2.0 * d, h - 2.0 * d],
    ];
    let phi = packing_fraction(bodies, region, 1e-4);
    let reference = mean(&case["packing_fraction_runs"]);
    let spread = (2.0 * num(&case["packing_fraction_std"])).max(TOLERANCE * reference);
    eprintln!("pour: bed height {h} m, packing fraction {phi} (LIGGGHTS {reference} +- {spread})");
    assert!(
        (phi - reference).abs() <= spread,
        "packing fraction {phi} vs LIGGGHTS {reference} +- {spread}"
    );
}
