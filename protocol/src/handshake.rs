//! The handshake: `Hello` (DEM -> fluid) and `Welcome` (fluid -> DEM), sent as byte slices so that
//! any two versions can always read each other's version number and refuse cleanly.

use core::mem::size_of;

/// Version of this protocol. Bump on any change of a message layout or of the step rules.
/// Version 2: Hello's `capabilities`, Welcome's `first_step` and `cell_size`, the step flag
/// `CHECKPOINT` (PROTOCOL.md 6.4).
pub const PROTOCOL_VERSION: u32 = 2;

/// The oldest version this build still speaks: a fluid answers a version-1 Hello with a
/// version-1 Welcome (no `first_step`, `cell_size`; no CHECKPOINT flags, no resumed runs).
pub const OLDEST_VERSION: u32 = 1;

/// First four bytes of every handshake message: ASCII "LBDM" read as a little-endian u32.
pub const MAGIC: u32 = u32::from_le_bytes(*b"LBDM");

/// Length of the fixed prefix (magic, version, size, kind) that every version keeps.
pub const PREFIX_LEN: usize = 16;

/// Message kinds in the prefix.
pub const KIND_HELLO: u32 = 1;
pub const KIND_WELCOME: u32 = 2;

/// Length of the text fields (software name, refusal reason), NUL padded UTF-8.
pub const TEXT_LEN: usize = 64;

/// The units a side speaks, each as its size in SI. All wire quantities are in the DEM side's units.
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct Units {
    pub length_m: f64,
    pub time_s: f64,
    pub mass_kg: f64,
}

impl Units {
    pub const SI: Units = Units {
        length_m: 1.0,
        time_s: 1.0,
        mass_kg: 1.0,
    };

    pub fn is_valid(&self) -> bool {
        [self.length_m, self.time_s, self.mass_kg]
            .iter()
            .all(|v| v.is_finite() && *v > 0.0)
    }

    /// SI value of one unit of velocity.
    pub fn velocity(&self) -> f64 {
        self.length_m / self.time_s
    }

    /// SI value of one unit of force.
    pub fn force(&self) -> f64 {
        self.mass_kg * self.length_m / (self.time_s * self.time_s)
    }

    /// SI value of one unit of torque.
    pub fn torque(&self) -> f64 {
        self.force() * self.length_m
    }

    /// A state in these units, converted to SI.
    pub fn state_to_si(&self, s: &crate::ParticleState) -> crate::ParticleState {
        let (l, v, w) = (self.length_m, self.velocity(), 1.0 / self.time_s);
        crate::ParticleState {
            id: s.id,
            position: s.position.map(|x| x * l),
            velocity: s.velocity.map(|x| x * v),
            angular_velocity: s.angular_velocity.map(|x| x * w),
            radius: s.radius * l,
        }
    }

    /// A reply in SI, converted to these units.
    pub fn reply_from_si(&self, r: &crate::ParticleReply) -> crate::ParticleReply {
        let (f, t) = (self.force(), self.torque());
        crate::ParticleReply {
            id: r.id,
            force: r.force.map(|x| x / f),
            torque: r.torque.map(|x| x / t),
        }
    }
}

/// What physics a side runs, as a bit set. Each physical effect must be applied by exactly one side.
pub struct Physics;

impl Physics {
    /// Gravity on the particles.
    pub const GRAVITY: u64 = 1 << 0;
    /// Buoyancy (the fluid's hydrostatic pressure) on the particles.
    pub const BUOYANCY: u64 = 1 << 1;
    /// Retired, reserved: the Stokes-drag stand-in fluid of the first milestone (F = -6 pi mu r v in
    /// a quiescent fluid). No side sends it now; the bit keeps its number and is never reused.
    pub const STOKES_DRAG_STANDIN: u64 = 1 << 2;
    /// Lattice-Boltzmann fluid.
    pub const LATTICE_BOLTZMANN: u64 = 1 << 3;
    /// Immersed moving boundary coupling (solid fraction, momentum exchange).
    pub const IMMERSED_BOUNDARY: u64 = 1 << 4;
    /// Particle-particle and particle-wall contacts.
    pub const CONTACTS: u64 = 1 << 5;
    /// Lubrication correction for sub-cell gaps.
    pub const LUBRICATION: u64 = 1 << 6;
    /// Stand-in DEM: free flight under the applied forces, elastic reflection at the domain faces.
    pub const BALLISTIC_STANDIN: u64 = 1 << 7;

    /// Effects that must not be applied twice.
    pub const EXCLUSIVE: u64 = Self::GRAVITY | Self::BUOYANCY | Self::LUBRICATION;

    pub fn names(bits: u64) -> Vec<&'static str> {
        const NAMES: [(u64, &str); 8] = [
            (Physics::GRAVITY, "gravity"),
            (Physics::BUOYANCY, "buoyancy"),
            (Physics::STOKES_DRAG_STANDIN, "stokes-drag-standin"),
            (Physics::LATTICE_BOLTZMANN, "lattice-boltzmann"),
            (Physics::IMMERSED_BOUNDARY, "immersed-boundary"),
            (Physics::CONTACTS, "contacts"),
            (Physics::LUBRICATION, "lubrication"),
            (Physics::BALLISTIC_STANDIN, "ballistic-standin"),
        ];
        NAMES
            .iter()
            .filter(|(bit, _)| bits & bit != 0)
            .map(|(_, name)| *name)
            .collect()
    }
}

/// DEM -> fluid, once, before step 0 (144 bytes in version 1).
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct Hello {
    pub magic: u32,
    pub version: u32,
    /// Size of this message in bytes.
    pub size: u32,
    pub kind: u32,
    /// Process id of the DEM side (used to detect its death or suspension).
    pub pid: u64,
    /// Sizes the DEM side uses for `ParticleState`, `ParticleReply` and `StepHeader`.
    pub state_size: u32,
    pub reply_size: u32,
    pub header_size: u32,
    /// [`Capabilities`] bits of the DEM side (version 1: reserved, 0).
    pub capabilities: u32,
    pub units: Units,
    /// [`Physics`] bits the DEM side applies.
    pub physics: u64,
    /// Number of particles in step 0.
    pub initial_count: u64,
    /// Name and version of the DEM software (NUL padded UTF-8).
    pub software: [u8; TEXT_LEN],
}

/// What a DEM side can do beyond the lockstep, as a bit set in [`Hello::capabilities`].
pub struct Capabilities;

impl Capabilities {
    /// It writes its whole state into the checkpoint folder when a reply carries
    /// `StepFlags::CHECKPOINT`, and goes on from such a state at `Welcome::first_step`
    /// (PROTOCOL.md 6.4).
    pub const CHECKPOINT: u32 = 1 << 0;
}

/// Outcome of the handshake, in [`Welcome::status`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u32)]
pub enum Status {
    Accepted = 0,
    VersionMismatch = 1,
    LayoutMismatch = 2,
    CapacityExceeded = 3,
    BadUnits = 4,
    PhysicsConflict = 5,
    CannotResume = 6,
}

impl Status {
    pub fn from_u32(v: u32) -> Option<Status> {
        [
            Status::Accepted,
            Status::VersionMismatch,
            Status::LayoutMismatch,
            Status::CapacityExceeded,
            Status::BadUnits,
            Status::PhysicsConflict,
            Status::CannotResume,
        ]
        .into_iter()
        .find(|s| *s as u32 == v)
    }
}

/// Fluid -> DEM, once, in answer to `Hello` (360 bytes in version 2, the first 344 in version 1).
/// Quantities in the DEM's units.
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct Welcome {
    pub magic: u32,
    pub version: u32,
    pub size: u32,
    pub kind: u32,
    /// Process id of the fluid side.
    pub pid: u64,
    /// A [`Status`]; anything but `Accepted` ends the run, `reason` says why.
    pub status: u32,
    /// The axes along which the domain is periodic: bit 0 x, bit 1 y, bit 2 z (0: none). A DEM
    /// wraps its spheres and pairs along them (PROTOCOL.md 6.2).
    pub periodic: u32,
    /// Most particles a step may carry.
    pub capacity: u64,
    /// Number of steps of the run (steps 0 .. steps-1).
    pub steps: u64,
    /// Fluid time step.
    pub dt: f64,
    pub domain_min: [f64; 3],
    pub domain_max: [f64; 3],
    pub gravity: [f64; 3],
    /// Fluid density (mass / length^3) and dynamic viscosity (mass / (length time)).
    pub fluid_density: f64,
    pub fluid_viscosity: f64,
    /// [`Physics`] bits the fluid side applies.
    pub physics: u64,
    pub software: [u8; TEXT_LEN],
    pub reason: [u8; TEXT_LEN * 2],
    /// Version 2: the run's first step (0, or the step of the checkpoint a resumed run goes on
    /// from; the run covers steps `first_step .. steps - 1`).
    pub first_step: u64,
    /// Version 2: the lattice's cell size (length), the lubrication cut-off (0: no lattice).
    pub cell_size: f64,
}

/// Why a handshake message could not be read.
#[derive(Debug, Clone, PartialEq)]
pub enum DecodeError {
    TooShort(usize),
    BadMagic(u32),
    WrongKind(u32),
    /// Versions differ: (ours, theirs).
    Version(u32, u32),
    /// Same version, different size: (ours, theirs).
    Size(usize, usize),
}

impl core::fmt::Display for DecodeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            DecodeError::TooShort(n) => write!(f, "handshake message of {n} bytes is too short"),
            DecodeError::BadMagic(m) => write!(f, "handshake magic {m:#010x} is not \"LBDM\""),
            DecodeError::WrongKind(k) => write!(f, "unexpected handshake message kind {k}"),
            DecodeError::Version(ours, theirs) => write!(
                f,
                "protocol version mismatch: this side speaks version {ours}, the peer speaks version {theirs}"
            ),
            DecodeError::Size(ours, theirs) => write!(
                f,
                "handshake layout mismatch: {ours} bytes here, {theirs} bytes from the peer"
            ),
        }
    }
}

/// Reads the version-independent prefix: (magic, version, size, kind).
pub fn read_prefix(bytes: &[u8]) -> Result<(u32, u32, u32, u32), DecodeError> {
    if bytes.len() < PREFIX_LEN {
        return Err(DecodeError::TooShort(bytes.len()));
    }
    let word = |i: usize| u32::from_le_bytes(bytes[4 * i..4 * i + 4].try_into().unwrap());
    Ok((word(0), word(1), word(2), word(3)))
}

/// Plain-old-data messages that travel as bytes: in version v, the first `size_in(v)` bytes of
/// the struct (a later version only appends fields).
pub trait Message: bytemuck::Pod {
    const KIND: u32;

    /// The message's size in `version`.
    fn size_in(version: u32) -> usize;

    /// The message's bytes, as many as its `size` field (its prefix's third word) says.
    fn to_bytes(&self) -> Vec<u8> {
        let all = bytemuck::bytes_of(self);
        let size = u32::from_le_bytes(all[8..12].try_into().unwrap()) as usize;
        all[..size.min(all.len())].to_vec()
    }

    /// Checks magic, kind, version (one this build speaks) and size, then copies the message out
    /// of `bytes` (fields of later versions zero).
    fn from_bytes(bytes: &[u8]) -> Result<Self, DecodeError> {
        let (magic, version, size, kind) = read_prefix(bytes)?;
        if magic != MAGIC {
            return Err(DecodeError::BadMagic(magic));
        }
        if !(OLDEST_VERSION..=PROTOCOL_VERSION).contains(&version) {
            return Err(DecodeError::Version(PROTOCOL_VERSION, version));
        }
        if kind != Self::KIND {
            return Err(DecodeError::WrongKind(kind));
        }
        let expected = Self::size_in(version);
        if size as usize != expected || bytes.len() < expected {
            return Err(DecodeError::Size(expected, size as usize));
        }
        let mut full = vec![0u8; size_of::<Self>()];
        full[..expected].copy_from_slice(&bytes[..expected]);
        Ok(bytemuck::pod_read_unaligned(&full))
    }
}

impl Message for Hello {
    const KIND: u32 = KIND_HELLO;

    /// 144 bytes in versions 1 and 2 (version 2 names the reserved word `capabilities`).
    fn size_in(_version: u32) -> usize {
        size_of::<Hello>()
    }
}

/// Bytes of a version-1 Welcome: up to `reason`'s end.
pub const WELCOME_V1_SIZE: usize = 344;

impl Message for Welcome {
    const KIND: u32 = KIND_WELCOME;

    fn size_in(version: u32) -> usize {
        if version == 1 {
            WELCOME_V1_SIZE
        } else {
            size_of::<Welcome>()
        }
    }
}

/// Encodes `text` as a NUL padded, truncated UTF-8 field.
pub fn text_field<const N: usize>(text: &str) -> [u8; N] {
    let mut out = [0u8; N];
    let mut end = text.len().min(N);
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    out[..end].copy_from_slice(&text.as_bytes()[..end]);
    out
}

/// Decodes a NUL padded UTF-8 field.
pub fn field_text(bytes: &[u8]) -> String {
    let end = bytes.iter().position(|b| *b == 0).unwrap_or(bytes.len());
    String::from_utf8_lossy(&bytes[..end]).into_owned()
}

impl Hello {
    pub fn new(units: Units, physics: u64, initial_count: usize, software: &str) -> Self {
        Self {
            magic: MAGIC,
            version: PROTOCOL_VERSION,
            size: size_of::<Hello>() as u32,
            kind: KIND_HELLO,
            pid: std::process::id() as u64,
            state_size: size_of::<crate::ParticleState>() as u32,
            reply_size: size_of::<crate::ParticleReply>() as u32,
            header_size: size_of::<crate::StepHeader>() as u32,
            capabilities: 0,
            units,
            physics,
            initial_count: initial_count as u64,
            software: text_field(software),
        }
    }

    /// True when the per-step message sizes agree with this build's.
    pub fn layout_matches(&self) -> bool {
        self.state_size as usize == size_of::<crate::ParticleState>()
            && self.reply_size as usize == size_of::<crate::ParticleReply>()
            && self.header_size as usize == size_of::<crate::StepHeader>()
    }
}

impl Welcome {
    /// An accepting welcome with the run's parameters left at zero, to be filled by the caller.
    pub fn accepted(software: &str) -> Self {
        Self {
            magic: MAGIC,
            version: PROTOCOL_VERSION,
            size: size_of::<Welcome>() as u32,
            kind: KIND_WELCOME,
            pid: std::process::id() as u64,
            status: Status::Accepted as u32,
            periodic: 0,
            capacity: 0,
            steps: 0,
            dt: 0.0,
            domain_min: [0.0; 3],
            domain_max: [0.0; 3],
            gravity: [0.0; 3],
            fluid_density: 0.0,
            fluid_viscosity: 0.0,
            physics: 0,
            software: text_field(software),
            reason: [0; TEXT_LEN * 2],
            first_step: 0,
            cell_size: 0.0,
        }
    }

    /// This Welcome as `version` sends it (a version-1 DEM gets the first 344 bytes).
    pub fn for_version(self, version: u32) -> Self {
        Self {
            version,
            size: Self::size_in(version) as u32,
            ..self
        }
    }

    pub fn refused(software: &str, status: Status, reason: &str) -> Self {
        Self {
            status: status as u32,
            reason: text_field(reason),
            ..Self::accepted(software)
        }
    }

    pub fn reason_text(&self) -> String {
        field_text(&self.reason)
    }

    /// The periodic axes (x, y, z) of [`Welcome::periodic`].
    pub fn periodic_axes(&self) -> [bool; 3] {
        std::array::from_fn(|a| self.periodic & (1 << a) != 0)
    }

    /// [`Welcome::periodic`] of the periodic axes (x, y, z).
    pub fn periodic_bits(axes: [bool; 3]) -> u32 {
        (0..3).filter(|&a| axes[a]).map(|a| 1 << a).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::mem::offset_of;

    #[test]
    fn hello_layout() {
        assert_eq!(size_of::<Hello>(), 144);
        assert_eq!(offset_of!(Hello, pid), 16);
        assert_eq!(offset_of!(Hello, state_size), 24);
        assert_eq!(offset_of!(Hello, capabilities), 36);
        assert_eq!(offset_of!(Hello, units), 40);
        assert_eq!(offset_of!(Hello, physics), 64);
        assert_eq!(offset_of!(Hello, initial_count), 72);
        assert_eq!(offset_of!(Hello, software), 80);
    }

    #[test]
    fn welcome_layout() {
        assert_eq!(size_of::<Welcome>(), 360);
        assert_eq!(offset_of!(Welcome, first_step), 344);
        assert_eq!(offset_of!(Welcome, cell_size), 352);
        assert_eq!(offset_of!(Welcome, status), 24);
        assert_eq!(offset_of!(Welcome, periodic), 28);
        assert_eq!(offset_of!(Welcome, capacity), 32);
        assert_eq!(offset_of!(Welcome, steps), 40);
        assert_eq!(offset_of!(Welcome, dt), 48);
        assert_eq!(offset_of!(Welcome, domain_min), 56);
        assert_eq!(offset_of!(Welcome, domain_max), 80);
        assert_eq!(offset_of!(Welcome, gravity), 104);
        assert_eq!(offset_of!(Welcome, fluid_density), 128);
        assert_eq!(offset_of!(Welcome, fluid_viscosity), 136);
        assert_eq!(offset_of!(Welcome, physics), 144);
        assert_eq!(offset_of!(Welcome, software), 152);
        assert_eq!(offset_of!(Welcome, reason), 216);
    }

    #[test]
    fn round_trip_and_version_refusal() {
        let hello = Hello::new(Units::SI, Physics::GRAVITY, 7, "test-dem 1.0");
        let bytes = hello.to_bytes();
        assert_eq!(Hello::from_bytes(&bytes), Ok(hello));
        let mut future = bytes.clone();
        future[4..8].copy_from_slice(&9u32.to_le_bytes());
        assert_eq!(
            Hello::from_bytes(&future),
            Err(DecodeError::Version(PROTOCOL_VERSION, 9))
        );
        assert_eq!(
            Welcome::from_bytes(&bytes),
            Err(DecodeError::WrongKind(KIND_HELLO))
        );
        assert_eq!(field_text(&hello.software), "test-dem 1.0");
    }

    /// A version-1 Welcome is the first 344 bytes, read back with the version-2 fields zero; a
    /// version-1 Hello is read as one with no capabilities.
    #[test]
    fn version_1_messages_are_read_and_written() {
        let mut welcome = Welcome::accepted("fluid");
        welcome.first_step = 40;
        welcome.cell_size = 1e-3;
        let v2 = welcome.to_bytes();
        assert_eq!(v2.len(), 360);
        assert_eq!(Welcome::from_bytes(&v2), Ok(welcome));
        let v1 = welcome.for_version(1).to_bytes();
        assert_eq!(v1.len(), WELCOME_V1_SIZE);
        let read = Welcome::from_bytes(&v1).unwrap();
        assert_eq!((read.version, read.first_step, read.cell_size), (1, 0, 0.0));
        assert_eq!(read.steps, welcome.steps);
        let mut hello = Hello::new(Units::SI, Physics::GRAVITY, 3, "old dem");
        hello.version = 1;
        let read = Hello::from_bytes(&hello.to_bytes()).unwrap();
        assert_eq!((read.version, read.capabilities), (1, 0));
    }

    #[test]
    fn units_convert_states_and_replies() {
        let mm_ms_g = Units {
            length_m: 1e-3,
            time_s: 1e-3,
            mass_kg: 1e-3,
        };
        let s = crate::ParticleState {
            id: 1,
            position: [2.0, 0.0, 0.0],
            velocity: [3.0, 0.0, 0.0],
            angular_velocity: [5.0, 0.0, 0.0],
            radius: 0.5,
        };
        let si = mm_ms_g.state_to_si(&s);
        assert_eq!(si.position[0], 2e-3);
        assert!((si.velocity[0] - 3.0).abs() < 1e-12, "mm/ms is m/s");
        assert!((si.angular_velocity[0] - 5e3).abs() < 1e-9);
        assert_eq!(si.radius, 5e-4);
        let r = crate::ParticleReply {
            id: 1,
            force: [1.0, 0.0, 0.0],
            torque: [1.0, 0.0, 0.0],
        };
        let back = mm_ms_g.reply_from_si(&r);
        // 1 g mm / ms^2 = 1 N, and 1 g mm^2 / ms^2 = 1e-3 N m
        assert!((back.force[0] - 1.0).abs() < 1e-12);
        assert!((back.torque[0] - 1e3).abs() < 1e-9);
    }

    #[test]
    fn text_is_truncated_on_a_char_boundary() {
        let field: [u8; 4] = text_field("abcé");
        assert_eq!(field_text(&field), "abc");
    }
}
