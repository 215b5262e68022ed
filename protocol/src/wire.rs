//! Per-step messages: `#[repr(C)]`, 8-byte aligned, no padding, so any language can map them
//! (and Rust cast them to and from bytes: bytemuck's `Pod`, whose derive refuses padding).

use iceoryx2::prelude::ZeroCopySend;

/// The state of one particle at the start of a step, sent DEM -> fluid (88 bytes).
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend, bytemuck::Pod, bytemuck::Zeroable)]
#[type_name("ParticleState")]
#[repr(C)]
pub struct ParticleState {
    /// Stable identifier chosen by the DEM side; unique among the particles of one step.
    pub id: u64,
    pub position: [f64; 3],
    pub velocity: [f64; 3],
    pub angular_velocity: [f64; 3],
    pub radius: f64,
}

/// The hydrodynamic load on one particle, sent fluid -> DEM (56 bytes), in the order of the states.
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend, bytemuck::Pod, bytemuck::Zeroable)]
#[type_name("ParticleReply")]
#[repr(C)]
pub struct ParticleReply {
    /// The id of the state this reply answers.
    pub id: u64,
    pub force: [f64; 3],
    pub torque: [f64; 3],
}

/// User header of both per-step messages (32 bytes).
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend, bytemuck::Pod, bytemuck::Zeroable)]
#[type_name("StepHeader")]
#[repr(C)]
pub struct StepHeader {
    /// Step index, starting at 0 and increasing by exactly 1.
    pub step: u64,
    /// Simulation time at the start of the step, in the client's time unit.
    pub time: f64,
    /// Number of particles in the slice that follows.
    pub count: u64,
    /// Bit set of [`StepFlags`].
    pub flags: u64,
}

impl StepHeader {
    pub fn new(step: u64, time: f64, count: usize, flags: u64) -> Self {
        Self {
            step,
            time,
            count: count as u64,
            flags,
        }
    }

    pub fn has(&self, flag: u64) -> bool {
        self.flags & flag != 0
    }
}

/// Flags of [`StepHeader::flags`].
pub struct StepFlags;

impl StepFlags {
    /// Sender wants the run to end after this step (Ctrl-C, a failed health check, ...).
    pub const STOP: u64 = 1;
    /// Fluid -> DEM: this is the reply of the last step of the run.
    pub const FINAL: u64 = 2;
    /// Fluid -> DEM (protocol version 2, only to a DEM with `Capabilities::CHECKPOINT`): write your
    /// whole state for the next step (n + 1) into the checkpoint folder before sending its states;
    /// their arrival tells the fluid that the DEM's part of the checkpoint is complete.
    pub const CHECKPOINT: u64 = 4;
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::mem::{align_of, offset_of, size_of};

    #[test]
    fn layouts_are_the_documented_ones() {
        assert_eq!(size_of::<ParticleState>(), 88);
        assert_eq!(align_of::<ParticleState>(), 8);
        assert_eq!(offset_of!(ParticleState, position), 8);
        assert_eq!(offset_of!(ParticleState, velocity), 32);
        assert_eq!(offset_of!(ParticleState, angular_velocity), 56);
        assert_eq!(offset_of!(ParticleState, radius), 80);
        assert_eq!(size_of::<ParticleReply>(), 56);
        assert_eq!(offset_of!(ParticleReply, force), 8);
        assert_eq!(offset_of!(ParticleReply, torque), 32);
        assert_eq!(size_of::<StepHeader>(), 32);
        assert_eq!(offset_of!(StepHeader, count), 16);
        assert_eq!(offset_of!(StepHeader, flags), 24);
    }
}
