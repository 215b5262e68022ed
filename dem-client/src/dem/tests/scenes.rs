//! Worlds set up from scenes: a pour that settles, a time step refused.

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
    let mut setup = crate::dem::setup(&scene, "pour.toml").unwrap();
    let w = &mut setup.world;
    let (k, dt) = crate::dem::timestep::substeps(scene.time.dt, setup.dt_max);
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
    let e = crate::dem::setup(&scene, "t.toml").err().unwrap().to_string();
    assert!(
        e.starts_with("t.toml: dem.dt = 0.001 s: is above the stability limit t_c / 10"),
        "{e}"
    );
}
