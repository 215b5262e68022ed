//! Outputs of `dem-client run`: particles.csv, energy.csv, VTK polydata (.vtp + .pvd).

use crate::dem::world::World;
use scene::checkpoint::OutputPositions;
use scene::row_file::RowFile;
use std::io::Write;
use std::path::Path;

/// Same columns as lbm-server's particles.csv; f and t are the contact force and torque. Each
/// step's rows reach the file whole, at once (a crash leaves whole rows).
pub struct ParticleCsv(RowFile);

impl ParticleCsv {
    pub fn create(path: &Path) -> std::io::Result<Self> {
        RowFile::create(path, "step,time,id,x,y,z,vx,vy,vz,wx,wy,wz,fx,fy,fz,tx,ty,tz").map(Self)
    }

    /// particles.csv of a resumed run, cut back to where its checkpoint found it.
    pub fn resume(path: &Path, at: &OutputPositions) -> Result<Self, String> {
        resumed(path, at).map(Self)
    }

    /// Bytes of whole rows in the file.
    pub fn kept(&self) -> u64 {
        self.0.kept()
    }

    pub fn write(&mut self, step: u64, world: &World) -> std::io::Result<()> {
        let w = self.0.staged();
        for b in &world.bodies {
            write!(w, "{step},{:e},{}", world.time, b.id)?;
            for v in [b.x, b.v, b.w, b.f, b.t] {
                write!(w, ",{:e},{:e},{:e}", v.x, v.y, v.z)?;
            }
            writeln!(w)?;
        }
        self.0.commit()
    }
}

/// step,time,kinetic_energy,contacts: a row every step, written to the file at each `commit`.
pub struct EnergyCsv(RowFile);

impl EnergyCsv {
    pub fn create(path: &Path) -> std::io::Result<Self> {
        RowFile::create(path, "step,time,kinetic_energy,contacts").map(Self)
    }

    /// energy.csv of a resumed run, cut back to where its checkpoint found it.
    pub fn resume(path: &Path, at: &OutputPositions) -> Result<Self, String> {
        resumed(path, at).map(Self)
    }

    /// Bytes of whole rows in the file (after a `commit`, all written).
    pub fn kept(&self) -> u64 {
        self.0.kept()
    }

    pub fn write(&mut self, step: u64, world: &World) -> std::io::Result<()> {
        writeln!(
            self.0.staged(),
            "{step},{:e},{:e},{}",
            world.time,
            world.kinetic_energy(),
            world.contact_count()
        )
    }

    /// Writes the rows since the last commit (at each output step and at the end).
    pub fn commit(&mut self) -> std::io::Result<()> {
        self.0.commit()
    }
}

/// particles_NNNNNN.vtp files and the particles.pvd collection that ParaView opens.
pub struct Vtk(scene::vtp::ParticleSeries);

impl Vtk {
    pub fn new(dir: &Path) -> Self {
        Self(scene::vtp::ParticleSeries::new(dir))
    }

    /// The series of a resumed run: the frames its checkpoint lists.
    pub fn resume(dir: &Path, at: &OutputPositions) -> Result<Self, String> {
        scene::vtp::ParticleSeries::resume(dir, at.particles_pvd.clone())
            .map(Self)
            .map_err(|e| format!("particles.pvd: {e}"))
    }

    /// The frames so far (time, file).
    pub fn frames(&self) -> &[(f64, String)] {
        self.0.frames()
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

/// The row file at `path` reopened where the checkpoint `at` found it.
fn resumed(path: &Path, at: &OutputPositions) -> Result<RowFile, String> {
    let name = path.file_name().unwrap_or_default().to_string_lossy();
    let kept = *at
        .files
        .get(name.as_ref())
        .ok_or_else(|| format!("the checkpoint does not record where {name} stood"))?;
    RowFile::resume(path, kept).map_err(|e| e.to_string())
}
