//! The `[coupling]` section: how the fluid and the particles exchange their loads, and how long
//! either side waits for the other.

use serde::Deserialize;

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Coupling {
    /// Longest wait for a peer that is alive, silent and idle (no CPU) [s]; one that works is
    /// waited for up to `protocol::transport::BUSY_FACTOR` (60) times as long.
    #[serde(default = "default_timeout")]
    pub timeout: f64,
    /// Most particles one step may carry (default: the initial count).
    pub capacity: Option<u64>,
    /// With a `[lattice]`: particles one cell can hold at once (1-4); a cell covered by more keeps
    /// those with the largest solid fractions (the same every run) and the run warns with the
    /// count dropped.
    #[serde(default = "default_slots")]
    pub slots: u32,
    /// With a `[lattice]`: solid weighting B, "noble-torczynski" (B(eps, tau)) or "seed" (B = eps).
    #[serde(default = "default_weighting")]
    pub weighting: String,
    /// With a `[lattice]`: the solid collision term, "noble-torczynski" (default: the seed's eq. 8,
    /// the non-equilibrium part bounced back) or "superposition" (the fluid's own collision with
    /// its equilibrium moved to the solid's velocity; docs/imb.md, "The solid collision").
    #[serde(default = "default_solid_collision")]
    pub solid_collision: String,
    /// With a `[lattice]`: lubrication correction for sphere-sphere and sphere-wall gaps below one
    /// cell (default on): integrated in the DEM's sub-steps by a DEM that declares LUBRICATION
    /// (dem-client does), else the fluid's held correction.
    #[serde(default = "default_lubrication")]
    pub lubrication: bool,
    /// With a `[lattice]`: within a fluid step the DEM lets the held fluid force and torque answer
    /// the velocity change the contacts cause, at the immersed boundary's own rate c = rho_f V / dt
    /// (docs/imb.md; default on; off: held constant).
    #[serde(default = "default_substep_drag")]
    pub substep_drag: bool,
    /// With a `[lattice]`: in each fluid step the spheres that can touch no sphere or wall, nor
    /// come within the squeeze films' cut-off, move in one exact step of their free motion, the
    /// others in the contacts' DEM sub-steps (docs/dem.md, "Free flight"; default on; off: every
    /// sphere in the contacts' sub-steps throughout).
    #[serde(default = "default_free_flight")]
    pub free_flight: bool,
    /// With a `[lattice]`: where the covered cells get their solid term (docs/imb.md, "Speed"):
    /// "fused" in the fluid kernels (each cell tests one bit), "redo" collided before them and
    /// stored over their result (the fluid kernels stay branch-free and run while the DEM takes
    /// its step), "skip" collided in place before them, which skip them (one bit per cell). All
    /// three give the same run bit for bit. "auto" (default): on a GPU the run times the three on
    /// its first steps and keeps the fastest (with `lattice.kernel`: lbm-server/src/trials.rs; in
    /// runs of a few hundred steps or more, the redo in shorter ones); on a CPU driver (lavapipe)
    /// it takes the redo and the quads' kernels. "timed": the trial on every device.
    #[serde(default = "default_covered_cells")]
    pub covered_cells: String,
    /// With a `[lattice]`: "none" (default) draws each sphere on the lattice at its radius;
    /// "calibrated" draws it larger by the immersed boundary's measured hydrodynamic radius
    /// deficit at the lattice's tau and operator (docs/imb.md, "Radius correction"; Noble-Torczynski
    /// weighting only). Buoyancy and the DEM keep the radius.
    #[serde(default = "default_radius_correction")]
    pub radius_correction: String,
}

fn default_radius_correction() -> String {
    "none".into()
}

fn default_lubrication() -> bool {
    true
}

fn default_substep_drag() -> bool {
    true
}

fn default_free_flight() -> bool {
    true
}

fn default_covered_cells() -> String {
    "auto".into()
}

fn default_slots() -> u32 {
    2
}

fn default_weighting() -> String {
    "noble-torczynski".into()
}

fn default_solid_collision() -> String {
    "noble-torczynski".into()
}

impl Default for Coupling {
    fn default() -> Self {
        Self {
            timeout: default_timeout(),
            capacity: None,
            slots: default_slots(),
            weighting: default_weighting(),
            solid_collision: default_solid_collision(),
            lubrication: default_lubrication(),
            substep_drag: default_substep_drag(),
            free_flight: default_free_flight(),
            covered_cells: default_covered_cells(),
            radius_correction: default_radius_correction(),
        }
    }
}

fn default_timeout() -> f64 {
    10.0
}
