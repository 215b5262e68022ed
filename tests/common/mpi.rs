//! Helpers of the tests of runs on MPI ranks: mpirun, and a small fluid scene.

use super::bin;
use std::path::{Path, PathBuf};
use std::process::Command;

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
    let mut cmd = Command::new(mpirun);
    cmd.args([
        "--allow-run-as-root",
        "--oversubscribe",
        "-np",
        &ranks.to_string(),
    ])
    .args(["-x", "LP_NUM_THREADS=1", "-x", "NODEVICE_SELECT=1"])
    .arg(bin("lbm-server"))
    .arg("run")
    .arg(scene)
    .arg("--out")
    .arg(out);
    cmd
}
