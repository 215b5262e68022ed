//! What a coupled scene (fluid and particles) run through `lbm-server run` writes and says: the
//! fields and summary.json (the default scene's time split), the same particles.csv every run and
//! every way of treating the covered cells (crowded beads, timed ways), the terminal's header
//! and warnings.

mod common;
use common::*;
use std::path::Path;

/// A coupled run writes the fluid's fields where the scene asks (`output.fields_interval`, and its
/// probe lines every `output.interval` steps), as a fluid run does; in the cells a settling sphere
/// of 12 cells covers, the liquid moves with it (1.3% slower at its centre: the cells near the
/// surface, partly covered, carry the liquid's velocity inwards; 12% slower for a sphere of 6 cells).
#[test]
fn a_coupled_run_writes_the_fields_the_scene_asks_for() {
    let (code, err, out) = run_scene("coupled-fields", SPHERE_FIELDS);
    assert_eq!(code, Some(0), "{err}");
    let pvd = std::fs::read_to_string(out.join("fields.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), 2, "steps 50 and 100: {pvd}");
    let vti = std::fs::read(out.join("fields/step000000100.vti")).unwrap();
    assert!(
        vti.len() > 16 * 32 * 32 * 32,
        "density and velocity of 32^3 cells present"
    );
    let rows = csv_numbers(&out.join("line0.csv"));
    assert_eq!(rows.len(), 4 * 32, "steps 25, 50, 75 and 100, 32 cells each");
    // The sphere's last state (step 99), far from the walls, against the line's cell nearest its
    // centre after step 100.
    let sphere = particle_rows(&out).last().unwrap().clone();
    let (z, vz) = (sphere[5], sphere[8]);
    assert!(vz < -1e-3, "the sphere settles: vz {vz} m/s");
    let at_centre = rows
        .iter()
        .filter(|r| r[0] == 100.0)
        .min_by(|a, b| (a[2] - z).abs().total_cmp(&(b[2] - z).abs()))
        .unwrap();
    let uz = at_centre[6];
    assert!(
        (uz - vz).abs() < 0.03 * vz.abs(),
        "liquid at the sphere's centre {uz} m/s, the sphere {vz} m/s"
    );
    let far = rows
        .iter()
        .filter(|r| r[0] == 100.0)
        .map(|r| r[6].abs())
        .fold(0.0, f64::max);
    assert!(
        far < 2.0 * vz.abs(),
        "no cell of the line faster than twice the sphere: {far}"
    );
    // The particles for ParaView (`dem.output.vtk`, on by default) at the steps of particles.csv,
    // with the fluid's force as particles.csv has it.
    let pvd = std::fs::read_to_string(out.join("particles.pvd")).unwrap();
    let steps = csv_steps(&out);
    assert_eq!(pvd.matches("<DataSet").count(), steps.len(), "{pvd}");
    let fz = vtp_force_z(&out, *steps.keys().last().unwrap());
    assert_eq!(fz, sphere[14], "the vtp's fluid force against particles.csv's");
}

/// The scene of [`a_coupled_run_writes_the_fields_the_scene_asks_for`]: a sphere of 12 cells
/// settling in a box of 32^3 cells, fields every 50 steps and a probe line along z through it.
const SPHERE_FIELDS: &str = "name = \"sphere-fields\"\ngravity = [0.0, 0.0, -9.81]\n[domain]\nmin = [0.0, 0.0, 0.0]\n\
                 max = [0.08, 0.08, 0.08]\n[fluid]\ndensity = 970.0\ndynamic_viscosity = 0.373\n[time]\n\
                 steps = 100\n[lattice]\ndx = 0.0025\noperator = \"trt\"\nvelocity_scale = 0.038\nmach = 0.1\n\
                 [output]\ninterval = 25\nfields_interval = 50\n\
                 [[output.line]]\naxis = \"z\"\nthrough = [0.04, 0.04, 0.0]\n\
                 [particles]\ndensity = 1120.0\n[[particles.sphere]]\nposition = [0.04, 0.04, 0.045]\n\
                 radius = 0.015\n";

/// The z component of the fluid's force on the first particle in the ParaView file of `step`.
fn vtp_force_z(out: &Path, step: u64) -> f64 {
    let vtp = std::fs::read_to_string(out.join(format!("particles_{step:06}.vtp"))).unwrap();
    let force = vtp
        .split("Name=\"fluid_force\"")
        .nth(1)
        .unwrap()
        .lines()
        .nth(1)
        .unwrap();
    force.split(' ').nth(2).unwrap().parse().unwrap()
}

/// The default scene (no file given) is a coupled run: the lattice, the immersed moving boundary
/// and the DEM. Its first 40 steps (0.022 s, up to the lowest layer's peak speed): the beads fall
/// faster and faster, the fluid pushes back harder and harder, and the first bead, in the lowest
/// layer, stays far below a lone bead's 0.10 m/s (it peaks at 0.039 m/s: the box's walls and the
/// liquid pushed back up between the beads). `--verbose`: the run's settings and the DEM's figures.
#[test]
fn the_default_scene_is_a_coupled_run() {
    let dir = temp_dir("default");
    let out = dir.join("out");
    let result = std::process::Command::new(bin("lbm-server"))
        .args(["run", "--verbose", "--steps", "40", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(0), "{err}");
    assert!(
        err.contains("scene 'default'") && err.contains("immersed moving boundary"),
        "{err}"
    );
    let s = summary(&out);
    assert_eq!(s["software"], format!("lbm-server {}", env!("CARGO_PKG_VERSION")));
    assert!(s["written_unix_s"].as_u64().unwrap() > 1_700_000_000, "{s}");
    assert_eq!(s["particles_initial"], 27);
    assert_eq!(s["lattice"]["cells"].to_string(), "[28,28,32]");
    let physics = s["fluid_physics"].to_string();
    for p in ["lattice-boltzmann", "immersed-boundary", "buoyancy"] {
        assert!(physics.contains(p), "{p} missing from {physics}");
    }
    assert!(!physics.contains("stokes"), "{physics}");
    // The DEM integrates the squeeze films in its sub-steps and says so; the fluid leaves them out.
    assert!(!physics.contains("lubrication"), "{physics}");
    let dem = s["peer"]["physics"].to_string();
    assert!(dem.contains("lubrication") && dem.contains("gravity"), "{dem}");
    assert!(err.contains("lubrication below"), "{err}");
    assert_time_split(&s, &err, 40);
    // Some beads start within a cell (the films' reach) of a neighbour or a wall: they take the
    // DEM's 48 sub-steps of each of its 39 advances as an island, the others fly.
    assert!(
        err.contains("(1872 DEM steps") && err.contains("0 steps in free flight, 39 with an island"),
        "{err}"
    );
    let first: Vec<Vec<f64>> = particle_rows(&out).into_iter().filter(|r| r[2] == 0.0).collect();
    assert_eq!(first.len(), 3, "steps 0, 20 and 39");
    let vz: Vec<f64> = first.iter().map(|r| r[8]).collect();
    let fz: Vec<f64> = first.iter().map(|r| r[14]).collect();
    assert!(
        vz.windows(2).all(|w| w[1] < w[0]),
        "falls faster and faster: {vz:?}"
    );
    assert!(
        fz.windows(2).all(|w| w[1] > w[0]),
        "the fluid pushes back harder: {fz:?}"
    );
    assert!(
        -vz[2] > 0.03 && -vz[2] < 0.045,
        "first bead at {} m/s: expected about 0.038 m/s",
        -vz[2]
    );
}

/// summary.json's `time_s` accounts for the wall time of a coupled run of `steps` steps: every part
/// measured (the fluid's step and the wait for the DEM take time every step), the parts adding up
/// to the wall time, `fluid_mlups` the lattice's cells x steps over the fluid part, and the run's
/// last line giving the split.
fn assert_time_split(s: &serde_json::Value, err: &str, steps: u64) {
    let t = &s["time_s"];
    let part = |name: &str| {
        t[name]
            .as_f64()
            .unwrap_or_else(|| panic!("time_s.{name} missing: {s}"))
    };
    let parts = ["waiting_for_dem", "fluid", "exchange", "output", "other"];
    let sum: f64 = parts.iter().map(|p| part(p)).sum();
    let wall = s["wall_time_s"].as_f64().unwrap();
    assert!(parts.iter().all(|p| part(p) >= 0.0), "{t}");
    assert!(part("fluid") > 0.0 && part("waiting_for_dem") > 0.0, "{t}");
    assert!(
        (sum - wall).abs() < 1e-6 * wall.max(1.0),
        "parts {sum} s, wall {wall} s: {t}"
    );
    let cells: u64 = s["lattice"]["cells"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_u64().unwrap())
        .product();
    let mlups = s["fluid_mlups"].as_f64().unwrap();
    let expected = (cells * steps) as f64 / part("fluid") / 1e6;
    assert!(
        (mlups - expected).abs() < 1e-9 * expected,
        "fluid_mlups {mlups}, expected {expected}"
    );
    assert!(
        err.contains("waiting for the DEM") && err.contains("MLUPS"),
        "{err}"
    );
}

/// Beads of 2 mm radius at these x (mm), y = 6 mm, z = 8 mm: `[[particles.sphere]]` tables.
fn beads_in_a_row(xs: &[f64]) -> String {
    xs.iter()
        .map(|x| {
            format!(
                "[[particles.sphere]]\nposition = [{}, 0.006, 0.008]\nradius = 0.002\n",
                x * 1e-3
            )
        })
        .collect()
}

/// Five beads in a row, 4.2 mm apart at 4 cells per diameter, one slot per cell: the cells between
/// neighbours are covered by both, and each keeps the larger solid fraction. Two runs write the same
/// particles.csv byte for byte (until 2026-12-01 a slot went to whichever particle arrived first:
/// three runs gave three different files), and the run warns about the dropped covers at its last
/// step, 40, which is no multiple of `lattice.check_interval` (such a tail went unchecked). A third
/// run with the solid term in the fluid kernels (`coupling.covered_cells = "fused"`; "auto" redoes
/// the covered cells of sparse particles) and a fourth with the covered cells skipped by the fluid
/// kernels ("skip") write the same file too.
#[test]
fn crowded_cells_give_the_same_run_every_time() {
    let beads = beads_in_a_row(&[3.7, 7.9, 12.1, 16.3, 20.5]);
    let scene = format!(
        "name = \"crowd\"\ngravity = [0.0, 0.0, -9.81]\n[domain]\nmin = [0.0, 0.0, 0.0]\n\
         max = [0.024, 0.012, 0.016]\n[fluid]\ndensity = 1235.0\ndynamic_viscosity = 0.2\n\
         [time]\nsteps = 40\n[lattice]\ndx = 0.001\noperator = \"trt\"\nvelocity_scale = 0.05\n\
         mach = 0.1\n[output]\ninterval = 1\n[coupling]\nslots = 1\n[particles]\ndensity = 2500.0\n{beads}"
    );
    let fused = scene.replace("slots = 1\n", "slots = 1\ncovered_cells = \"fused\"\n");
    let skip = scene.replace("slots = 1\n", "slots = 1\ncovered_cells = \"skip\"\n");
    let files: Vec<String> = [("crowd_a", &scene, "redone"), ("crowd_b", &scene, "redone")]
        .into_iter()
        .chain([
            ("crowd_fused", &fused, "solid term in the fluid kernels"),
            ("crowd_skip", &skip, "skipped by the fluid kernels"),
        ])
        .map(|(tag, scene, mode)| {
            let (code, err, out) = run_scene_verbose(tag, scene);
            assert_eq!(code, Some(0), "{err}");
            assert!(
                err.contains("by step 40,") && err.contains("did not fit coupling.slots = 1"),
                "the last step is checked and the dropped covers named: {err}"
            );
            assert!(err.contains(mode), "{tag}: covered cells {mode}: {err}");
            std::fs::read_to_string(out.join("particles.csv")).unwrap()
        })
        .collect();
    assert_eq!(files[0].lines().count(), 1 + 40 * 5, "a row per bead per step");
    assert!(files[0] == files[1], "the two runs' particles.csv differ");
    assert!(
        files[0] == files[2],
        "fused and redone covered cells give different particles.csv"
    );
    assert!(
        files[0] == files[3],
        "skipped and redone covered cells give different particles.csv"
    );
}

/// Without `--verbose` a run says a short header (scene, particles, lattice, steps and simulated
/// time, device), a line per warning pointing at `--verbose`, the dropped covers once, the DEM's
/// step and its end in a line each, its progress and its last line; with it each warning in full
/// and the dropped covers at every check. Three beads of 4 cells at tau 1.06 (two warnings), one
/// slot per cell (covers dropped by the checks of steps 20 and 30, none by step 10).
#[test]
fn a_run_says_a_short_header_and_a_line_per_warning() {
    let beads = beads_in_a_row(&[3.7, 7.9, 12.1]);
    let scene = format!(
        "name = \"brief\"\ngravity = [0.0, 0.0, -9.81]\n[domain]\nmin = [0.0, 0.0, 0.0]\n\
         max = [0.016, 0.012, 0.016]\n[fluid]\ndensity = 1235.0\ndynamic_viscosity = 0.2\n\
         [time]\nsteps = 30\n[lattice]\ndx = 0.001\noperator = \"trt\"\nvelocity_scale = 0.05\n\
         mach = 0.1\ncheck_interval = 10\n[output]\ninterval = 10\n[coupling]\nslots = 1\n\
         [particles]\ndensity = 2500.0\n{beads}"
    );
    let (code, err, _) = run_scene("brief", &scene);
    assert_eq!(code, Some(0), "{err}");
    let said: Vec<&str> = err
        .lines()
        .filter(|l| !l.starts_with("lbm-server: step "))
        .collect();
    let header = "lbm-server: scene 'brief': 3 particles, lattice 16x12x16 (trt, tau 1.061), immersed \
                  moving boundary; 30 steps = 0.035 s; ";
    let more = "(--verbose says more)";
    let expected = [
        header,
        "lbm-server: warning: lattice tau = 1.061 (trt): the immersed boundary's drag falls as tau grows",
        "lbm-server: warning: the smallest particles are 4.0 cells across",
        "lbm-server: warning: by step 20, ",
        "dem-client: DEM step ",
        "dem-client: finished after 30 steps (",
        "lbm-server: 30 steps in ",
    ];
    for start in expected {
        assert!(said.iter().any(|l| l.starts_with(start)), "{start:?} in {err}");
    }
    assert_eq!(said.len(), expected.len(), "a line each: {err}");
    let warnings = said.iter().filter(|l| l.contains(": warning: "));
    assert!(
        warnings.take(2).all(|l| l.ends_with(more)) && err.contains("(--verbose: what limits it)"),
        "{err}"
    );
    let (code, err, _) = run_scene_verbose("brief_verbose", &scene);
    assert_eq!(code, Some(0), "{err}");
    assert!(
        !err.contains(more) && err.contains("(validation/lbm/REPORT.md, \"drag against tau\")"),
        "the warnings in full: {err}"
    );
    assert_eq!(err.matches("did not fit coupling.slots = 1").count(), 2, "{err}");
    assert!(err.contains("lubrication below"), "the DEM's step limits: {err}");
}

/// `coupling.covered_cells = "timed"` and `lattice.kernel = "auto"`: the run times the quads' and
/// the per-cell kernels, then redo, skip and fused, on its own first steps (from step 10, each 5
/// steps a round, 3 rounds), says what it measured and kept, and writes the same particles.csv as
/// a run that takes the quads' kernels and redoes the covered cells throughout (the kernels and
/// ways agree bit for bit, so changing between them changes nothing but the speed); summary.json
/// names the kernels and the way kept and holds the trial's lines.
#[test]
fn a_timed_run_changes_ways_and_not_its_particles() {
    let (code, redo_err, redo) = run_scene_verbose("timed_redo", &ways_scene("redo", "quads"));
    assert_eq!(code, Some(0), "{redo_err}");
    assert!(!redo_err.contains("covered cells timed"), "{redo_err}");
    assert!(!redo_err.contains("kernels timed"), "{redo_err}");
    let (code, err, timed) = run_scene_verbose("timed", &ways_scene("timed", "auto"));
    assert_eq!(code, Some(0), "{err}");
    assert!(
        err.contains("the kernels and the ways of the covered cells timed on the run's first steps"),
        "{err}"
    );
    let (kernel, kept) = kept_by_the_trial(&err);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(timed.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["covered_cells"], kept, "summary.json names the way kept");
    assert_eq!(summary["kernel"], kernel, "summary.json names the kernels kept");
    assert_eq!(
        summary["trial"].as_array().map(Vec::len),
        Some(2),
        "the trial's lines"
    );
    let particles = |out: &Path| std::fs::read_to_string(out.join("particles.csv")).unwrap();
    assert_eq!(
        particles(&timed).lines().count(),
        1 + 25 * 3,
        "rows every 10 steps and the last"
    );
    assert!(
        particles(&timed) == particles(&redo),
        "the timed run's particles.csv differs from the redone run's"
    );
}

/// The scene of [`a_timed_run_changes_ways_and_not_its_particles`]: three beads in a row settling,
/// 240 steps, with the covered cells' `way` and the `kernel` given.
fn ways_scene(way: &str, kernel: &str) -> String {
    let beads = beads_in_a_row(&[3.7, 7.9, 12.1]);
    format!(
        "name = \"ways\"\ngravity = [0.0, 0.0, -9.81]\n[domain]\nmin = [0.0, 0.0, 0.0]\n\
         max = [0.016, 0.012, 0.016]\n[fluid]\ndensity = 1235.0\ndynamic_viscosity = 0.2\n\
         [time]\nsteps = 240\n[lattice]\ndx = 0.001\noperator = \"trt\"\nvelocity_scale = 0.05\n\
         mach = 0.1\nkernel = \"{kernel}\"\n[output]\ninterval = 10\n[coupling]\ncovered_cells = \"{way}\"\n\
         [particles]\ndensity = 2500.0\n{beads}"
    )
}

/// The kernels and the way of the covered cells that the trial said it kept, from the run's
/// stderr `err`; every way timed.
fn kept_by_the_trial(err: &str) -> (&'static str, &'static str) {
    let line = |what: &str| {
        err.lines()
            .find(|l| l.contains(what))
            .unwrap_or_else(|| panic!("the trial's line {what:?}: {err}"))
    };
    let kernels = line("kernels timed with the covered cells redo");
    let kernel = ["quads", "cells"]
        .into_iter()
        .find(|k| kernels.ends_with(&format!(": {k} kept")))
        .unwrap_or_else(|| panic!("a kernel kept: {kernels}"));
    let ways = line(&format!("covered cells timed with the {kernel} kernels"));
    let kept = ["redo", "skip", "fused"]
        .into_iter()
        .find(|w| ways.ends_with(&format!(": {w} kept")))
        .unwrap_or_else(|| panic!("a way kept: {ways}"));
    for way in ["redo", "skip", "fused"] {
        assert!(
            ways.contains(&format!("{way} ")) && ways.contains(" ms"),
            "{way} timed: {ways}"
        );
    }
    (kernel, kept)
}
