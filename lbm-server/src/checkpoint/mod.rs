//! Checkpoints: OUT/checkpoint/, from which `lbm-server run --resume OUT` goes on bit-identically
//! (docs/checkpoint.md).
//!
//! - `header.rs`: what header.json says ([`Header`]): format version, scene hash, lattice,
//!   storage, step, counts, where each output file stood ([`OutputPositions`]), and each file of
//!   the checkpoint with its size and checksum.
//! - `schedule.rs`: when one is due ([`Schedule`]: every `output.checkpoint_interval` steps,
//!   every `output.checkpoint_wall_interval` minutes, at the end and on Ctrl-C).
//! - `write.rs`: written atomically ([`Writer`]): into OUT/checkpoint.staging, from a copy of the
//!   state taken off the device, on a thread while the run goes on; checksums; then renamed over
//!   OUT/checkpoint, the previous one kept (checkpoint.old) until the new one is complete.
//! - `checkpoints.rs`: a run's checkpoints ([`Checkpoints`]): the schedule, the header, the
//!   state taken off the device and handed to the writer.
//! - `read.rs`: read back and checked ([`Loaded`]): the newest complete one, every file's size
//!   and checksum, the scene, lattice, storage and particle count against the run's.

mod checkpoints;
mod header;
mod read;
mod schedule;
mod write;

pub use checkpoints::Checkpoints;
pub use header::{scene_hash, OutputPositions};
pub use read::{Expected, Loaded};

/// The folders of a run's checkpoints, in its output folder: the last complete one, the one being
/// written, and the one before while the new one replaces it.
pub const DIR: &str = "checkpoint";
pub const STAGING: &str = "checkpoint.staging";
pub const OLD: &str = "checkpoint.old";
