//! What a run leaves behind: OUT/particles.csv (and the .vtp series) and the lattice as the
//! summaries report it. A coupled run's summary.json is `run/summary.rs`'s; what it says on the
//! terminal is `terminal.rs`'s.

use crate::checkpoint::OutputPositions;
use protocol::{ParticleReply, ParticleState};
use scene::row_file::RowFile;
use serde::Serialize;
use std::io::Write;
use std::path::Path;

/// The particles of a coupled run at its output steps, SI units: particles.csv (one row per
/// particle per output step, header row first; each step's rows written whole, at once, so a crash
/// leaves whole rows) and, with `dem.output.vtk`, particles_NNNNNN.vtp
/// + particles.pvd for ParaView (each particle's state and the fluid's load on it).
pub struct ParticleOutput {
    rows: RowFile,
    vtk: Option<scene::vtp::ParticleSeries>,
}

impl ParticleOutput {
    pub const HEADER: &'static str = "step,time,id,x,y,z,vx,vy,vz,wx,wy,wz,fx,fy,fz,tx,ty,tz";

    /// particles.csv in `out`, with its header; the .vtp series where `vtk`.
    pub fn create(out: &Path, vtk: bool) -> std::io::Result<Self> {
        let rows = RowFile::create(&out.join("particles.csv"), Self::HEADER)?;
        let vtk = vtk.then(|| scene::vtp::ParticleSeries::new(out));
        Ok(Self { rows, vtk })
    }

    /// particles.csv (and the .vtp series where `vtk`) of a resumed run, as they stood `at` its
    /// checkpoint: the rows written after it cut off.
    pub fn resume(out: &Path, vtk: bool, at: &OutputPositions) -> Result<Self, String> {
        let kept = *at
            .files
            .get("particles.csv")
            .ok_or("the checkpoint does not record where particles.csv stood")?;
        let rows = RowFile::resume(&out.join("particles.csv"), kept).map_err(|e| e.to_string())?;
        let vtk = match vtk {
            true => Some(
                scene::vtp::ParticleSeries::resume(out, at.particles_pvd.clone())
                    .map_err(|e| format!("particles.pvd: {e}"))?,
            ),
            false => None,
        };
        Ok(Self { rows, vtk })
    }

    /// Where particles.csv and the .vtp series stand, into `at` (a checkpoint's).
    pub fn positions(&self, at: &mut OutputPositions) {
        at.files.insert("particles.csv".into(), self.rows.kept());
        if let Some(vtk) = &self.vtk {
            at.particles_pvd = vtk.frames().to_vec();
        }
    }

    /// Writes the particles of one step (states and replies in SI, same order); an error names
    /// the file.
    pub fn write_step(
        &mut self,
        step: u64,
        time: f64,
        states: &[ParticleState],
        replies: &[ParticleReply],
    ) -> Result<(), String> {
        self.write_rows(step, time, states, replies)
            .map_err(|e| e.to_string())?;
        let Some(vtk) = &mut self.vtk else {
            return Ok(());
        };
        let ids: Vec<u64> = states.iter().map(|s| s.id).collect();
        let positions: Vec<[f64; 3]> = states.iter().map(|s| s.position).collect();
        let radii: Vec<f64> = states.iter().map(|s| s.radius).collect();
        let vectors = [
            ("velocity", states.iter().map(|s| s.velocity).collect()),
            (
                "angular_velocity",
                states.iter().map(|s| s.angular_velocity).collect(),
            ),
            ("fluid_force", replies.iter().map(|r| r.force).collect()),
            ("fluid_torque", replies.iter().map(|r| r.torque).collect()),
        ];
        let frame = scene::vtp::Frame {
            ids: &ids,
            positions: &positions,
            radii: &radii,
            vectors: &vectors,
        };
        vtk.write(step, time, &frame)
            .map_err(|e| format!("particles_{step:06}.vtp: {e}"))
    }

    fn write_rows(
        &mut self,
        step: u64,
        time: f64,
        states: &[ParticleState],
        replies: &[ParticleReply],
    ) -> std::io::Result<()> {
        let w = self.rows.staged();
        for (s, r) in states.iter().zip(replies) {
            write!(w, "{step},{time:e},{}", s.id)?;
            for v in [s.position, s.velocity, s.angular_velocity, r.force, r.torque] {
                write!(w, ",{:e},{:e},{:e}", v[0], v[1], v[2])?;
            }
            writeln!(w)?;
        }
        self.rows.commit()
    }
}

/// The lattice of a coupled run, as summary.json reports it.
#[derive(Debug, Clone, Serialize)]
pub struct LatticeSummary {
    pub cells: [usize; 3],
    pub dx_m: f64,
    pub dt_s: f64,
    pub tau: f64,
    pub mach: f64,
    pub operator: String,
    /// TRT's magic parameter as used (`lattice.magic`, lowered by `lattice.max_tau_minus`) and
    /// the antisymmetric relaxation time it gives.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub magic: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tau_minus: Option<f64>,
    /// `lattice.ramp_time`: the inlets and moving walls rise from rest over it.
    pub ramp_time_s: f64,
}

impl LatticeSummary {
    pub fn of(u: &scene::lattice::LatticeUnits) -> Self {
        let trt = u.operator == scene::lattice::CollisionOperator::Trt;
        Self {
            cells: u.n,
            dx_m: u.dx,
            dt_s: u.dt,
            tau: u.tau,
            mach: u.mach,
            operator: u.operator.to_string(),
            magic: trt.then_some(u.magic),
            tau_minus: trt.then(|| crate::lbm::geometry::tau_minus(u.magic, u.tau)),
            ramp_time_s: u.seconds(u.ramp_steps),
        }
    }
}

/// The fluid program and its version, for the summaries.
pub fn software() -> String {
    format!("lbm-server {}", env!("CARGO_PKG_VERSION"))
}

/// Seconds since 1970-01-01 UTC (0 if the clock is before it).
pub fn unix_seconds() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs())
}
