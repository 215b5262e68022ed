//! A fluid checkpoint read back for `--resume`: the newest complete one, every file checked
//! (`scene::checkpoint::open_newest`) before anything is overwritten, and what it was written for
//! compared with the run.

use crate::lbm::gpu::RawState;
use scene::checkpoint::Header;
use std::path::{Path, PathBuf};

/// A checkpoint found and checked.
#[derive(Clone)]
pub struct Loaded {
    pub dir: PathBuf,
    pub header: Header,
}

/// What a run expects of the checkpoint it resumes from.
pub struct Expected<'a> {
    pub scene_text: &'a str,
    pub lattice: [usize; 3],
    pub storage: &'a str,
    /// The particle count where the run knows it (a fluid-only run: 0; a coupled one learns it
    /// from the DEM's Hello).
    pub particles: Option<u64>,
}

impl Loaded {
    /// The newest complete checkpoint in `out`, its header read and every file checked.
    pub fn open(out: &Path) -> Result<Loaded, String> {
        let (dir, header) = scene::checkpoint::open_newest(out)?;
        Ok(Loaded { dir, header })
    }

    /// The run and the checkpoint must agree on the scene, lattice, storage and particle count:
    /// else an error naming what differs.
    pub fn check_run(&self, run: &Expected) -> Result<(), String> {
        let h = &self.header;
        let differs = |what: &str, theirs: String, ours: String| {
            Err(format!(
                "the checkpoint in {} is of another {what}: {theirs} there, {ours} in this run",
                self.dir.display()
            ))
        };
        let hash = scene::checkpoint::scene_hash(run.scene_text);
        if h.scene_hash != hash {
            return differs(
                "scene (scene.toml changed)",
                format!("hash {}", h.scene_hash),
                format!("hash {hash}"),
            );
        }
        if h.lattice != run.lattice {
            return differs(
                "lattice",
                format!("{:?} cells", h.lattice),
                format!("{:?}", run.lattice),
            );
        }
        if h.storage != run.storage {
            return differs("lattice.storage", h.storage.clone(), run.storage.to_string());
        }
        if let Some(particles) = run.particles.filter(|p| *p != h.particles) {
            return differs("particle count", h.particles.to_string(), particles.to_string());
        }
        Ok(())
    }

    /// The lattice's state: the populations and status words, the clock and the faces' ramp.
    pub fn raw_state(&self, population_bytes: usize) -> Result<RawState, String> {
        let populations = self.array("populations")?;
        if populations.len() != 19 * population_bytes {
            return Err(format!(
                "checkpoint: populations.bin holds {} bytes, the lattice needs {}",
                populations.len(),
                19 * population_bytes
            ));
        }
        Ok(RawState {
            populations: populations.chunks(population_bytes).map(<[u8]>::to_vec).collect(),
            status: self.array("status")?,
            time: self.header.step,
            face_scale: self.header.face_scale,
        })
    }

    /// The bytes of the array `name`.
    fn array(&self, name: &str) -> Result<Vec<u8>, String> {
        let entry = self
            .header
            .files
            .iter()
            .find(|f| f.name == name)
            .ok_or_else(|| format!("checkpoint: {} has no array '{name}'", self.dir.display()))?;
        let path = self.dir.join(&entry.file);
        std::fs::read(&path).map_err(|e| format!("checkpoint: {}: {e}", path.display()))
    }
}
