//! A run decomposed over MPI ranks (`mpirun -np N lbm-server run`), against the same run in one
//! process, walled and periodic, on 2 and 4 ranks: a fluid-only run's probe lines and every field
//! snapshot byte for byte; a coupled run's particles.csv and snapshots byte for byte, spheres
//! across the cuts; and the refusals of blocks and settings that cannot be. The runs need mpirun
//! and an lbm-server built with `--features mpi`; where either is missing they say so and pass.

mod common;
use common::mpi::{mpirun, mpirun_command, scene, PERIODIC, SOLID, WALLED};
use common::*;
use std::path::Path;
use std::process::Output;

fn text(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned() + &String::from_utf8_lossy(&o.stdout)
}

/// The outputs of a fluid run that must not depend on the ranks: the probe lines, fields.pvd (a
/// snapshot named .vti on one rank, .pvti on several) and each snapshot's cells, density then
/// velocity, as the bytes of its .vti (one rank) or of its pieces put together (several).
fn outputs(out: &Path) -> Vec<(String, Vec<u8>)> {
    let read = |f: &str| std::fs::read(out.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
    let mut files: Vec<(String, Vec<u8>)> = ["line0.csv", "line1.csv"]
        .iter()
        .map(|f| (f.to_string(), read(f)))
        .collect();
    files.extend(snapshots(out, &["6", "12"]));
    files
}

/// fields.pvd (a snapshot named .vti on one rank, .pvti on several) and the cells of the
/// snapshots after `steps`, density then velocity, as the bytes of its .vti (one rank) or of its
/// pieces put together (several).
fn snapshots(out: &Path, steps: &[&str]) -> Vec<(String, Vec<u8>)> {
    let read = |f: &str| std::fs::read(out.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
    let pvd = String::from_utf8(read("fields.pvd")).unwrap();
    let mut files = vec![("fields.pvd".into(), pvd.replace(".pvti\"", ".vti\"").into_bytes())];
    for step in steps {
        let name = format!("fields/step{step:0>9}");
        let cells = match out.join(format!("{name}.pvti")).is_file() {
            true => pieces_put_together(&out.join(format!("{name}.pvti"))),
            false => vti_cells(&read(&format!("{name}.vti"))).1,
        };
        files.push((name, cells));
    }
    files
}

/// A .vti's extent (first and last point along x, y, z) and its cells' density and velocity
/// (raw appended data, x fastest).
fn vti_cells(bytes: &[u8]) -> ([usize; 6], Vec<u8>) {
    let marker = b"encoding=\"raw\">_";
    let start = bytes.windows(marker.len()).position(|w| w == marker).unwrap() + marker.len();
    let header = String::from_utf8_lossy(&bytes[..start]);
    let len = |at: usize| u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap()) as usize;
    let density = &bytes[start + 8..start + 8 + len(start)];
    let v = start + 8 + density.len();
    let velocity = &bytes[v + 8..v + 8 + len(v)];
    (extent(&header, "<Piece Extent=\""), [density, velocity].concat())
}

/// The six numbers of the extent after `key` in `text`.
fn extent(text: &str, key: &str) -> [usize; 6] {
    let at = text.find(key).unwrap_or_else(|| panic!("{key} in {text}")) + key.len();
    let numbers: Vec<usize> = text[at..]
        .split('"')
        .next()
        .unwrap()
        .split(' ')
        .map(|n| n.parse().unwrap())
        .collect();
    numbers.try_into().unwrap()
}

/// The cells of the whole grid of a .pvti, put together from its pieces (each placed by its
/// extent, checked against the piece's own), as [`vti_cells`] gives a whole .vti's: every cell
/// covered once.
fn pieces_put_together(pvti: &Path) -> Vec<u8> {
    let text = std::fs::read_to_string(pvti).unwrap();
    let whole = extent(&text, "WholeExtent=\"");
    let n = [whole[1], whole[3], whole[5]];
    let cells = n[0] * n[1] * n[2];
    let (mut density, mut velocity) = (vec![None; cells], vec![None; cells]);
    for piece in text.split("<Piece ").skip(1) {
        let e = extent(piece, "Extent=\"");
        let source = piece
            .split("Source=\"")
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap();
        let (own, values) = vti_cells(&std::fs::read(pvti.parent().unwrap().join(source)).unwrap());
        assert_eq!(own, e, "{source}: its extent is the .pvti's");
        let mut k = 0;
        for z in e[4]..e[5] {
            for y in e[2]..e[3] {
                for x in e[0]..e[1] {
                    let g = x + n[0] * (y + n[1] * z);
                    assert!(
                        density[g].is_none(),
                        "{source}: cell ({x}, {y}, {z}) in two pieces"
                    );
                    density[g] = Some(values[4 * k..4 * k + 4].to_vec());
                    let at = 4 * (e[1] - e[0]) * (e[3] - e[2]) * (e[5] - e[4]) + 12 * k;
                    velocity[g] = Some(values[at..at + 12].to_vec());
                    k += 1;
                }
            }
        }
    }
    let all = |v: Vec<Option<Vec<u8>>>| -> Vec<u8> {
        v.into_iter()
            .flat_map(|c| c.expect("every cell in a piece"))
            .collect()
    };
    [all(density), all(velocity)].concat()
}

/// The scene on one process, then on each of `runs`' ranks with its `[parallel]` section (or
/// none): the same `outputs` byte for byte, and the summary names the ranks and blocks. False
/// where the runs cannot be made (said why).
fn same_on_ranks(
    tag: &str,
    text_: &str,
    runs: &[(usize, &str)],
    outputs: fn(&Path) -> Vec<(String, Vec<u8>)>,
) -> bool {
    let Some(mpirun) = mpirun() else {
        eprintln!("skipped: mpirun is not installed (apt-get install openmpi-bin libopenmpi-dev)");
        return false;
    };
    let dir = temp_dir(tag);
    let scene = write_scene(&dir, text_);
    let single = dir.join("one");
    let o = server(&scene, &single, &[]).output().unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let expected = outputs(&single);
    for &(n, parallel) in runs {
        let out = dir.join(format!("np{n}"));
        let scene = dir.join(format!("np{n}.toml"));
        std::fs::write(&scene, format!("{text_}\n{parallel}\n")).unwrap();
        let o = mpirun_command(&mpirun, n, &scene, &out).output().unwrap();
        if text(&o).contains("built without MPI") {
            eprintln!("skipped: lbm-server is built without MPI (cargo build -p lbm-server --features mpi)");
            return false;
        }
        assert_eq!(o.status.code(), Some(0), "{n} ranks: {}", text(&o));
        for ((file, want), (_, have)) in expected.iter().zip(outputs(&out)) {
            assert!(
                *want == have,
                "{n} ranks: {file} differs from the single process's"
            );
        }
        let s = summary(&out);
        assert_eq!(s["parallel"]["ranks"], n, "{s}");
        let blocks: u64 = (0..3)
            .map(|a| s["parallel"]["blocks"][a].as_u64().unwrap())
            .product();
        assert_eq!(blocks, n as u64, "{s}");
        assert_eq!(s["parallel"]["devices"].as_array().unwrap().len(), n, "{s}");
    }
    true
}

#[test]
fn a_walled_run_on_2_and_4_ranks_is_the_single_process_run_byte_for_byte() {
    same_on_ranks(
        "mpi-walled",
        &scene("walled", WALLED, SOLID),
        &[(2, ""), (4, "")],
        outputs,
    );
}

#[test]
fn a_periodic_run_cut_along_two_axes_is_the_single_process_run_byte_for_byte() {
    let blocks = "[parallel]\nblocks = [2, 1, 2]";
    same_on_ranks(
        "mpi-periodic",
        &scene("periodic", PERIODIC, ""),
        &[(4, blocks)],
        outputs,
    );
}

/// Blocks that cannot be are refused before anything runs, naming the field and value: on one
/// process, more blocks than ranks (or, built without MPI, more than one block).
#[test]
fn blocks_that_cannot_be_are_refused_before_the_run() {
    let dir = temp_dir("mpi-blocks");
    let scene_file = write_scene(&dir, &scene("blocks", WALLED, "[parallel]\nblocks = [1, 1, 2]"));
    let o = server(&scene_file, &dir.join("out"), &[]).output().unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    let err = text(&o);
    assert!(err.contains("parallel.blocks = [1, 1, 2]"), "{err}");
    assert!(
        err.contains("needs the MPI build") || err.contains("2 blocks, but the run has 1 rank"),
        "{err}"
    );
    assert!(!dir.join("out").join("summary.json").exists(), "nothing ran");
    let scene_file = write_scene(&dir, &scene("blocks", WALLED, "[parallel]\nblocks = [3, 1, 1]"));
    let o = server(&scene_file, &dir.join("out"), &[]).output().unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains("parallel.blocks[0] = 3: must divide the lattice's 8 cells along x"),
        "{}",
        text(&o)
    );
}

/// Started as one of several ranks (as mpirun starts it) by a build without MPI, the run is
/// refused: each rank would run the whole scene alone.
#[test]
fn a_build_without_mpi_refuses_to_run_as_one_of_several_ranks() {
    let dir = temp_dir("mpi-without");
    let scene_file = write_scene(&dir, &scene("without", PERIODIC, ""));
    let probe = server(&scene_file, &dir.join("probe"), &["--steps", "1"])
        .output()
        .unwrap();
    let blocks = write_scene(
        &dir,
        &scene("without", PERIODIC, "[parallel]\nblocks = [1, 1, 2]"),
    );
    let built = server(&blocks, &dir.join("probe2"), &[]).output().unwrap();
    assert_eq!(probe.status.code(), Some(0), "{}", text(&probe));
    if !text(&built).contains("needs the MPI build") {
        eprintln!("skipped: lbm-server is built with MPI");
        return;
    }
    let scene_file = write_scene(&dir, &scene("without", PERIODIC, ""));
    let o = server(&scene_file, &dir.join("out"), &[])
        .env("OMPI_COMM_WORLD_SIZE", "2")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("built without MPI"), "{}", text(&o));
}

/// A coupled scene of 24 steps (1 mm cells, TRT), particles.csv every 4 steps, a snapshot every
/// 12: in a walled box
/// of 12 x 12 x 16 mm two falling spheres, one across the cuts of 2 blocks (z = 8 mm) and of 4
/// (y = 6 mm too: across an edge); `periodic`, in a periodic box of 16 x 14 x 16 mm driven by a
/// body force, the first across the periodic x faces as well (the cuts of [2, 1, 2] blocks).
fn coupled_scene(name: &str, periodic: bool) -> String {
    let (max, gravity, first_x) = match periodic {
        true => ("[0.016, 0.014, 0.016]", 0.0, 0.0005),
        false => ("[0.012, 0.012, 0.016]", -9.81, 0.006),
    };
    let faces = match periodic {
        true => format!("body_acceleration = [0.5, 0.0, 0.2]\n[lattice.faces]\n{PERIODIC}"),
        false => String::new(),
    };
    format!(
        r#"name = "{name}"
gravity = [0.0, 0.0, {gravity}]
[domain]
min = [0.0, 0.0, 0.0]
max = {max}
[fluid]
density = 1000.0
dynamic_viscosity = 0.2
[time]
steps = 24
[output]
interval = 4
fields_interval = 12
[coupling]
timeout = 10.0
[particles]
density = 2500.0
[[particles.sphere]]
position = [{first_x}, 0.006, 0.008]
radius = 0.002
velocity = [0.01, -0.02, 0.0]
[[particles.sphere]]
position = [0.003, 0.0095, 0.0125]
radius = 0.002
velocity = [0.0, 0.0, -0.03]
[lattice]
dx = 0.001
operator = "trt"
tau = 0.8
velocity_scale = 0.05
check_interval = 8
{faces}
"#
    )
}

/// The outputs of a coupled run that must not depend on the ranks: particles.csv, fields.pvd and
/// the snapshots' cells (their pieces put together on several ranks).
fn coupled_outputs(out: &Path) -> Vec<(String, Vec<u8>)> {
    let bytes = std::fs::read(out.join("particles.csv")).unwrap();
    assert_eq!(csv_steps(out).len(), 7, "steps 0, 4, ..., 20 and the last");
    let mut files = vec![("particles.csv".into(), bytes)];
    files.extend(snapshots(out, &["12", "24"]));
    files
}

#[test]
fn a_coupled_walled_run_on_2_and_4_ranks_writes_the_single_process_particles_byte_for_byte() {
    let scene = coupled_scene("coupled-walled", false);
    same_on_ranks("mpi-coupled-walled", &scene, &[(2, ""), (4, "")], coupled_outputs);
}

#[test]
fn a_coupled_periodic_run_on_2_and_4_ranks_writes_the_single_process_particles_byte_for_byte() {
    let blocks = "[parallel]\nblocks = [2, 1, 2]";
    let scene = coupled_scene("coupled-periodic", true);
    same_on_ranks(
        "mpi-coupled-periodic",
        &scene,
        &[(2, ""), (4, blocks)],
        coupled_outputs,
    );
}

/// What a coupled run on several ranks cannot take yet is refused before anything runs (exit
/// 2), naming the setting.
#[test]
fn a_coupled_run_on_ranks_refuses_the_covered_cells_it_cannot_take() {
    let Some(mpirun) = mpirun() else {
        eprintln!("skipped: mpirun is not installed");
        return;
    };
    let dir = temp_dir("mpi-coupled-refused");
    let text_ = coupled_scene("coupled-fused", false)
        .replace("timeout = 10.0", "timeout = 10.0\ncovered_cells = \"fused\"");
    let scene = write_scene(&dir, &text_);
    let o = mpirun_command(&mpirun, 2, &scene, &dir.join("out"))
        .output()
        .unwrap();
    if text(&o).contains("built without MPI") {
        eprintln!("skipped: lbm-server is built without MPI");
        return;
    }
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains("coupling.covered_cells = \"fused\" on 2 ranks"),
        "{}",
        text(&o)
    );
    assert!(!dir.join("out").join("particles.csv").exists(), "nothing ran");
}
