//! Checkpoints of a granular run alone (`dem-client run`, docs/checkpoint.md): OUT/checkpoint/
//! with dem.bin (the world's whole state, `checkpoint.rs`) and header.json (the format shared with
//! lbm-server: scene hash, step, sphere count, where particles.csv, energy.csv and the .vtp
//! series stood; lattice [0, 0, 0], storage "none"). Taken at the start of a step, before its
//! outputs: a run resumed from it writes what an uninterrupted one does from there.

use crate::checkpoint::{decode, encode, DEM_FILE};
use crate::dem::world::World;
use crate::output::{EnergyCsv, ParticleCsv, Vtk};
use scene::checkpoint::{put_in_place, staging_folder, write_synced, Header, OutputPositions, Schedule};
use std::path::{Path, PathBuf};

/// The checkpoints of one run.
pub struct RunCheckpoints {
    out: PathBuf,
    pub schedule: Schedule,
    scene_hash: String,
    /// `--checkpoint-interval`, given to this run or to the one it resumed.
    given: Option<u64>,
}

/// The outputs of a granular run, as a checkpoint records where they stand.
pub struct Outputs<'a> {
    pub csv: &'a ParticleCsv,
    pub energy: &'a mut EnergyCsv,
    pub vtk: Option<&'a Vtk>,
}

impl RunCheckpoints {
    /// The checkpoints of a run of `scene` into `out`, every `every` steps where given
    /// (`--checkpoint-interval`, or the one the run resumed from was given).
    pub fn new(out: &Path, scene: &scene::Scene, scene_text: &str, every: Option<u64>) -> Self {
        Self {
            out: out.to_path_buf(),
            schedule: Schedule::new(scene, every),
            scene_hash: scene::checkpoint::scene_hash(scene_text),
            given: every,
        }
    }

    /// Writes the checkpoint of `step` (the world's state at its start, the outputs before it),
    /// and says so; nothing where the run writes no checkpoints.
    pub fn write(&mut self, step: u64, world: &World, outputs: Outputs) -> Result<(), String> {
        if !self.schedule.enabled() {
            return Ok(());
        }
        outputs.energy.commit().map_err(|e| e.to_string())?;
        let mut at = OutputPositions::default();
        at.files.insert("particles.csv".into(), outputs.csv.kept());
        at.files.insert("energy.csv".into(), outputs.energy.kept());
        if let Some(vtk) = outputs.vtk {
            at.particles_pvd = vtk.frames().to_vec();
        }
        let staging = staging_folder(&self.out)?;
        let bytes = encode(step, world, &[]);
        let dem = write_synced(
            &staging.join(DEM_FILE),
            "dem",
            "dem",
            vec![bytes.len()],
            &[&bytes],
        )?;
        let header = Header {
            format: scene::checkpoint::FORMAT.into(),
            version: scene::checkpoint::VERSION,
            scene_hash: self.scene_hash.clone(),
            lattice: [0; 3],
            storage: "none".into(),
            step,
            time_s: world.time,
            particles: world.bodies.len() as u64,
            aa_phase: 0,
            face_scale: 1.0,
            covered_cells: None,
            checkpoint_interval: self.given,
            outputs: at,
            files: vec![dem],
        };
        put_in_place(&self.out, &header)?;
        self.schedule.written();
        protocol::say!(
            "dem-client: checkpoint at step {step} written to {}",
            self.out.join(scene::checkpoint::DIR).display()
        );
        Ok(())
    }
}

/// The newest checkpoint in `out`, checked against the scene (its text `scene_text`, its
/// `spheres`), restored into `world`: its header (its step, where the outputs stood, the
/// `--checkpoint-interval` its run was given).
pub fn resume(out: &Path, scene_text: &str, world: &mut World) -> Result<Header, String> {
    let (dir, header) = scene::checkpoint::open_newest(out)?;
    let hash = scene::checkpoint::scene_hash(scene_text);
    if header.scene_hash != hash {
        return Err(format!(
            "the checkpoint in {} is of another scene (scene.toml changed): hash {} there, {hash} in this run",
            dir.display(),
            header.scene_hash
        ));
    }
    if header.particles != world.bodies.len() as u64 {
        return Err(format!(
            "the checkpoint in {} is of another particle count: {} there, {} in this run",
            dir.display(),
            header.particles,
            world.bodies.len()
        ));
    }
    let path = dir.join(DEM_FILE);
    let bytes = std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    decode(&bytes, header.step, world).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(header)
}
