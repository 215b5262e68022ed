//! The fluid's field outputs, for fluid runs and coupled runs alike: VTK snapshots of density and
//! velocity (fields/stepNNNNNNNNN.vti, listed with their times in fields.pvd) and the probe lines
//! of `output.line` (line<N>.csv), all in SI units.

use crate::checkpoint::OutputPositions;
use crate::vtk::{write_vti, Grid, Series};
use scene::lattice::LatticeUnits;
use scene::{ProbeLine, Scene};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The field outputs of one run, in its output folder.
pub struct FieldOutput {
    out: PathBuf,
    grid: Grid,
    series: Series,
    /// Each probe line's cells (indices of the whole lattice, in the line's order), the axis it
    /// runs along and its file.
    probes: Vec<(Vec<usize>, usize, std::io::BufWriter<std::fs::File>)>,
    domain_min: [f64; 3],
    fluid_density: f64,
    /// The lattice's units: its cells' centres, seconds and velocities in SI.
    units: LatticeUnits,
}

impl FieldOutput {
    /// The outputs of a run of `scene` on the lattice `units` into `out`: a line<N>.csv with its
    /// header for each probe line (fields/ is made with the first snapshot).
    /// Resumed (`at`, a checkpoint's positions), each line<N>.csv is cut back to where the
    /// checkpoint found it and fields.pvd holds the checkpoint's snapshots.
    pub fn new(
        scene: &Scene,
        units: &LatticeUnits,
        out: &Path,
        at: Option<&OutputPositions>,
    ) -> Result<FieldOutput, String> {
        let io = |e: std::io::Error| format!("{}: {e}", out.display());
        let mut probes = Vec::new();
        for (i, line) in scene.output.line.iter().enumerate() {
            let name = format!("line{i}.csv");
            let w = match at {
                None => {
                    let file = std::fs::File::create(out.join(&name)).map_err(io)?;
                    let mut w = std::io::BufWriter::new(file);
                    writeln!(w, "step,time,s,density,ux,uy,uz").map_err(io)?;
                    w
                }
                Some(at) => std::io::BufWriter::new(at.reopen(out, &name)?),
            };
            let (cells, axis) = line_cells(line, scene, units);
            probes.push((cells, axis, w));
        }
        let pvd = out.join("fields.pvd");
        let series = match at {
            None => Series::new(pvd),
            Some(at) => Series::resume(pvd, at.fields_pvd.clone()).map_err(io)?,
        };
        Ok(FieldOutput {
            out: out.to_path_buf(),
            grid: Grid {
                n: units.n,
                origin: scene.domain.min,
                dx: units.dx,
            },
            series,
            probes,
            domain_min: scene.domain.min,
            fluid_density: scene.fluid.density,
            units: units.clone(),
        })
    }

    /// Density [kg/m^3] and velocity [m/s] of every cell of the lattice `fields`.
    fn si_fields(&self, fields: &[[f32; 4]]) -> (Vec<f32>, Vec<[f32; 3]>) {
        si_fields(fields, self.fluid_density, &self.units)
    }

    /// The snapshot after `step` steps: fields/stepNNNNNNNNN.vti, added to fields.pvd.
    pub fn write_snapshot(&mut self, step: u64, fields: &[[f32; 4]]) -> Result<(), String> {
        let name = format!("{}.vti", snapshot_name(step));
        let (density, velocity) = self.si_fields(fields);
        let io = |e: std::io::Error| format!("{name}: {e}");
        std::fs::create_dir_all(self.out.join("fields")).map_err(io)?;
        write_vti(&self.out.join(&name), &self.grid, &density, &velocity).map_err(io)?;
        self.add_snapshot(step, &name)
    }

    /// Adds the snapshot `file` (relative to the output folder; written) of `step` to
    /// fields.pvd.
    pub fn add_snapshot(&mut self, step: u64, file: &str) -> Result<(), String> {
        self.series
            .add(self.units.seconds(step as f64), file)
            .map_err(|e| format!("fields.pvd: {e}"))
    }

    /// The snapshot of the last check that passed (step `good`), where a run blew up: a line
    /// for the run's error message.
    pub fn write_last_good(&self, good: u64, fields: &[[f32; 4]]) -> String {
        let (density, velocity) = self.si_fields(fields);
        let path = self.out.join("last_good.vti");
        let written = write_vti(&path, &self.grid, &density, &velocity).map_err(|e| e.to_string());
        last_good_line(good, written.map(|()| path))
    }

    /// A row per cell of each probe line after `step` steps, from the `values` of its cells
    /// ([`probe_cells`], in that order).
    pub fn write_line_values(&mut self, step: u64, values: &[[f32; 4]]) -> Result<(), String> {
        let (rho, c) = (self.fluid_density, self.units.velocity_unit());
        let (min, units, grid) = (self.domain_min, &self.units, &self.grid);
        let mut values = values.iter();
        for (cells, axis, w) in &mut self.probes {
            for (&cell, f) in cells.iter().zip(&mut values) {
                let idx = [
                    cell % grid.n[0],
                    (cell / grid.n[0]) % grid.n[1],
                    cell / (grid.n[0] * grid.n[1]),
                ];
                let s = units.cell_centre(idx, min)[*axis];
                let u = [f[1] as f64 * c, f[2] as f64 * c, f[3] as f64 * c];
                writeln!(
                    w,
                    "{step},{:e},{s:e},{:e},{:e},{:e},{:e}",
                    units.seconds(step as f64),
                    f[0] as f64 * rho,
                    u[0],
                    u[1],
                    u[2]
                )
                .map_err(|e| format!("line probe: {e}"))?;
            }
        }
        Ok(())
    }

    /// Where the outputs stand, for a checkpoint: the probe lines written out and their lengths,
    /// the snapshots listed in fields.pvd, into `at`.
    pub fn positions(&mut self, at: &mut OutputPositions) -> Result<(), String> {
        self.flush()?;
        for (i, (_, _, w)) in self.probes.iter().enumerate() {
            let len = w
                .get_ref()
                .metadata()
                .map_err(|e| format!("line{i}.csv: {e}"))?
                .len();
            at.files.insert(format!("line{i}.csv"), len);
        }
        at.fields_pvd = self.series.entries().to_vec();
        Ok(())
    }

    /// Writes out what the probe lines hold.
    pub fn flush(&mut self) -> Result<(), String> {
        for (_, _, w) in &mut self.probes {
            w.flush().map_err(|e| format!("line probe: {e}"))?;
        }
        Ok(())
    }
}

/// The name of the snapshot after `step` steps, relative to the output folder, without its
/// extension (.vti on one rank, .pvti on several).
pub fn snapshot_name(step: u64) -> String {
    format!("fields/step{step:09}")
}

/// Density [kg/m^3] and velocity [m/s] of lattice `fields` (lattice units), for a fluid of
/// `fluid_density` on the lattice `units`.
pub fn si_fields(fields: &[[f32; 4]], fluid_density: f64, units: &LatticeUnits) -> (Vec<f32>, Vec<[f32; 3]>) {
    let rho = fluid_density as f32;
    let c = units.velocity_unit() as f32;
    (
        fields.iter().map(|f| f[0] * rho).collect(),
        fields.iter().map(|f| [f[1] * c, f[2] * c, f[3] * c]).collect(),
    )
}

/// The cells of the scene's probe lines (indices of the whole lattice `units`), line after line.
pub fn probe_cells(scene: &Scene, units: &LatticeUnits) -> Vec<usize> {
    let lines = scene.output.line.iter();
    lines.flat_map(|l| line_cells(l, scene, units).0).collect()
}

/// The line a blow-up's error message gets for the last good snapshot (step `good`): where it
/// was `written`, or why not.
pub fn last_good_line(good: u64, written: Result<PathBuf, String>) -> String {
    match written {
        Ok(path) => format!("; last good snapshot (step {good}) in {}", path.display()),
        Err(e) => format!("; could not write the last good snapshot: {e}"),
    }
}

/// The cells of the probe line `line` (indices of the whole lattice `units`, along its axis),
/// and that axis.
fn line_cells(line: &ProbeLine, scene: &Scene, units: &LatticeUnits) -> (Vec<usize>, usize) {
    let (n, min) = (units.n, scene.domain.min);
    let axis = ["x", "y", "z"]
        .iter()
        .position(|a| *a == line.axis)
        .expect("validated axis");
    let cell_of = |a: usize| {
        let v = units.cells(line.through[a] - min[a]).floor();
        (v.max(0.0) as usize).min(n[a] - 1)
    };
    let mut idx = [cell_of(0), cell_of(1), cell_of(2)];
    let cells = (0..n[axis])
        .map(|i| {
            idx[axis] = i;
            idx[0] + n[0] * (idx[1] + n[1] * idx[2])
        })
        .collect();
    (cells, axis)
}
