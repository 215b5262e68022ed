//! Wire protocol of the LBM-DEM co-simulation.
//!
//! Two processes step in lockstep: the DEM side publishes the particle states of step `n`, the
//! fluid side replies with the hydrodynamic force and torque of step `n`, and only then does the
//! DEM side advance to `n + 1`. `PROTOCOL.md` at the repository root is the language-neutral
//! specification; this crate is the reference implementation over iceoryx2 shared memory.

pub mod cleanup;
pub mod handshake;
pub mod liveness;
pub mod squeeze_film;
pub mod substep_drag;
pub mod transport;
pub mod wire;

pub use handshake::{Capabilities, Hello, Physics, Status, Units, Welcome, PROTOCOL_VERSION};
pub use transport::{DemLink, FluidLink, LinkError, Peer};
pub use wire::{ParticleReply, ParticleState, StepFlags, StepHeader};

/// Writes one line to stderr in a single write, so that the two processes of a run, which share
/// a terminal, never interleave within a line.
pub fn write_line(line: &str) {
    use std::io::Write;
    let _ = std::io::stderr().write_all(format!("{line}\n").as_bytes());
}

/// `eprintln!` for the co-simulation's processes: one write per line (see [`write_line`]).
#[macro_export]
macro_rules! say {
    ($($arg:tt)*) => { $crate::write_line(&format!($($arg)*)) };
}
