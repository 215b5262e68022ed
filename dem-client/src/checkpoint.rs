//! The DEM's part of a checkpoint (docs/checkpoint.md): dem.bin, the world's whole state
//! (`dem/world/saved.rs`) after a header (magic, format version, the step it is the state of, the
//! sphere count) and, coupled, the counters of the coupled particles. Coupled, the fluid asks for
//! it with `StepFlags::CHECKPOINT` and names the folders in the environment; alone
//! (`dem-client run`), the run writes whole checkpoints itself (`run_checkpoint.rs`).

use crate::connect::CoupledParticles;
use crate::dem::bytes::{Decoder, Encoder};
use crate::dem::world::World;
use std::path::{Path, PathBuf};

/// The DEM's file in a checkpoint folder.
pub const DEM_FILE: &str = "dem.bin";
/// First 8 bytes of dem.bin, and its format version.
const MAGIC: &[u8; 8] = b"LBDMDEM\0";
const VERSION: u64 = 1;

/// Where a fluid that starts the DEM names the staging folder to write into when asked, and the
/// folder of the checkpoint a resumed run goes on from (PROTOCOL.md 6.4).
pub const CHECKPOINT_DIR_ENV: &str = "LBMDEM_CHECKPOINT_DIR";
pub const RESUME_DIR_ENV: &str = "LBMDEM_RESUME_DIR";

/// A folder given as an argument, else in the environment variable `env`.
pub fn folder(arg: Option<&PathBuf>, env: &str) -> Option<PathBuf> {
    arg.cloned()
        .or_else(|| std::env::var_os(env).filter(|v| !v.is_empty()).map(PathBuf::from))
}

/// dem.bin's bytes: the header, the world, and `extra` (the coupled counters, or nothing).
pub fn encode(step: u64, world: &World, extra: &[u64]) -> Vec<u8> {
    let mut e = Encoder::default();
    e.bytes.extend_from_slice(MAGIC);
    e.u64(VERSION);
    e.u64(step);
    e.u64(world.bodies.len() as u64);
    world.save(&mut e);
    e.list(extra, |e, v| e.u64(*v));
    e.bytes
}

/// Restores `world` from dem.bin's `bytes`, which must be the state of `step`; the extra
/// counters.
pub fn decode(bytes: &[u8], step: u64, world: &mut World) -> Result<Vec<u64>, String> {
    if bytes.len() < 8 || &bytes[..8] != MAGIC {
        return Err("dem.bin is not a dem-client state (bad magic)".into());
    }
    let mut d = Decoder::new(&bytes[8..]);
    let version = d.u64()?;
    if version != VERSION {
        return Err(format!(
            "dem.bin is of format version {version}, this dem-client reads {VERSION}"
        ));
    }
    let saved = d.u64()?;
    if saved != step {
        return Err(format!(
            "dem.bin holds the state of step {saved}, the run resumes at step {step}"
        ));
    }
    let _spheres = d.u64()?;
    world.restore(&mut d)?;
    let extra = d.list(|d| d.u64())?;
    if !d.done() {
        return Err("dem.bin has bytes after its end (corrupt)".into());
    }
    Ok(extra)
}

/// Writes dem.bin into `dir` (synced): the coupled particles' state for `step`; then the marker
/// that the DEM's part is complete.
pub fn write_coupled(dir: &Path, step: u64, particles: &CoupledParticles) -> Result<(), String> {
    let bytes = encode(step, &particles.world, &particles.counters());
    let path = dir.join(DEM_FILE);
    scene::checkpoint::write_synced(&path, "dem", "dem", vec![bytes.len()], &[&bytes])?;
    let marker = dir.join(scene::checkpoint::DEM_COMPLETE);
    scene::checkpoint::write_synced(&marker, "dem.complete", "dem", vec![0], &[])?;
    Ok(())
}

/// Reads the coupled particles' state of `step` from dem.bin in `dir`.
pub fn read_coupled(dir: &Path, step: u64, particles: &mut CoupledParticles) -> Result<(), String> {
    let path = dir.join(DEM_FILE);
    let bytes = std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let extra = decode(&bytes, step, &mut particles.world).map_err(|e| format!("{}: {e}", path.display()))?;
    particles.set_counters(&extra)
}
