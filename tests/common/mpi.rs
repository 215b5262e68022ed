//! Helpers of the tests of runs on MPI ranks: mpirun, a small fluid scene and a coupled one, and
//! the snapshots' cells (a .pvti's pieces put together) to compare with one process's.

use super::{bin, csv_steps};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A box of 8 x 8 x 8 cells (1 mm, tau 0.8) with a body force, run 12 steps with probe lines
/// and snapshots every 6 steps; `faces` and `extra` (a solid box, `[parallel]`) as given.
pub fn scene(name: &str, faces: &str, extra: &str) -> String {
    format!(
        r#"name = "{name}"
[domain]
min = [0.0, 0.0, 0.0]
max = [0.008, 0.008, 0.008]
[fluid]
density = 1000.0
dynamic_viscosity = 1.0e-3
[time]
steps = 12
[lattice]
dx = 0.001
operator = "mrt"
tau = 0.8
velocity_scale = 5.0e-4
body_acceleration = [1.0e-4, 2.0e-5, -1.0e-5]
check_interval = 4
[lattice.faces]
{faces}
[output]
interval = 6
fields_interval = 6
[[output.line]]
axis = "y"
through = [0.0035, 0.004, 0.0045]
[[output.line]]
axis = "z"
through = [0.0045, 0.0035, 0.004]
{extra}
"#
    )
}

pub const WALLED: &str = "x_min = \"periodic\"\nx_max = \"periodic\"\ny_min = \"wall\"\ny_max = \"wall\"\n\
                      z_min = \"wall\"\nz_max = { type = \"moving_wall\", velocity = [5.0e-4, 1.0e-4, 0.0] }";
pub const PERIODIC: &str =
    "x_min = \"periodic\"\nx_max = \"periodic\"\ny_min = \"periodic\"\ny_max = \"periodic\"\n\
                        z_min = \"periodic\"\nz_max = \"periodic\"";
/// Solid cells on both sides of the cuts of 2 and 4 blocks.
pub const SOLID: &str = "[[lattice.solid_box]]\nmin = [0.002, 0.003, 0.003]\nmax = [0.005, 0.005, 0.005]";

/// Output files that must not depend on the ranks: each name and its bytes (as compared).
pub type Files = Vec<(String, Vec<u8>)>;

/// mpirun, where it is installed.
pub fn mpirun() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join("mpirun"))
        .find(|p| p.is_file())
}

/// `mpirun -np N lbm-server run SCENE --out OUT` (as root too; more ranks than cores; one
/// llvmpipe thread per rank).
pub fn mpirun_command(mpirun: &Path, ranks: usize, scene: &Path, out: &Path) -> Command {
    let mut cmd = mpirun_run(mpirun, ranks);
    cmd.arg(scene).arg("--out").arg(out);
    cmd
}

/// `mpirun -np N lbm-server run` (as [`mpirun_command`]), its arguments to be added; it and its
/// ranks die with the test ([`super::die_with_test`]).
pub fn mpirun_run(mpirun: &Path, ranks: usize) -> Command {
    let mut cmd = Command::new(mpirun);
    super::die_with_test(&mut cmd)
        .args([
            "--allow-run-as-root",
            "--oversubscribe",
            "-np",
            &ranks.to_string(),
        ])
        .args(["-x", "LP_NUM_THREADS=1", "-x", "NODEVICE_SELECT=1"])
        .arg(bin("lbm-server"))
        .arg("run");
    cmd
}

/// A process's stderr and stdout.
pub fn text(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned() + &String::from_utf8_lossy(&o.stdout)
}

/// fields.pvd (a snapshot named .vti on one rank, .pvti on several) and the cells of the
/// snapshots after `steps`, density then velocity, as the bytes of its .vti (one rank) or of its
/// pieces put together (several).
pub fn snapshots(out: &Path, steps: &[&str]) -> Files {
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
pub fn vti_cells(bytes: &[u8]) -> ([usize; 6], Vec<u8>) {
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
pub fn extent(text: &str, key: &str) -> [usize; 6] {
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
pub fn pieces_put_together(pvti: &Path) -> Vec<u8> {
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

/// A coupled scene of 24 steps (1 mm cells, TRT), particles.csv every 4 steps, a snapshot every
/// 12: in a walled box
/// of 12 x 12 x 16 mm two falling spheres, one across the cuts of 2 blocks (z = 8 mm) and of 4
/// (y = 6 mm too: across an edge); `periodic`, in a periodic box of 16 x 14 x 16 mm driven by a
/// body force, the first across the periodic x faces as well (the cuts of [2, 1, 2] blocks).
pub fn coupled_scene(name: &str, periodic: bool) -> String {
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

/// The outputs of a fluid run that must not depend on the ranks: the probe lines, fields.pvd (a
/// snapshot named .vti on one rank, .pvti on several) and each snapshot's cells, density then
/// velocity, as the bytes of its .vti (one rank) or of its pieces put together (several).
pub fn fluid_outputs(out: &Path) -> Files {
    let read = |f: &str| std::fs::read(out.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
    let mut files: Vec<(String, Vec<u8>)> = ["line0.csv", "line1.csv"]
        .iter()
        .map(|f| (f.to_string(), read(f)))
        .collect();
    files.extend(snapshots(out, &["6", "12"]));
    files
}

/// The outputs of a coupled run that must not depend on the ranks: particles.csv, fields.pvd and
/// the snapshots' cells (their pieces put together on several ranks).
pub fn coupled_outputs(out: &Path) -> Files {
    let bytes = std::fs::read(out.join("particles.csv")).unwrap();
    assert_eq!(csv_steps(out).len(), 7, "steps 0, 4, ..., 20 and the last");
    let mut files = vec![("particles.csv".into(), bytes)];
    files.extend(snapshots(out, &["12", "24"]));
    files
}
