//! LIGGGHTS as the DEM of a coupled run (clients/liggghts/): it settles a sphere as the built-in
//! DEM does, the fluid's force and torque act on its atoms as held, and decks that cannot join a
//! run are refused with exit status 2. Where LIGGGHTS is not installed the tests that need it say
//! that they were skipped and why, and pass.

mod common;
use common::*;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::Duration;

const ADAPTER: &str = LIGGGHTS_ADAPTER;
const CHECK_LOADS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/clients/liggghts/check_loads.py");
const DECK: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/clients/liggghts/ten_cate_e1.in");

/// Ten Cate E1's sphere and liquid (validation/scenes/ten-cate-e1.toml, 6 cells per diameter) in
/// a smaller box, 20 x 20 x 32 cells, for `steps` steps.
fn settling_scene(steps: u64) -> String {
    format!(
        r#"name = "liggghts-settling"
gravity = [0.0, 0.0, -9.81]
[domain]
min = [0.0, 0.0, 0.0]
max = [0.05, 0.05, 0.08]
[fluid]
density = 970.0
dynamic_viscosity = 0.373
[time]
steps = {steps}
[lattice]
dx = 0.0025
operator = "trt"
velocity_scale = 0.038
mach = 0.1
[output]
interval = 1
[particles]
density = 1120.0
[[particles.sphere]]
position = [0.025, 0.025, 0.06]
radius = 0.0075
"#
    )
}

/// A Couette flow along x between the floor and a lid at 0.01 m/s, 16 mm above it (16^3 cells,
/// periodic along x and y), with a neutrally buoyant sphere of radius 2 mm at its centre; no
/// gravity; 1000 steps of 0.1 ms (the flow develops in about 0.03 s).
const SHEAR_SCENE: &str = r#"name = "liggghts-shear"
gravity = [0.0, 0.0, 0.0]
[domain]
min = [0.0, 0.0, 0.0]
max = [0.016, 0.016, 0.016]
[fluid]
density = 1000.0
dynamic_viscosity = 1.0
[time]
steps = 1000
[lattice]
dx = 0.001
tau = 0.8
velocity_scale = 0.01
[lattice.faces]
x_min = "periodic"
x_max = "periodic"
y_min = "periodic"
y_max = "periodic"
z_min = "wall"
z_max = { type = "moving_wall", velocity = [0.01, 0.0, 0.0] }
[output]
interval = 50
[particles]
density = 1000.0
[[particles.sphere]]
position = [0.008, 0.008, 0.008]
radius = 0.002
"#;

/// The sphere of `SHEAR_SCENE` as a LIGGGHTS deck: periodic along x and y, no gravity, no walls
/// (it touches nothing).
fn shear_deck() -> PathBuf {
    let deck = "units si\natom_style granular\natom_modify map array\nboundary p p f\nnewton off\n\
                communicate single vel yes\nregion domain block 0.0 0.016 0.0 0.016 0.0 0.016 units box\n\
                create_box 1 domain\nneighbor 0.001 bin\n\
                fix m1 all property/global youngsModulus peratomtype 5.0e6\n\
                fix m2 all property/global poissonsRatio peratomtype 0.3\n\
                fix m3 all property/global coefficientRestitution peratomtypepair 1 0.9\n\
                fix m4 all property/global coefficientFriction peratomtypepair 1 0.5\n\
                pair_style gran model hertz tangential history\npair_coeff * *\ntimestep 1e-5\n\
                create_atoms 1 single 0.008 0.008 0.008 units box\n\
                set atom 1 diameter 0.004 density 1000.0\nfix integr all nve/sphere\n";
    let path = temp_dir("liggghts-shear-deck").join("shear.in");
    std::fs::write(&path, deck).unwrap();
    path
}

/// The deck's variables for the box and sphere of `settling_scene`.
const SETTLING_VARS: [(&str, &str); 6] = [
    ("lx", "0.05"),
    ("ly", "0.05"),
    ("lz", "0.08"),
    ("x0", "0.025"),
    ("y0", "0.025"),
    ("z0", "0.06"),
];

/// Runs the adapter in `dir` (its log there) against run `run`.
fn adapter(dir: &Path, run: &str, scene: &Path, deck: &Path, vars: &[(&str, &str)]) -> Command {
    let mut cmd = Command::new("python3");
    cmd.arg(ADAPTER)
        .args(["--service", run, "--timeout", "30"])
        .arg("--scene")
        .arg(scene)
        .arg("--deck")
        .arg(deck)
        .arg("--log")
        .arg(dir.join("log.liggghts"))
        .env("PYTHONPATH", PYTHON_CLIENTS)
        .current_dir(dir);
    for (name, value) in vars {
        cmd.args(["--var", name, value]);
    }
    cmd
}

/// The largest settling speed (-vz) in a run's particles.csv.
fn peak_settling_speed(out: &Path) -> f64 {
    particle_rows(out).iter().map(|r| -r[8]).fold(f64::MIN, f64::max)
}

fn text(output: &Output) -> String {
    output_text(output)
}

/// Runs `scene_text` with the built-in DEM, then with LIGGGHTS on `deck` (with `vars`); both must
/// complete every step. Returns the two output folders and what the adapter said.
fn both_dems(tag: &str, scene_text: &str, deck: &Path, vars: &[(&str, &str)]) -> (PathBuf, PathBuf, String) {
    let dir = temp_dir(tag);
    let scene = write_scene(&dir, scene_text);
    let builtin_out = dir.join("builtin");
    let builtin = server(&scene, &builtin_out, &[])
        .output()
        .expect("lbm-server runs");
    assert!(builtin.status.success(), "built-in DEM run:\n{}", text(&builtin));

    let out = dir.join("liggghts");
    let (mut server, run) = start_external(&scene, &out);
    let client = adapter(&dir, &run, &scene, deck, vars)
        .output()
        .expect("python3 runs");
    assert!(client.status.success(), "adapter failed:\n{}", text(&client));
    let (code, _) = server.wait_exit(Duration::from_secs(60));
    assert_eq!(code, Some(0), "{}", Proc::drain(&server.stderr));
    let s = summary(&out);
    assert_eq!(s["steps_completed"], summary(&builtin_out)["steps_completed"]);
    assert!(
        s["peer"]["software"].as_str().unwrap().contains("LIGGGHTS"),
        "{s}"
    );
    assert!(leftover_files(&run).is_empty(), "{:?}", leftover_files(&run));
    (builtin_out, out, text(&client))
}

/// Prints `what` from both DEMs and asserts that LIGGGHTS's is within 0.5% of the built-in DEM's.
fn same_within_half_a_percent(what: &str, builtin: f64, liggghts: f64) {
    eprintln!("{what}: built-in DEM {builtin}, LIGGGHTS {liggghts}");
    assert!(
        (liggghts - builtin).abs() <= 0.005 * builtin.abs(),
        "{what}: LIGGGHTS {liggghts}, built-in DEM {builtin}"
    );
}

/// Ten Cate E1's sphere settles as fast with LIGGGHTS (clients/liggghts/ten_cate_e1.in) as with
/// the built-in DEM on the same scene: their peak speeds within 0.5%. Both see the same held
/// fluid force over the fluid step, integrated exactly in free flight (the built-in DEM in one
/// exact step, LIGGGHTS in 152 velocity-Verlet steps), so they agree far closer than that.
#[test]
fn liggghts_settles_a_sphere_as_the_builtin_dem_does() {
    if !liggghts_present("liggghts_settles_a_sphere_as_the_builtin_dem_does") {
        return;
    }
    let steps = 120;
    let (builtin, liggghts, said) = both_dems(
        "liggghts-settling",
        &settling_scene(steps),
        Path::new(DECK),
        &SETTLING_VARS,
    );
    assert!(
        said.contains(&format!("completed {steps} steps, 1 atoms")),
        "{said}"
    );
    assert!(said.contains("(fluid step / 152)"), "{said}");
    let reference = peak_settling_speed(&builtin);
    assert!(reference > 0.02, "the sphere settles: {reference} m/s");
    same_within_half_a_percent(
        "peak settling speed [m/s]",
        reference,
        peak_settling_speed(&liggghts),
    );
}

/// A neutrally buoyant sphere midway in a Couette flow (periodic along x and y, the lid moving
/// at 0.01 m/s over 16 mm: shear rate 0.625 /s) spins at half the shear rate, about y. The
/// torque path: the fluid's torque held over LIGGGHTS's steps (added to the atoms' torque in
/// fix external's callback) spins it as the built-in DEM does, within 0.5%, and near 0.3125
/// rad/s (within 3%).
#[test]
fn liggghts_spins_a_sphere_in_shear_as_the_builtin_dem_does() {
    if !liggghts_present("liggghts_spins_a_sphere_in_shear_as_the_builtin_dem_does") {
        return;
    }
    let (builtin, liggghts, said) = both_dems("liggghts-shear", SHEAR_SCENE, &shear_deck(), &[]);
    assert!(said.contains("periodic along ['x', 'y']"), "{said}");
    let spin = |out: &Path| particle_rows(out).last().expect("rows")[10];
    let reference = spin(&builtin);
    assert!(
        (reference - 0.3125).abs() <= 0.03 * 0.3125,
        "half the shear rate: {reference}"
    );
    same_within_half_a_percent("spin in shear [rad/s]", reference, spin(&liggghts));
}

/// A force and a torque held over LIGGGHTS's steps (fix external and the atoms' torque, changed
/// between the spans as the coupled loop changes them) accelerate a sphere at F/m and spin it
/// at T/I exactly (clients/liggghts/check_loads.py).
#[test]
fn liggghts_atoms_feel_the_held_force_and_torque() {
    if !liggghts_present("liggghts_atoms_feel_the_held_force_and_torque") {
        return;
    }
    let dir = temp_dir("liggghts-loads");
    let check = Command::new("python3")
        .arg(CHECK_LOADS)
        .current_dir(&dir)
        .output()
        .expect("python3 runs");
    let said = text(&check);
    assert!(check.status.success(), "{said}");
    assert!(said.contains("force and torque act as held"), "{said}");
}

/// Refused with exit status 2 and a message naming the problem, before anything is shared.
fn refused(tag: &str, deck_text: Option<&str>, env: &[(&str, &str)], expected: &[&str]) {
    let dir = temp_dir(tag);
    let scene = write_scene(&dir, &settling_scene(10));
    let deck = match deck_text {
        Some(t) => {
            let path = dir.join("deck.in");
            std::fs::write(&path, t).unwrap();
            path
        }
        None => Path::new(DECK).to_path_buf(),
    };
    let run = format!("lbmdem_{}_refused", std::process::id());
    let mut cmd = adapter(&dir, &run, &scene, &deck, &SETTLING_VARS);
    cmd.envs(env.iter().copied());
    let output = cmd.output().expect("python3 runs");
    let said = text(&output);
    assert_eq!(output.status.code(), Some(2), "{tag}: {said}");
    for needle in expected {
        assert!(said.contains(needle), "{tag}: no {needle:?} in:\n{said}");
    }
    assert!(leftover_files(&run).is_empty(), "{:?}", leftover_files(&run));
}

/// The example deck with `extra` commands at its end.
fn deck_with(extra: &str) -> String {
    std::fs::read_to_string(DECK).unwrap() + extra
}

#[test]
fn without_liggghts_the_adapter_says_how_to_install_it() {
    refused(
        "liggghts-missing",
        None,
        &[("LIGGGHTS_LIBRARY", "/nonexistent/libliggghts.so.3")],
        &["LIGGGHTS is not installed", "apt-get install liggghts"],
    );
}

#[test]
fn decks_whose_atoms_are_not_the_scenes_particles_are_refused() {
    if !liggghts_present("decks_whose_atoms_are_not_the_scenes_particles_are_refused") {
        return;
    }
    let atomic = "units si\natom_style atomic\nregion domain block 0 0.05 0 0.05 0 0.08 units box\n\
                  create_box 1 domain\nmass 1 0.001\ncreate_atoms 1 single 0.025 0.025 0.06 units box\n";
    refused(
        "liggghts-atomic",
        Some(atomic),
        &[],
        &["has no per-atom radius, omega", "atom_style granular"],
    );
    let second = "create_atoms 1 single 0.01 0.01 0.01 units box\nset atom 2 diameter 0.005 density 1120\n";
    refused(
        "liggghts-count",
        Some(&deck_with(second)),
        &[],
        &["creates 2 atoms, the scene", "has 1 particle:"],
    );
    let renumbered = format!("{second}group first id 1\ndelete_atoms group first compress no\n");
    refused(
        "liggghts-ids",
        Some(&deck_with(&renumbered)),
        &[],
        &["atom ID 2 of", "has no particle in the scene"],
    );
    refused(
        "liggghts-typo",
        Some(&deck_with("fixx oops all nve/sphere\n")),
        &[],
        &["failed: ERROR: Unknown command: fixx oops"],
    );
}

/// `lbm-server run SCENE --dem liggghts` in one command: the deck written from the scene
/// (OUT/dem.liggghts.in: the sphere from the scene reader, the domain's faces as walls, Hertz)
/// settles the sphere as the built-in DEM does, peak speeds within 0.5%.
#[test]
fn dem_liggghts_in_one_command_settles_a_sphere_as_the_builtin_dem_does() {
    let test = "dem_liggghts_in_one_command_settles_a_sphere_as_the_builtin_dem_does";
    if !liggghts_present(test) {
        return;
    }
    let dir = temp_dir("dem-liggghts");
    let scene = write_scene(&dir, &settling_scene(120));
    let builtin_out = dir.join("builtin");
    let builtin = server(&scene, &builtin_out, &[])
        .output()
        .expect("lbm-server runs");
    assert!(builtin.status.success(), "built-in DEM run:\n{}", text(&builtin));
    let out = dir.join("liggghts");
    let mut fluid = start(server(&scene, &out, &["--dem", "liggghts"]));
    let (code, _) = fluid.wait_exit(Duration::from_secs(300));
    let said = Proc::drain(&fluid.stdout) + &Proc::drain(&fluid.stderr);
    assert_eq!(code, Some(0), "{said}");
    let deck = std::fs::read_to_string(out.join("dem.liggghts.in")).expect("the deck is in OUT");
    assert!(
        deck.contains("pair_style gran model hertz tangential history"),
        "{deck}"
    );
    assert!(deck.contains("zplane 0.08"), "{deck}");
    let s = summary(&out);
    assert_eq!(s["steps_completed"], 120);
    assert!(
        s["peer"]["software"].as_str().unwrap().contains("LIGGGHTS"),
        "{s}"
    );
    same_within_half_a_percent(
        "peak settling speed [m/s]",
        peak_settling_speed(&builtin_out),
        peak_settling_speed(&out),
    );
    let run = format!("lbmdem_{}_", fluid.child.id());
    assert!(leftover_files(&run).is_empty(), "{:?}", leftover_files(&run));
}

/// `--dem liggghts` where LIGGGHTS cannot be loaded: exit 2 before the fluid starts, saying how to
/// install it.
#[test]
fn dem_liggghts_without_liggghts_says_how_to_install_it() {
    let dir = temp_dir("dem-liggghts-missing");
    let scene = write_scene(&dir, &settling_scene(10));
    let run = server(&scene, &dir.join("out"), &["--dem", "liggghts"])
        .env("LIGGGHTS_LIBRARY", "/nonexistent/libliggghts.so.3")
        .output()
        .expect("lbm-server runs");
    let said = text(&run);
    assert_eq!(run.status.code(), Some(2), "{said}");
    assert!(said.contains("LIGGGHTS is not installed"), "{said}");
    assert!(said.contains("apt-get install liggghts"), "{said}");
    assert!(!said.contains("DEM:"), "nothing ran: {said}");
}
