//! The particles as VTK polydata for ParaView, written alike by `dem-client run` and by a coupled
//! `lbm-server run`: particles_NNNNNN.vtp per output step (one point per particle with its id,
//! radius and vectors) and particles.pvd, the collection with their times.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// The particles of one output step, SI units, one entry per particle in each slice.
pub struct Frame<'a> {
    pub ids: &'a [u64],
    pub positions: &'a [[f64; 3]],
    pub radii: &'a [f64],
    /// Named per-particle vectors (velocity first: ParaView's default vectors).
    pub vectors: &'a [(&'a str, Vec<[f64; 3]>)],
}

/// particles_NNNNNN.vtp files in a folder and the particles.pvd collection that lists them.
pub struct ParticleSeries {
    dir: PathBuf,
    frames: Vec<(f64, String)>,
}

impl ParticleSeries {
    pub fn new(dir: &Path) -> Self {
        Self {
            dir: dir.to_path_buf(),
            frames: Vec::new(),
        }
    }

    /// The series of a resumed run: its frames so far (a checkpoint's; particles.pvd was cut
    /// back to them by `scene::checkpoint::cut_back`).
    pub fn resume(dir: &Path, frames: Vec<(f64, String)>) -> std::io::Result<Self> {
        Ok(Self {
            dir: dir.to_path_buf(),
            frames,
        })
    }

    /// The frames so far: time [s] and file name.
    pub fn frames(&self) -> &[(f64, String)] {
        &self.frames
    }

    /// Writes `frame` as step `step` at time `time` [s] and rewrites particles.pvd.
    pub fn write(&mut self, step: u64, time: f64, frame: &Frame) -> std::io::Result<()> {
        let name = format!("particles_{step:06}.vtp");
        let mut w = BufWriter::new(File::create(self.dir.join(&name))?);
        write_vtp(&mut w, frame)?;
        w.flush()?;
        self.frames.push((time, name));
        self.write_pvd()
    }

    fn write_pvd(&self) -> std::io::Result<()> {
        let mut w = BufWriter::new(File::create(self.dir.join("particles.pvd"))?);
        writeln!(w, "<?xml version=\"1.0\"?>")?;
        writeln!(
            w,
            "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">"
        )?;
        writeln!(w, "<Collection>")?;
        for (t, name) in &self.frames {
            writeln!(
                w,
                "<DataSet timestep=\"{t:e}\" group=\"\" part=\"0\" file=\"{name}\"/>"
            )?;
        }
        writeln!(w, "</Collection>\n</VTKFile>")?;
        w.flush()
    }
}

fn write_vtp(w: &mut impl Write, frame: &Frame) -> std::io::Result<()> {
    let n = frame.ids.len();
    writeln!(w, "<?xml version=\"1.0\"?>")?;
    writeln!(
        w,
        "<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">"
    )?;
    writeln!(w, "<PolyData>")?;
    writeln!(w, "<Piece NumberOfPoints=\"{n}\" NumberOfVerts=\"{n}\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">")?;
    writeln!(
        w,
        "<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">"
    )?;
    for p in frame.positions {
        writeln!(w, "{:e} {:e} {:e}", p[0], p[1], p[2])?;
    }
    writeln!(w, "</DataArray></Points>")?;
    write_verts(w, n)?;
    let default_vectors = frame.vectors.first().map_or("", |v| v.0);
    writeln!(w, "<PointData Scalars=\"radius\" Vectors=\"{default_vectors}\">")?;
    writeln!(w, "<DataArray type=\"UInt64\" Name=\"id\" format=\"ascii\">")?;
    for id in frame.ids {
        write!(w, "{id} ")?;
    }
    writeln!(w, "\n</DataArray>")?;
    writeln!(w, "<DataArray type=\"Float64\" Name=\"radius\" format=\"ascii\">")?;
    for r in frame.radii {
        write!(w, "{r:e} ")?;
    }
    writeln!(w, "\n</DataArray>")?;
    for (name, values) in frame.vectors {
        writeln!(
            w,
            "<DataArray type=\"Float64\" Name=\"{name}\" NumberOfComponents=\"3\" format=\"ascii\">"
        )?;
        for v in values {
            writeln!(w, "{:e} {:e} {:e}", v[0], v[1], v[2])?;
        }
        writeln!(w, "</DataArray>")?;
    }
    writeln!(w, "</PointData>\n</Piece>\n</PolyData>\n</VTKFile>")
}

/// One vertex cell per point.
fn write_verts(w: &mut impl Write, n: usize) -> std::io::Result<()> {
    writeln!(
        w,
        "<Verts><DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">"
    )?;
    for i in 0..n {
        write!(w, "{i} ")?;
    }
    writeln!(
        w,
        "\n</DataArray><DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">"
    )?;
    for i in 1..=n {
        write!(w, "{i} ")?;
    }
    writeln!(w, "\n</DataArray></Verts>")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two particles: every array holds one entry per particle, the collection lists each step.
    #[test]
    fn a_frame_has_an_entry_per_particle_in_every_array() {
        let dir = std::env::temp_dir().join(format!("vtp-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let vectors = [
            ("velocity", vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]),
            ("fluid_force", vec![[0.5, 0.0, -0.5], [0.0; 3]]),
        ];
        let frame = Frame {
            ids: &[7, 9],
            positions: &[[0.1, 0.2, 0.3], [0.4, 0.5, 0.6]],
            radii: &[0.01, 0.02],
            vectors: &vectors,
        };
        let mut series = ParticleSeries::new(&dir);
        series.write(0, 0.0, &frame).unwrap();
        series.write(20, 0.5, &frame).unwrap();
        let text = std::fs::read_to_string(dir.join("particles_000020.vtp")).unwrap();
        assert!(text.contains("NumberOfPoints=\"2\""));
        assert!(text.contains("Vectors=\"velocity\""));
        assert!(text.contains("\n7 9 \n"), "ids");
        assert!(text.contains("Name=\"fluid_force\""));
        assert!(text.contains("5e-1 0e0 -5e-1\n0e0 0e0 0e0\n"), "fluid_force rows");
        let pvd = std::fs::read_to_string(dir.join("particles.pvd")).unwrap();
        assert_eq!(pvd.matches("<DataSet").count(), 2);
        assert!(pvd.contains("timestep=\"5e-1\"") && pvd.contains("particles_000020.vtp"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
