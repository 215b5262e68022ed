//! header.json of a checkpoint: what it holds and where the run's outputs stood.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// The format's name and version (a checkpoint of another version is refused).
pub const FORMAT: &str = "lbm-dem checkpoint";
pub const VERSION: u32 = 1;

/// header.json.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Header {
    /// [`FORMAT`] and [`VERSION`].
    pub format: String,
    pub version: u32,
    /// FNV-1a 64 of the run's scene.toml ([`scene_hash`]).
    pub scene_hash: String,
    /// Cells along x, y, z ([0, 0, 0]: a granular run alone).
    pub lattice: [usize; 3],
    /// `lattice.storage`: fp32, fp16s or fp16c ("none": a granular run alone).
    pub storage: String,
    /// Steps completed: the run goes on with this step.
    pub step: u64,
    /// Simulated time [s] of `step`.
    pub time_s: f64,
    /// Particles at `step` (0 in a fluid-only run).
    pub particles: u64,
    /// The AA pattern's phase of the populations (`step` % 2): 0, each cell's f_i in slot i.
    pub aa_phase: u64,
    /// The share of their velocity the inlets and moving walls had (their ramp).
    pub face_scale: f64,
    /// Where the covered cells took their solid term (coupled runs: fused, redo or skip).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub covered_cells: Option<String>,
    /// The step interval given on the command line (`--checkpoint-interval`), which a resumed run
    /// keeps unless given another.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub checkpoint_interval: Option<u64>,
    /// Where the outputs stood.
    pub outputs: OutputPositions,
    /// Each file of the checkpoint: the fluid's arrays, then the DEM's files.
    pub files: Vec<FileEntry>,
}

/// A file of a checkpoint: raw little-endian array (`dtype` as numpy names it, C-order `shape`),
/// or the DEM's state (`dtype` "dem").
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FileEntry {
    pub name: String,
    pub file: String,
    pub dtype: String,
    pub shape: Vec<usize>,
    pub bytes: u64,
    /// FNV-1a 64 of its bytes, 16 hex digits (`scene::checksum`).
    pub checksum: String,
}

/// Where a run's outputs stood at a checkpoint: each appended file's length in bytes
/// (particles.csv, line<N>.csv), and the entries of each .pvd series.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct OutputPositions {
    pub files: BTreeMap<String, u64>,
    pub fields_pvd: Vec<(f64, String)>,
    pub particles_pvd: Vec<(f64, String)>,
}

impl OutputPositions {
    /// The output file `name` in `out`, opened to go on at its recorded length (what is after it
    /// is cut off by `cut_back`).
    pub fn reopen(&self, out: &Path, name: &str) -> Result<std::fs::File, String> {
        let kept = *self
            .files
            .get(name)
            .ok_or_else(|| format!("the checkpoint does not record where {name} stood"))?;
        let rows = crate::row_file::RowFile::resume(&out.join(name), kept).map_err(|e| e.to_string())?;
        Ok(rows.into_file())
    }
}

/// The scene hash of a checkpoint: FNV-1a 64 of the scene file's text.
pub fn scene_hash(text: &str) -> String {
    crate::checksum::fnv1a64(text.as_bytes())
}
