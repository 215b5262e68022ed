//! Cross-DEM checks (validation/crossdem/): the default scene with contacts settles alike with the
//! built-in DEM, LIGGGHTS and YADE, each started by `lbm-server run --dem ...`; and a DEM the run
//! starts that refuses its input (LIGGGHTS or YADE missing, a deck whose atoms lack radius or
//! omega, atoms or bodies that are not the scene's particles) ends the run with a clear message,
//! exit status 2, no process and no shared-memory file left; and the LIGGGHTS adapter's compiled
//! loads (clients/native) act as its Python loads do. Where LIGGGHTS or YADE is absent the tests
//! that need it say that they were skipped and why, and pass.

mod common;
use common::*;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const YADE_CLIENT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/clients/yade");
/// Where .ci/run installs iceoryx2 for Debian's python (YADE's).
const YADE_IOX: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/target/yade-py");

/// Says why a test is skipped, on stderr itself: the test harness captures `eprintln!`.
fn skipped(why: &str) {
    use std::io::Write;
    let _ = writeln!(std::io::stderr().lock(), "{why}");
}

/// Whether YADE and iceoryx2 for its python are here; where not, says that `test` was skipped.
fn yade_present(test: &str) -> bool {
    let found = Command::new("/usr/bin/python3")
        .args(["-c", "import iceoryx2"])
        .env("PYTHONPATH", YADE_IOX)
        .output()
        .is_ok_and(|o| o.status.success());
    if launch_path("yade").is_some() && found {
        return true;
    }
    skipped(&format!(
        "{test}: skipped: YADE or iceoryx2 for /usr/bin/python3 is missing (sh validation/dem/install.sh; \
         /usr/bin/python3 -m pip install --target {YADE_IOX} iceoryx2==0.10.0)"
    ));
    false
}

fn launch_path(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join(name))
        .find(|p| p.is_file())
}

/// `lbm-server run SCENE --steps N --dem DEM`, to completion (YADE's iceoryx2 on PYTHONPATH).
fn run_with(scene: &Path, out: &Path, steps: u64, extra: &[&str]) -> Output {
    let steps = steps.to_string();
    let mut args = vec!["--steps", steps.as_str()];
    args.extend_from_slice(extra);
    server(scene, out, &args)
        .env("PYTHONPATH", YADE_IOX)
        .output()
        .expect("lbm-server runs")
}

/// The mean height of the particles at the last step of a run's particles.csv.
fn final_mean_height(out: &Path) -> f64 {
    let rows = particle_rows(out);
    let last = rows.iter().map(|r| r[0]).fold(f64::MIN, f64::max);
    let z: Vec<f64> = rows.iter().filter(|r| r[0] == last).map(|r| r[5]).collect();
    z.iter().sum::<f64>() / z.len() as f64
}

/// The default scene (27 beads onto the floor and each other) cut to 400 steps (0.225 s: the
/// lowest layer has landed, the upper ones land on it): the mean height with LIGGGHTS and YADE
/// within 0.5% of the built-in DEM's (validation/crossdem/REPORT.md has the whole run).
#[test]
fn the_default_scene_settles_alike_with_each_dem() {
    let test = "the_default_scene_settles_alike_with_each_dem";
    let scene = Path::new(ROOT).join("validation/scenes/default.toml");
    let dir = temp_dir("crossdem-default");
    let builtin = run_with(&scene, &dir.join("builtin"), 400, &[]);
    assert!(builtin.status.success(), "{}", output_text(&builtin));
    let reference = final_mean_height(&dir.join("builtin"));
    for dem in ["liggghts", "yade"] {
        let present = match dem {
            "liggghts" => liggghts_present(test),
            _ => yade_present(test),
        };
        if !present {
            continue;
        }
        let out = dir.join(dem);
        let run = run_with(&scene, &out, 400, &["--dem", dem]);
        assert!(run.status.success(), "{dem}: {}", output_text(&run));
        let z = final_mean_height(&out);
        eprintln!("{test}: mean height at step 399: built-in {reference:.7e} m, {dem} {z:.7e} m");
        assert!(
            (z / reference - 1.0).abs() < 0.005,
            "{dem}: {z} m against the built-in DEM's {reference} m"
        );
    }
}

/// `lbm-server run --dem-command CMD` where CMD refuses its input: exit 2 with its message and the
/// server's, the DEM gone, no shared-memory file of the run left.
fn refused_run(tag: &str, scene: &Path, command: &str, expected: &[&str]) {
    let dir = temp_dir(tag);
    let pid_file = dir.join("dem.pid");
    let line = format!("echo $$ > {}; exec {command}", pid_file.display());
    let child = server(
        scene,
        &dir.join("out"),
        &["--steps", "20", "--dem-command", &line],
    )
    .current_dir(&dir)
    .env("PYTHONPATH", format!("{YADE_IOX}:{PYTHON_CLIENTS}:{YADE_CLIENT}"))
    .stdout(std::process::Stdio::piped())
    .stderr(std::process::Stdio::piped())
    .spawn()
    .expect("lbm-server runs");
    let run = format!("lbmdem_{}_", child.id());
    let output = child.wait_with_output().expect("lbm-server ends");
    let said = output_text(&output);
    assert_eq!(output.status.code(), Some(2), "{tag}: {said}");
    for needle in expected
        .iter()
        .chain(&["lbm-server: error: the DEM refused its input"])
    {
        assert!(said.contains(needle), "{tag}: no {needle:?} in:\n{said}");
    }
    let pid: u32 = std::fs::read_to_string(&pid_file)
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    assert!(is_gone(pid), "{tag}: the DEM {pid} is still running");
    let s = summary(&dir.join("out"));
    assert!(
        s["exit_reason"].as_str().unwrap().contains("refused its input"),
        "{tag}: {s}"
    );
    assert!(
        leftover_files(&run).is_empty(),
        "{tag}: {:?}",
        leftover_files(&run)
    );
}

/// Ten Cate E1's sphere in a 20 x 20 x 32 box, as tests/liggghts_client.rs's settling scene.
fn one_sphere_scene(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(Path::new(ROOT).join("validation/scenes/ten-cate-e1.toml"))
        .unwrap()
        .replace("max = [0.1, 0.1, 0.16]", "max = [0.05, 0.05, 0.08]")
        .replace(
            "position = [0.05, 0.05, 0.1275]",
            "position = [0.025, 0.025, 0.06]",
        );
    write_scene(dir, &text)
}

/// A LIGGGHTS deck of the scene's sphere with `extra` after it.
fn deck(dir: &Path, style: &str, extra: &str) -> PathBuf {
    let text = format!(
        "units si\natom_style {style}\natom_modify map array\nboundary f f f\n\
         region domain block 0 0.05 0 0.05 0 0.08 units box\ncreate_box 1 domain\n\
         {extra}timestep 1e-5\n"
    );
    std::fs::create_dir_all(dir).unwrap();
    let path = dir.join("deck.in");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn a_dem_command_that_refuses_its_input_ends_the_run_with_exit_2() {
    let dir = temp_dir("crossdem-refuses");
    let scene = one_sphere_scene(&dir);
    refused_run(
        "crossdem-exit-2",
        &scene,
        "sh -c 'echo my-dem: error: no such material >&2; exit 2'",
        &["my-dem: error: no such material"],
    );
}

#[test]
fn liggghts_decks_that_do_not_fit_the_scene_end_the_run_with_exit_2() {
    let test = "liggghts_decks_that_do_not_fit_the_scene_end_the_run_with_exit_2";
    if !liggghts_present(test) {
        return;
    }
    let dir = temp_dir("crossdem-decks");
    let scene = one_sphere_scene(&dir);
    let sphere = "create_atoms 1 single 0.025 0.025 0.06 units box\n";
    let granular = "set atom * diameter 0.015 density 1120\nfix integr all nve/sphere\n";
    let cases = [
        (
            "atomic",
            deck(&dir.join("atomic"), "atomic", &format!("mass 1 0.001\n{sphere}")),
            "has no per-atom radius, omega",
        ),
        (
            "count",
            deck(
                &dir.join("count"),
                "granular",
                &format!("{sphere}create_atoms 1 single 0.01 0.01 0.01 units box\n{granular}"),
            ),
            "creates 2 atoms, the scene",
        ),
        (
            "ids",
            deck(
                &dir.join("ids"),
                "granular",
                &format!(
                    "create_atoms 1 single 0.01 0.01 0.01 units box\n{sphere}{granular}\
                          group first id 1\ndelete_atoms group first compress no\n"
                ),
            ),
            "atom ID 2 of",
        ),
    ];
    for (tag, deck, message) in cases {
        let command = format!("python3 {LIGGGHTS_ADAPTER} --deck {} --log none", deck.display());
        refused_run(&format!("crossdem-deck-{tag}"), &scene, &command, &[message]);
    }
}

/// A YADE script whose spheres are not the scene's particles (two where the scene has one; a
/// body id the scene does not have).
const MISFIT_YADE: &str = r#"import sys
import lbmdem_yade
case = sys.argv[-2]
O.materials.append(FrictMat(young=5e6, density=1120))
O.bodies.append(sphere((0.025, 0.025, 0.06), 0.0075))
if case == "count":
    O.bodies.append(sphere((0.01, 0.01, 0.01), 0.0075))
O.engines = [ForceResetter(), NewtonIntegrator(damping=0.0, gravity=(0, 0, -9.81))]
O.dt = 1e-4
lbmdem_yade.couple(scene=sys.argv[-1], ids={3: 0} if case == "ids" else None, max_dt=1e-3)
"#;

#[test]
fn yade_scripts_that_do_not_fit_the_scene_end_the_run_with_exit_2() {
    let test = "yade_scripts_that_do_not_fit_the_scene_end_the_run_with_exit_2";
    if !yade_present(test) {
        return;
    }
    let dir = temp_dir("crossdem-yade");
    let scene = one_sphere_scene(&dir);
    let script = dir.join("misfit.py");
    std::fs::write(&script, MISFIT_YADE).unwrap();
    for (case, message) in [
        ("count", "YADE couples 2 spheres, the scene"),
        ("ids", "which the scene"),
    ] {
        let command = format!("yade -n -x {} {case} {}", script.display(), scene.display());
        refused_run(&format!("crossdem-yade-{case}"), &scene, &command, &[message]);
    }
}

#[test]
fn dem_yade_without_yade_says_how_to_install_it() {
    let dir = temp_dir("crossdem-no-yade");
    let scene = one_sphere_scene(&dir);
    let output = server(&scene, &dir.join("out"), &["--dem", "yade"])
        .env("PATH", "/nonexistent")
        .output()
        .expect("lbm-server runs");
    let said = output_text(&output);
    assert_eq!(output.status.code(), Some(2), "{said}");
    assert!(said.contains("YADE is not installed"), "{said}");
    assert!(said.contains("apt-get install yade python3-yade"), "{said}");
    assert!(!said.contains("lbm-server: scene '"), "nothing ran: {said}");
}

/// The LIGGGHTS adapter's compiled loads (clients/native) move the atoms as its Python loads do:
/// held to the bit, following the atoms (the sub-step drag and the squeeze films) within 1e-9,
/// LIGGGHTS reordering its atoms within a fluid step (clients/liggghts/check_native.py); and a
/// held force and torque act exactly from step 0 (check_loads.py --native). Skipped where
/// LIGGGHTS or the native helper (`cargo build -p lbmdem-native`) is missing.
#[test]
fn liggghts_native_loads_are_the_python_adapters() {
    let test = "liggghts_native_loads_are_the_python_adapters";
    if !liggghts_present(test) {
        return;
    }
    let clients = Path::new(ROOT).join("clients/liggghts");
    let path = format!("{PYTHON_CLIENTS}:{}", clients.display());
    for (script, args, said_ok) in [
        ("check_native.py", &[][..], "the native loads are the adapter's"),
        (
            "check_loads.py",
            &["--native"][..],
            "force and torque act as held",
        ),
    ] {
        let check = Command::new("python3")
            .arg(clients.join(script))
            .args(args)
            .current_dir(temp_dir("crossdem-native"))
            .env("PYTHONPATH", &path)
            .output()
            .expect("python3 runs");
        let said = output_text(&check);
        if check.status.code() == Some(2) {
            skipped(&format!("{test}: skipped: {}", said.trim()));
            return;
        }
        assert!(check.status.success(), "{script}: {said}");
        assert!(said.contains(said_ok), "{script}: {said}");
    }
}
