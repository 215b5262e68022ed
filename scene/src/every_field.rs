//! Every number of the scene format is checked before anything runs: scenes that give every field
//! there is, each number in turn made NaN, infinite, zero or huge, must be refused naming that
//! field and value. A field added to the format and left out of these scenes fails
//! `the_full_scenes_give_every_field`, so no number escapes the checks.

use crate::Scene;
use std::collections::{BTreeMap, BTreeSet};
use toml::Value;

/// A coupled scene with a TRT lattice that gives every field it can (the others are in
/// [`FLUID_ONLY`] and [`GRANULAR`]); `CSV` stands for the path of a particle file.
const COUPLED: &str = r#"
name = "full"
gravity = [0.0, 0.0, -9.81]
[domain]
min = [0.0, 0.0, 0.0]
max = [0.016, 0.016, 0.016]
periodic = ["x"]
[fluid]
density = 1000.0
dynamic_viscosity = 1.0
[time]
steps = 100
[output]
interval = 10
fields_interval = 50
checkpoint_interval = 20
checkpoint_wall_interval = 30.0
[[output.line]]
axis = "z"
through = [0.008, 0.008, 0.008]
[coupling]
timeout = 10.0
capacity = 100
slots = 2
weighting = "noble-torczynski"
solid_collision = "noble-torczynski"
lubrication = true
substep_drag = true
free_flight = true
covered_cells = "auto"
radius_correction = "none"
[particles]
density = 2500.0
[[particles.sphere]]
position = [0.004, 0.004, 0.012]
radius = 0.001
velocity = [0.0, 0.0, -0.001]
angular_velocity = [0.0, 0.0, 0.0]
[[particles.block]]
origin = [0.008, 0.008, 0.006]
count = [2, 1, 1]
spacing = 0.004
radius = 0.0012
velocity = [0.0, 0.0, 0.0]
[lattice]
dx = 0.001
operator = "trt"
storage = "fp32"
kernel = "auto"
tau = 0.8
velocity_scale = 0.01
mach = 0.1
magic = 0.1875
max_tau_minus = 1.0
mrt = { e = 1.19, epsilon = 1.4, q = 1.2, pi = 1.4, m = 1.98 }
body_acceleration = [0.0, 0.0, 0.0]
check_interval = 100
ramp_time = 0.0
[lattice.faces]
x_min = "periodic"
x_max = "periodic"
y_min = "wall"
y_max = "wall"
z_min = "wall"
z_max = { type = "moving_wall", velocity = [0.001, 0.0, 0.0] }
[[lattice.solid_box]]
min = [0.0, 0.0, 0.0]
max = [0.016, 0.016, 0.002]
[dem]
dt = 1.0e-6
dt_divisor = 50.0
skin = 0.0005
particle_material = "glass"
domain_walls = true
domain_wall_material = "glass"
[[dem.material]]
name = "glass"
young_modulus = 5.0e6
poisson_ratio = 0.3
restitution = 0.9
friction = 0.5
rolling_friction = 0.1
density = 2500.0
[dem.contact]
preset = "liggghts"
normal = "linear"
tangential = "history"
rolling = "constant_torque"
normal_stiffness = 1000.0
normal_damping = 0.01
tangential_stiffness = 1000.0
tangential_damping = 0.01
impact_velocity = 0.1
damping_law = "liggghts"
clamp_normal_force = true
tangential_spring = "total"
wall_radius_factor = 1.0
coulomb_normal = "absolute"
lever_arm = "contact_point"
[[dem.plane]]
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
material = "glass"
[[dem.box]]
min = [0.0, 0.0, 0.0]
max = [0.016, 0.016, 0.016]
inside = true
material = "glass"
[[dem.insert]]
origin = [0.004, 0.012, 0.004]
count = [1, 1, 2]
spacing = 0.004
radius = [0.001, 0.0012]
jitter = 0.0001
velocity = [0.0, 0.0, 0.0]
seed = 7
material = "glass"
[[dem.csv]]
file = "CSV"
material = "glass"
[dem.output]
vtk = true
"#;

/// A fluid-only MRT lattice from `resolution` and `mach`, times in seconds, an inlet and an
/// outlet.
const FLUID_ONLY: &str = r#"
name = "full-fluid"
[domain]
min = [0.0, 0.0, 0.0]
max = [0.016, 0.016, 0.016]
[fluid]
density = 1000.0
dynamic_viscosity = 0.001
[time]
duration = 0.1
[output]
time_interval = 0.01
fields_time_interval = 0.05
checkpoint_time_interval = 0.05
[lattice]
resolution = 16
operator = "mrt"
velocity_scale = 0.01
mach = 0.1
[lattice.faces]
x_min = { type = "velocity_inlet", velocity = [0.001, 0.0, 0.0] }
x_max = { type = "pressure_outlet", pressure = 0.0 }
[parallel]
blocks = [1, 1, 2]
overlap = false
"#;

/// A granular scene alone: `time.dt` and a linear contact from its contact time.
const GRANULAR: &str = r#"
name = "full-granular"
[domain]
min = [0.0, 0.0, 0.0]
max = [0.01, 0.01, 0.01]
periodic = ["x", "y"]
[fluid]
density = 1.2
dynamic_viscosity = 1.8e-5
[time]
dt = 1.0e-4
steps = 10
[particles]
density = 2500.0
[[particles.sphere]]
position = [0.005, 0.005, 0.005]
radius = 0.001
[dem.contact]
normal = "linear"
contact_time = 0.001
"#;

/// The full scenes as TOML values, with [`COUPLED`]'s particle file written.
fn full_scenes() -> Vec<Value> {
    let csv = std::env::temp_dir().join(format!("scene-every-field-{}.csv", std::process::id()));
    std::fs::write(
        &csv,
        "x,y,z,r,vx,vy,vz,wx,wy,wz\n0.012,0.004,0.012,0.001,0,0,0,0,0,0\n",
    )
    .unwrap();
    let coupled = COUPLED.replace("CSV", &csv.display().to_string());
    [coupled.as_str(), FLUID_ONLY, GRANULAR]
        .iter()
        .map(|text| {
            let scene = Scene::parse(text, "full.toml");
            assert!(scene.is_ok(), "the full scene is valid: {scene:?}");
            text.parse::<Value>().unwrap()
        })
        .collect()
}

/// One step of a path into a TOML value: a key or an array index.
#[derive(Clone)]
enum Step {
    Key(String),
    Index(usize),
}

/// A path as scene messages write it: `particles.block[0].origin[2]`.
fn show(path: &[Step]) -> String {
    let mut out = String::new();
    for step in path {
        match step {
            Step::Key(k) if out.is_empty() => out.push_str(k),
            Step::Key(k) => out.push_str(&format!(".{k}")),
            Step::Index(i) => out.push_str(&format!("[{i}]")),
        }
    }
    out
}

/// The field a path names: the number itself, or the array it is a component of.
fn field_of(path: &[Step]) -> String {
    match path.last() {
        Some(Step::Index(_)) => show(&path[..path.len() - 1]),
        _ => show(path),
    }
}

/// Calls `visit` with every value under `value` (itself first) and its path.
fn walk(value: &Value, path: &mut Vec<Step>, visit: &mut impl FnMut(&[Step], &Value)) {
    visit(path, value);
    let children: Vec<(Step, &Value)> = match value {
        Value::Table(t) => t.iter().map(|(k, v)| (Step::Key(k.clone()), v)).collect(),
        Value::Array(a) => a.iter().enumerate().map(|(i, v)| (Step::Index(i), v)).collect(),
        _ => Vec::new(),
    };
    for (step, child) in children {
        path.push(step);
        walk(child, path, visit);
        path.pop();
    }
}

/// Every number of `scene`, with its path and whether it is an integer.
fn numbers(scene: &Value) -> Vec<(Vec<Step>, bool)> {
    let mut out = Vec::new();
    walk(scene, &mut Vec::new(), &mut |path, value| {
        if value.is_integer() || value.is_float() {
            out.push((path.to_vec(), value.is_integer()));
        }
    });
    out
}

fn at<'a>(value: &'a mut Value, path: &[Step]) -> &'a mut Value {
    path.iter().fold(value, |v, step| match step {
        Step::Key(k) => &mut v[k.as_str()],
        Step::Index(i) => &mut v[*i],
    })
}

/// `scene` with the number at `path` replaced by `number`, parsed as `lbm-server run` does (a
/// panic becomes an error that names no field).
fn parse_with(scene: &Value, path: &[Step], number: Value) -> Result<Scene, crate::SceneError> {
    let mut changed = scene.clone();
    *at(&mut changed, path) = number;
    let text = toml::to_string(&changed).unwrap();
    let shown = show(path);
    std::panic::catch_unwind(|| Scene::parse(&text, "full.toml")).unwrap_or_else(|_| {
        Err(crate::SceneError {
            file: "full.toml".into(),
            field: "<panic>".into(),
            value: shown,
            problem: "the checks panicked".into(),
        })
    })
}

/// Every floating-point number of the full scenes, made NaN, inf or -inf, is refused naming its
/// field and the value.
#[test]
fn a_number_that_is_not_finite_is_refused_naming_its_field() {
    let mut failures = Vec::new();
    for scene in full_scenes() {
        for (path, integer) in numbers(&scene) {
            for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                let (field, shown) = (field_of(&path), show(&path));
                match parse_with(&scene, &path, Value::Float(bad)) {
                    Ok(_) => failures.push(format!("{shown} = {bad}: accepted")),
                    // An integer field cannot hold it: the parser refuses it.
                    Err(e) if integer && e.field.is_empty() && e.problem.contains("invalid type") => {}
                    Err(e) => {
                        let named = e.field == field || e.field.starts_with(&format!("{field}["));
                        let valued = e.value.contains(if bad.is_nan() { "NaN" } else { "inf" });
                        if !(named && valued) {
                            failures.push(format!("{shown} = {bad}: {e}"));
                        }
                    }
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The integers that may be 0 or huge (a huge interval or seed is no mistake).
const ANY_INTEGER: &[(&str, i64)] = &[
    ("output.fields_interval", 0),
    ("output.fields_interval", i64::MAX),
    ("output.interval", i64::MAX),
    ("output.checkpoint_interval", 0),
    ("output.checkpoint_interval", i64::MAX),
    ("lattice.check_interval", i64::MAX),
    ("dem.insert[0].seed", 0),
    ("dem.insert[0].seed", i64::MAX),
];

/// Every integer of the full scenes, made 0 or the largest TOML integer, is refused naming its
/// field (or by the parser, where the field's type cannot hold it), unless [`ANY_INTEGER`]
/// allows it; none panics.
#[test]
fn an_integer_out_of_range_is_refused_naming_its_field() {
    let mut failures = Vec::new();
    for scene in full_scenes() {
        for (path, _) in numbers(&scene).into_iter().filter(|(_, integer)| *integer) {
            for bad in [0, i64::MAX] {
                let (field, shown) = (field_of(&path), show(&path));
                match parse_with(&scene, &path, Value::Integer(bad)) {
                    Ok(_) if ANY_INTEGER.contains(&(shown.as_str(), bad)) => {}
                    Ok(_) => failures.push(format!("{shown} = {bad}: accepted")),
                    Err(e) if e.field.is_empty() && e.problem.contains("invalid value") => {}
                    Err(e) if e.field == field || e.field.starts_with(&format!("{field}[")) => {}
                    Err(e) => failures.push(format!("{shown} = {bad}: {e}")),
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A table's path without array indices; the faces' tables (an untagged enum, whose fields no
/// error lists) as `lattice.faces.*`.
fn table_kind(path: &[Step]) -> String {
    let keys: Vec<&str> = path
        .iter()
        .filter_map(|s| match s {
            Step::Key(k) => Some(k.as_str()),
            Step::Index(_) => None,
        })
        .collect();
    match keys.as_slice() {
        ["lattice", "faces", _] => "lattice.faces.*".into(),
        _ => keys.join("."),
    }
}

/// Every table of `scene`: (kind, a path to one, its keys).
fn tables(scene: &Value) -> Vec<(String, Vec<Step>, Vec<String>)> {
    let mut out = Vec::new();
    walk(scene, &mut Vec::new(), &mut |path, value| {
        if let Value::Table(t) = value {
            out.push((table_kind(path), path.to_vec(), t.keys().cloned().collect()));
        }
    });
    out
}

/// The fields an unknown-field error lists (`expected one of `a`, `b``).
fn listed_fields(problem: &str) -> Vec<String> {
    let (_, rest) = problem
        .split_once("unknown field `zzz_unknown`")
        .unwrap_or_else(|| panic!("not an unknown-field error: {problem}"));
    let line = rest.lines().next().unwrap_or("");
    line.split('`').skip(1).step_by(2).map(String::from).collect()
}

/// The fields the scene format has in a table of `kind`, as the parser lists them for an unknown
/// key put into the table at `path` of `scene`.
fn format_fields(scene: &Value, kind: &str, path: &[Step]) -> Vec<String> {
    let problem = if kind == "lattice.faces.*" {
        let e = toml::from_str::<crate::lattice::FaceTable>("zzz_unknown = 1").unwrap_err();
        e.to_string()
    } else {
        let mut changed = scene.clone();
        let table = at(&mut changed, path).as_table_mut().expect("a table");
        table.insert("zzz_unknown".into(), Value::Integer(1));
        let text = toml::to_string(&changed).unwrap();
        Scene::parse(&text, "full.toml").expect_err(kind).problem
    };
    listed_fields(&problem)
}

/// The full scenes give every field of every table of the scene format, so that the tests
/// above reach every number.
#[test]
fn the_full_scenes_give_every_field() {
    let scenes = full_scenes();
    let mut given: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    let mut one: BTreeMap<String, (usize, Vec<Step>)> = BTreeMap::new();
    for (s, scene) in scenes.iter().enumerate() {
        for (kind, path, keys) in tables(scene) {
            given.entry(kind.clone()).or_default().extend(keys);
            one.entry(kind).or_insert((s, path));
        }
    }
    let mut missing = Vec::new();
    for (kind, (s, path)) in &one {
        for field in format_fields(&scenes[*s], kind, path) {
            if !given[kind].contains(&field) {
                missing.push(format!("{kind}.{field}"));
            }
        }
    }
    assert!(given.len() >= 20, "{} tables", given.len());
    assert!(missing.is_empty(), "give these in a full scene: {missing:?}");
}
