//! The checkpoint format that lbm-server and dem-client share (docs/checkpoint.md): OUT/checkpoint/
//! with header.json ([`Header`]) and the raw arrays and state files it lists, each with its size
//! and checksum; when one is due ([`Schedule`]); how one is put in place atomically and found and
//! checked again.
//!
//! - `header.rs`: header.json, where the outputs stood ([`OutputPositions`]).
//! - `schedule.rs`: every `output.checkpoint_interval` steps, every
//!   `output.checkpoint_wall_interval` minutes.
//! - `files.rs`: files written and synced with their checksum, the staging folder put in place
//!   (the previous checkpoint kept until then), the newest complete one found and checked.

mod files;
mod header;
mod schedule;

pub use files::{cut_back, files_besides, open_newest, put_in_place, staging_folder, write_synced};
pub use header::{scene_hash, FileEntry, Header, OutputPositions, FORMAT, VERSION};
pub use schedule::Schedule;

/// The folders of a run's checkpoints, in its output folder: the last complete one, the one being
/// written, and the one before while the new one replaces it.
pub const DIR: &str = "checkpoint";
pub const STAGING: &str = "checkpoint.staging";
pub const OLD: &str = "checkpoint.old";
/// The marker file a DEM writes last into the staging folder: its part is complete.
pub const DEM_COMPLETE: &str = "dem.complete";
