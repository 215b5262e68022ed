//! Outputs of `dem-client run`: particles.csv, energy.csv, VTK polydata (.vtp + .pvd).

use crate::dem::world::World;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

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
pub struct Vtk(scene::vtp::ParticleSeries);

impl Vtk {
    pub fn new(dir: &Path) -> Self {
        Self(scene::vtp::ParticleSeries::new(dir))
    }

    /// The world's spheres with their velocity, angular velocity and contact force and torque.
    pub fn write(&mut self, step: u64, world: &World) -> std::io::Result<()> {
        let bodies = &world.bodies;
        let ids: Vec<u64> = bodies.iter().map(|b| b.id).collect();
        let positions: Vec<[f64; 3]> = bodies.iter().map(|b| b.x.into()).collect();
        let radii: Vec<f64> = bodies.iter().map(|b| b.r).collect();
        let vector = |get: fn(&crate::dem::world::Body) -> crate::dem::V3| -> Vec<[f64; 3]> {
            bodies.iter().map(|b| get(b).into()).collect()
        };
        let vectors = [
            ("velocity", vector(|b| b.v)),
            ("angular_velocity", vector(|b| b.w)),
            ("contact_force", vector(|b| b.f)),
            ("contact_torque", vector(|b| b.t)),
        ];
        let frame = scene::vtp::Frame {
            ids: &ids,
            positions: &positions,
            radii: &radii,
            vectors: &vectors,
        };
        self.0.write(step, world.time, &frame)
    }
}
