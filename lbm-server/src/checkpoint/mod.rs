//! The fluid's checkpoints: OUT/checkpoint/, from which `lbm-server run --resume OUT` goes on
//! bit-identically (docs/checkpoint.md; the format, shared with dem-client, is
//! `scene::checkpoint`'s).
//!
//! - `checkpoints.rs`: a run's checkpoints ([`Checkpoints`]): when they are due, the header, the
//!   lattice's state taken off the device and handed to the writer.
//! - `write.rs`: the writer: the arrays written into OUT/checkpoint.staging on a thread while the
//!   run goes on, with the DEM's files found there, then put in place.
//! - `read.rs`: a checkpoint read back ([`Loaded`]) and compared with the run ([`Expected`]).

mod checkpoints;
mod read;
mod write;

pub use checkpoints::Checkpoints;
pub use read::{Expected, Loaded};
pub use scene::checkpoint::{OutputPositions, DIR, OLD, STAGING};
