//! Outputs of `dem-client run`: particles.csv, energy.csv, VTK polydata (.vtp + .pvd).

use crate::dem::world::World;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Same columns as lbm-server's particles.csv; f and t are the contact force and torque.
pub struct ParticleCsv(BufWriter<File>);

impl ParticleCsv {
    pub fn create(path: &Path) -> std::io::Result<Self> {
        let mut w = BufWriter::new(File::create(path)?);
        writeln!(w, "step,time,id,x,y,z,vx,vy,vz,wx,wy,wz,fx,fy,fz,tx,ty,tz")?;
        Ok(Self(w))
    }

    pub fn write(&mut self, step: u64, world: &World) -> std::io::Result<()> {
        for b in &world.bodies {
            write!(self.0, "{step},{:e},{}", world.time, b.id)?;
            for v in [b.x, b.v, b.w, b.f, b.t] {
                write!(self.0, ",{:e},{:e},{:e}", v.x, v.y, v.z)?;
            }
            writeln!(self.0)?;
        }
        Ok(())
    }

    pub fn flush(&mut self) -> std::io::Result<()> {
        self.0.flush()
    }
}

/// step,time,kinetic_energy,contacts.
pub struct EnergyCsv(BufWriter<File>);

impl EnergyCsv {
    pub fn create(path: &Path) -> std::io::Result<Self> {
        let mut w = BufWriter::new(File::create(path)?);
        writeln!(w, "step,time,kinetic_energy,contacts")?;
        Ok(Self(w))
    }

    pub fn write(&mut self, step: u64, world: &World) -> std::io::Result<()> {
        writeln!(
            self.0,
            "{step},{:e},{:e},{}",
            world.time,
            world.kinetic_energy(),
            world.contact_count()
        )
    }

    pub fn flush(&mut self) -> std::io::Result<()> {
        self.0.flush()
    }
}

/// particles_NNNNNN.vtp files and the particles.pvd collection that ParaView opens.
pub struct Vtk {
    dir: PathBuf,
    frames: Vec<(f64, String)>,
}

impl Vtk {
    pub fn new(dir: &Path) -> Self {
        Self {
            dir: dir.to_path_buf(),
            frames: Vec::new(),
        }
    }

    pub fn write(&mut self, step: u64, world: &World) -> std::io::Result<()> {
        let name = format!("particles_{step:06}.vtp");
        let mut w = BufWriter::new(File::create(self.dir.join(&name))?);
        write_vtp(&mut w, world)?;
        w.flush()?;
        self.frames.push((world.time, name));
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

/// A per-particle vector of the VTK output.
type Field = fn(&crate::dem::world::Body) -> crate::dem::V3;

fn write_vtp(w: &mut impl Write, world: &World) -> std::io::Result<()> {
    let n = world.bodies.len();
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
    for b in &world.bodies {
        writeln!(w, "{:e} {:e} {:e}", b.x.x, b.x.y, b.x.z)?;
    }
    writeln!(w, "</DataArray></Points>")?;
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
    writeln!(w, "\n</DataArray></Verts>")?;
    writeln!(w, "<PointData Scalars=\"radius\" Vectors=\"velocity\">")?;
    writeln!(w, "<DataArray type=\"UInt64\" Name=\"id\" format=\"ascii\">")?;
    for b in &world.bodies {
        write!(w, "{} ", b.id)?;
    }
    writeln!(w, "\n</DataArray>")?;
    writeln!(w, "<DataArray type=\"Float64\" Name=\"radius\" format=\"ascii\">")?;
    for b in &world.bodies {
        write!(w, "{:e} ", b.r)?;
    }
    writeln!(w, "\n</DataArray>")?;
    let vectors: [(&str, Field); 4] = [
        ("velocity", |b| b.v),
        ("angular_velocity", |b| b.w),
        ("contact_force", |b| b.f),
        ("contact_torque", |b| b.t),
    ];
    for (name, get) in vectors {
        writeln!(
            w,
            "<DataArray type=\"Float64\" Name=\"{name}\" NumberOfComponents=\"3\" format=\"ascii\">"
        )?;
        for b in &world.bodies {
            let v = get(b);
            writeln!(w, "{:e} {:e} {:e}", v.x, v.y, v.z)?;
        }
        writeln!(w, "</DataArray>")?;
    }
    writeln!(w, "</PointData>\n</Piece>\n</PolyData>\n</VTKFile>")
}
