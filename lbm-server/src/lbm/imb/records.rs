//! What crosses between host and device each coupled step: the particles in lattice units
//! ([`SolidParticle`], or any [`SolidParticles`]) and their GPU records, the loads that come back, the
//! covers lost, and the sizes of the coupling's buffers per record.

/// A particle in lattice units (cell i spans [i, i + 1] along each axis).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SolidParticle {
    pub position: [f64; 3],
    pub radius: f64,
    pub velocity: [f64; 3],
    pub angular_velocity: [f64; 3],
}

/// Covers lost since the start of a coupled run ([`GpuLattice::lost_covers`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LostCovers {
    /// Particle-cell covers beyond a cell's slots (dropped; the run warns).
    pub dropped: u32,
    /// Covered cells beyond the list of covered cells (the run stops).
    pub unlisted: u32,
}

/// Force and torque on a particle over one step, in lattice units.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Load {
    pub force: [f64; 3],
    pub torque: [f64; 3],
}

/// The particles of a coupled step in lattice units, by index: a slice of [`SolidParticle`]s, or
/// a DEM's states converted as the step reads them (no copy in between: the host's passes over
/// the particles are part of every coupled step, docs/imb.md "Speed").
pub trait SolidParticles: Sync {
    fn count(&self) -> usize;
    fn particle(&self, j: usize) -> SolidParticle;
    /// Particle j's radius (the step sizes the pair ranges from the radii first).
    fn radius(&self, j: usize) -> f64 {
        self.particle(j).radius
    }
}

impl SolidParticles for [SolidParticle] {
    fn count(&self) -> usize {
        self.len()
    }
    fn particle(&self, j: usize) -> SolidParticle {
        self[j]
    }
    fn radius(&self, j: usize) -> f64 {
        self[j].radius
    }
}

/// The shader's `Particle`: what goes to the GPU each step (48 bytes).
#[repr(C)]
#[derive(Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct GpuParticle {
    pub(super) pos_r: [f32; 4],
    pub(super) vel: [f32; 3],
    pub(super) first: u32,
    pub(super) omega: [f32; 3],
    pub(super) edge: u32,
}

/// The shader's loads: force and torque, what comes back each step (24 bytes).
pub(super) type GpuLoad = [f32; 6];

pub(super) const PARTICLE_BYTES: u64 = std::mem::size_of::<GpuParticle>() as u64;
pub(super) const LOAD_BYTES: u64 = std::mem::size_of::<GpuLoad>() as u64;
/// imb_loads.wgsl's SLICES: `reduce`'s invocations per particle, each with its partial load after the
/// particles' loads in the loads buffer.
pub(super) const REDUCE_SLICES: u32 = 8;
/// Bytes of the loads buffer per particle: its load and its slices' partial loads.
pub(super) const LOADS_BUFFER_BYTES: u64 = LOAD_BYTES * (1 + REDUCE_SLICES as u64);
/// The shader's pair: one vec4 per cell of a particle's bounding box.
pub(super) const PAIR_BYTES: u64 = 16;
/// An entry of the shader's `saved`: a covered cell and its 19 populations (over the `fields` buffer).
pub(super) const SAVED_BYTES: u64 = 80;

/// Most particles a coupled step takes: imb.wgsl's `slot_key` holds 24-bit particle indices.
pub(super) const MAX_PARTICLES: usize = 1 << 24;
