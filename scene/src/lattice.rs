//! The `[lattice]` section: how the fluid is discretised, and the one place where SI units become
//! lattice units (dx, dt, tau, lattice velocities and forces).

use crate::numbers::{fail, finite3, non_negative, positive, vec3};
use crate::{Scene, SceneError};
use serde::Deserialize;

mod conversions;
mod faces;
mod kernel;
mod operator;
mod storage;

pub use kernel::Kernel;
pub use operator::{mach_limit, CollisionOperator};
pub use storage::Storage;

/// `[lattice]` (SI units).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LatticeSection {
    /// Cell size [m]; give this or `resolution`.
    pub dx: Option<f64>,
    /// Cells along x; give this or `dx`.
    pub resolution: Option<u64>,
    /// Collision operator: "bgk", "trt" (default) or "mrt", as written ([`LatticeUnits::operator`]
    /// is the one parsed).
    #[serde(default = "default_operator")]
    pub operator: String,
    /// Relaxation time (above 1/2 + [`TAU_MARGIN`]); when given, it sets dt. Otherwise dt
    /// follows from `mach`.
    pub tau: Option<f64>,
    /// Characteristic (largest expected) fluid speed [m/s].
    pub velocity_scale: f64,
    /// Target Mach number of `velocity_scale` when `tau` is not given (default 0.1).
    #[serde(default = "default_mach")]
    pub mach: f64,
    /// TRT magic parameter Lambda (default 3/16).
    #[serde(default = "default_magic")]
    pub magic: f64,
    /// TRT: the largest antisymmetric relaxation time tau- (none by default). A fixed magic makes
    /// tau- = 1/2 + magic / (tau - 1/2) grow without bound as tau nears 1/2, where TRT blew up
    /// (validation/lbm/REPORT.md, "Stability near tau = 1/2"); with this set the magic becomes
    /// min(magic, (tau - 1/2)(max_tau_minus - 1/2)). 1 held where BGK held.
    pub max_tau_minus: Option<f64>,
    /// MRT relaxation rates of the non-hydrodynamic moments (d'Humieres 2002 defaults), each in
    /// (0, 2).
    #[serde(default)]
    pub mrt: MrtRates,
    /// Acceleration driving the fluid, e.g. a pressure gradient / density [m/s^2] (finite).
    #[serde(default)]
    pub body_acceleration: [f64; 3],
    /// Boundary type of each domain face.
    #[serde(default)]
    pub faces: Faces,
    /// Solid boxes (no-slip obstacles) [m]; one that makes no cell solid (outside the domain, or
    /// between the cell centres) is accepted with a warning.
    #[serde(default)]
    pub solid_box: Vec<SolidBox>,
    /// Steps between two health checks (non-finite values, density, speed).
    #[serde(default = "default_check_interval")]
    pub check_interval: u64,
    /// Time [s] over which the velocity inlets and moving walls rise from rest to their velocity,
    /// as (1 - cos(pi t / ramp_time)) / 2 (default 0: at full velocity from the first step). A
    /// start at full speed sends a pressure wave of the inlet's speed through the liquid, which a
    /// pressure outlet sends back; near tau = 1/2 it hardly decays (docs/lbm.md).
    #[serde(default)]
    pub ramp_time: f64,
    /// How the populations are stored on the device: "fp32" (default), "fp16s" (IEEE half) or
    /// "fp16c" (16 bits with one more mantissa bit for the small deviations); the arithmetic is
    /// f32 either way (docs/lbm.md, "Storage"); as written ([`LatticeUnits::storage`] is the one
    /// parsed).
    #[serde(default = "default_storage")]
    pub storage: String,
    /// The fluid kernels: "quads" (by cell class, four-cell quads: built for CPU drivers such as
    /// lavapipe), "cells" (a thread per cell: built for GPUs) or "auto" (default: the run times
    /// both on its first steps and keeps the faster; docs/lbm.md, "Kernels"). The same results
    /// bit for bit. As written ([`LatticeUnits::kernel`] is the one parsed).
    #[serde(default = "default_kernel")]
    pub kernel: String,
}

#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MrtRates {
    pub e: f64,
    pub epsilon: f64,
    pub q: f64,
    pub pi: f64,
    pub m: f64,
}

impl Default for MrtRates {
    fn default() -> Self {
        Self {
            e: 1.19,
            epsilon: 1.4,
            q: 1.2,
            pi: 1.4,
            m: 1.98,
        }
    }
}

/// Face types: "periodic", "wall", or a table {type = "moving_wall", velocity = [..]},
/// {type = "velocity_inlet", velocity = [..]}, {type = "pressure_outlet", pressure = Pa}.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Faces {
    #[serde(default = "wall")]
    pub x_min: FaceSpec,
    #[serde(default = "wall")]
    pub x_max: FaceSpec,
    #[serde(default = "wall")]
    pub y_min: FaceSpec,
    #[serde(default = "wall")]
    pub y_max: FaceSpec,
    #[serde(default = "wall")]
    pub z_min: FaceSpec,
    #[serde(default = "wall")]
    pub z_max: FaceSpec,
}

impl Default for Faces {
    fn default() -> Self {
        Self {
            x_min: wall(),
            x_max: wall(),
            y_min: wall(),
            y_max: wall(),
            z_min: wall(),
            z_max: wall(),
        }
    }
}

impl Faces {
    /// (name, spec) of the six faces in the order x_min, x_max, y_min, y_max, z_min, z_max.
    pub fn all(&self) -> [(&'static str, &FaceSpec); 6] {
        [
            ("x_min", &self.x_min),
            ("x_max", &self.x_max),
            ("y_min", &self.y_min),
            ("y_max", &self.y_max),
            ("z_min", &self.z_min),
            ("z_max", &self.z_max),
        ]
    }
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum FaceSpec {
    /// "periodic" or "wall".
    Name(String),
    Table(FaceTable),
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FaceTable {
    #[serde(rename = "type")]
    pub kind: String,
    /// [m/s] for moving walls and velocity inlets (finite, below the operator's Mach limit).
    pub velocity: Option<[f64; 3]>,
    /// Gauge pressure [Pa] for pressure outlets (finite, above -rho c_s^2, where the outlet's
    /// density would reach 0).
    pub pressure: Option<f64>,
}

fn wall() -> FaceSpec {
    FaceSpec::Name("wall".into())
}

/// A solid box [m]; cells whose centre lies inside are solid.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolidBox {
    pub min: [f64; 3],
    pub max: [f64; 3],
}

fn default_operator() -> String {
    "trt".into()
}
fn default_kernel() -> String {
    "auto".into()
}

fn default_storage() -> String {
    "fp32".into()
}
fn default_mach() -> f64 {
    0.1
}
fn default_magic() -> f64 {
    3.0 / 16.0
}
fn default_check_interval() -> u64 {
    100
}

/// A face in lattice units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LatticeFace {
    Periodic,
    Wall,
    MovingWall([f64; 3]),
    VelocityInlet([f64; 3]),
    PressureOutlet(f64),
}

/// The discretisation of a scene: everything the kernels need, in lattice units, and the scales
/// to convert back.
#[derive(Debug, Clone, PartialEq)]
pub struct LatticeUnits {
    pub n: [usize; 3],
    /// Cell size [m] and time step [s].
    pub dx: f64,
    pub dt: f64,
    pub tau: f64,
    /// Lattice viscosity (tau - 1/2) / 3.
    pub nu: f64,
    /// Mach number of the velocity scale: u_lattice / c_s.
    pub mach: f64,
    pub operator: CollisionOperator,
    /// TRT's magic parameter as used: `lattice.magic`, lowered by `lattice.max_tau_minus`.
    pub magic: f64,
    pub mrt: MrtRates,
    /// Body force density in lattice units.
    pub force: [f64; 3],
    pub faces: [LatticeFace; 6],
    /// Solid cells, x fastest.
    pub solid: Vec<bool>,
    pub check_interval: u64,
    /// Steps over which the face velocities rise from rest (`lattice.ramp_time` / dt).
    pub ramp_steps: f64,
    /// The populations' storage.
    pub storage: Storage,
    /// The fluid kernels `lattice.kernel` names; None for "auto" (the run's start-up trial
    /// chooses).
    pub kernel: Option<Kernel>,
}

/// Smallest tau - 1/2 accepted, for every operator. BGK was refused below 0.51 until BGK held a
/// sphere's wake to tau 0.5024 (validation/lbm/REPORT.md, "Stability near tau = 1/2"); near
/// there lbm-server warns with what was measured.
pub const TAU_MARGIN: f64 = 0.0005;

/// The time step [s] and tau of the lattice of cell size `dx`: from `lattice.tau` where given,
/// else from the Mach number of `lattice.velocity_scale`; refused where tau lies too near 1/2.
fn time_step(scene: &Scene, lattice: &LatticeSection, dx: f64, file: &str) -> Result<(f64, f64), SceneError> {
    let nu_si = scene.fluid.dynamic_viscosity / scene.fluid.density;
    positive(file, "lattice.velocity_scale", lattice.velocity_scale, "m/s")?;
    positive(file, "lattice.mach", lattice.mach, "")?;
    let dt = match lattice.tau {
        Some(tau) if !tau.is_finite() => {
            return Err(fail(
                file,
                "lattice.tau",
                tau,
                "must be a finite number above 1/2",
            ))
        }
        Some(tau) => (tau - 0.5) * dx * dx / (3.0 * nu_si),
        None => lattice.mach / 3f64.sqrt() * dx / lattice.velocity_scale,
    };
    let tau = 0.5 + 3.0 * nu_si * dt / (dx * dx);
    let field = if lattice.tau.is_some() {
        "lattice.tau"
    } else {
        "lattice (derived tau)"
    };
    if tau.is_nan() || tau - 0.5 < TAU_MARGIN {
        let remedy = if lattice.tau.is_some() {
            "raise lattice.tau"
        } else {
            "refine dx or raise lattice.mach (tau - 1/2 grows as mach / dx)"
        };
        return Err(fail(
            file,
            field,
            format!("{tau:.5}"),
            format!("is below 0.5 + {TAU_MARGIN}: unstable; {remedy}"),
        ));
    }
    Ok((dt, tau))
}

/// The lattice Mach number of `lattice.velocity_scale`, refused above operator `op`'s limit.
fn lattice_mach(
    lattice: &LatticeSection,
    op: CollisionOperator,
    dx: f64,
    dt: f64,
    file: &str,
) -> Result<f64, SceneError> {
    let mach = lattice.velocity_scale * dt / dx * 3f64.sqrt();
    if mach > mach_limit(op) {
        return Err(fail(
            file,
            "lattice.velocity_scale",
            format!("{} m/s", lattice.velocity_scale),
            format!(
                "gives lattice Mach {mach:.3}, above {} for {op}: lower tau or coarsen dx",
                mach_limit(op)
            ),
        ));
    }
    Ok(mach)
}

/// TRT's magic parameter at `tau`: `lattice.magic`, or less where `lattice.max_tau_minus` bounds
/// tau- = 1/2 + magic / (tau - 1/2).
fn trt_magic(
    lattice: &LatticeSection,
    op: CollisionOperator,
    tau: f64,
    file: &str,
) -> Result<f64, SceneError> {
    positive(file, "lattice.magic", lattice.magic, "")?;
    let Some(max) = lattice.max_tau_minus else {
        return Ok(lattice.magic);
    };
    if op != CollisionOperator::Trt {
        return Err(fail(
            file,
            "lattice.max_tau_minus",
            max,
            format!("applies to TRT only, not {:?}", op.name()),
        ));
    }
    if !(max.is_finite() && max > 0.5) {
        return Err(fail(
            file,
            "lattice.max_tau_minus",
            max,
            "must be a finite number above 1/2",
        ));
    }
    Ok(bounded_magic(lattice.magic, tau, max))
}

/// The TRT magic parameter at `tau` that keeps tau- = 1/2 + magic / (tau - 1/2) at most
/// `max_tau_minus`: min(magic, (tau - 1/2)(max_tau_minus - 1/2)).
pub fn bounded_magic(magic: f64, tau: f64, max_tau_minus: f64) -> f64 {
    magic.min((tau - 0.5) * (max_tau_minus - 0.5))
}

impl LatticeUnits {
    /// Derives and checks the lattice of `scene` (which has a `[lattice]` section); with it the
    /// warnings of what the lattice holds that does nothing (a solid box that makes no cell solid).
    pub fn derive(
        scene: &Scene,
        lattice: &LatticeSection,
        file: &str,
    ) -> Result<(LatticeUnits, Vec<String>), SceneError> {
        let dx = cell_size(scene, lattice, file)?;
        let n = cell_counts(scene, lattice, dx, file)?;
        let Some(op) = CollisionOperator::named(&lattice.operator) else {
            return Err(fail(
                file,
                "lattice.operator",
                format!("{:?}", lattice.operator),
                "expected \"bgk\", \"trt\" or \"mrt\"",
            ));
        };
        let Some(storage) = Storage::named(&lattice.storage) else {
            return Err(fail(
                file,
                "lattice.storage",
                format!("{:?}", lattice.storage),
                "expected \"fp32\", \"fp16s\" or \"fp16c\"",
            ));
        };
        let kernel = kernel_of(lattice, file)?;
        let (dt, tau) = time_step(scene, lattice, dx, file)?;
        let mach = lattice_mach(lattice, op, dx, dt, file)?;
        let faces = faces::lattice_faces(scene, lattice, op, [dx, dt], file)?;
        let (solid, warnings) = solid_cells(scene, lattice, n, dx, file)?;
        check_steps_rates_and_forces(lattice, file)?;
        let force = lattice.body_acceleration.map(|a| a * dt * dt / dx);
        let units = LatticeUnits {
            n,
            dx,
            dt,
            tau,
            nu: (tau - 0.5) / 3.0,
            mach,
            operator: op,
            magic: trt_magic(lattice, op, tau, file)?,
            mrt: lattice.mrt,
            force,
            faces,
            solid,
            check_interval: lattice.check_interval,
            ramp_steps: lattice.ramp_time / dt,
            storage,
            kernel,
        };
        Ok((units, warnings))
    }
}

/// `lattice.kernel`: the kernels it names, None for "auto".
fn kernel_of(lattice: &LatticeSection, file: &str) -> Result<Option<Kernel>, SceneError> {
    match lattice.kernel.as_str() {
        "auto" => Ok(None),
        name => Kernel::named(name).map(Some).ok_or_else(|| {
            fail(
                file,
                "lattice.kernel",
                format!("{name:?}"),
                "expected \"auto\", \"quads\" or \"cells\"",
            )
        }),
    }
}

/// `lattice.check_interval`, `lattice.ramp_time`, the MRT rates (in (0, 2): 2 would leave a
/// moment unrelaxed, beyond it grow) and `lattice.body_acceleration`.
fn check_steps_rates_and_forces(lattice: &LatticeSection, file: &str) -> Result<(), SceneError> {
    if lattice.check_interval == 0 {
        return Err(fail(file, "lattice.check_interval", 0, "must be at least 1 step"));
    }
    non_negative(file, "lattice.ramp_time", lattice.ramp_time, "s")?;
    let m = &lattice.mrt;
    let rates = [
        ("e", m.e),
        ("epsilon", m.epsilon),
        ("q", m.q),
        ("pi", m.pi),
        ("m", m.m),
    ];
    if let Some((name, rate)) = rates.iter().find(|(_, rate)| !(*rate > 0.0 && *rate < 2.0)) {
        return Err(fail(
            file,
            format!("lattice.mrt.{name}"),
            rate,
            "must lie in (0, 2) (a relaxation rate)",
        ));
    }
    finite3(
        file,
        "lattice.body_acceleration",
        lattice.body_acceleration,
        "m/s^2",
    )
}

fn cell_size(scene: &Scene, lattice: &LatticeSection, file: &str) -> Result<f64, SceneError> {
    let lx = scene.domain.max[0] - scene.domain.min[0];
    match (lattice.dx, lattice.resolution) {
        (Some(dx), None) => positive(file, "lattice.dx", dx, "m").map(|()| dx),
        (None, Some(r)) if r > 0 => Ok(lx / r as f64),
        (None, Some(r)) => Err(fail(file, "lattice.resolution", r, "must be at least 1 cell")),
        _ => Err(fail(
            file,
            "lattice",
            "dx and resolution",
            "give exactly one of lattice.dx or lattice.resolution",
        )),
    }
}

/// The cells along each axis of cell size `dx`, refused (naming `lattice.dx` or
/// `lattice.resolution`, whichever gave it) where one is not a whole number or all are 2^31 or more.
#[allow(clippy::needless_range_loop)]
fn cell_counts(
    scene: &Scene,
    lattice: &LatticeSection,
    dx: f64,
    file: &str,
) -> Result<[usize; 3], SceneError> {
    let (field, value) = match lattice.resolution {
        Some(r) => ("lattice.resolution", r.to_string()),
        None => ("lattice.dx", format!("{dx} m")),
    };
    let mut n = [0usize; 3];
    for a in 0..3 {
        let cells = (scene.domain.max[a] - scene.domain.min[a]) / dx;
        if (cells - cells.round()).abs() > 1e-6 * cells.max(1.0) || cells.round() < 1.0 {
            return Err(fail(
                file,
                field,
                &value,
                format!("the domain's extent along axis {a} is {cells:.4} cells: it must be a whole number"),
            ));
        }
        n[a] = cells.round() as usize;
    }
    let total = n
        .iter()
        .try_fold(1u128, |product, &v| product.checked_mul(v as u128));
    if total.is_none_or(|total| total >= 1 << 31) {
        return Err(fail(
            file,
            field,
            &value,
            format!("gives {} x {} x {} cells, above 2^31", n[0], n[1], n[2]),
        ));
    }
    Ok(n)
}

/// The solid cells of the solid boxes (those whose centre lies in one), and a warning for each
/// box that makes no cell solid.
fn solid_cells(
    scene: &Scene,
    lattice: &LatticeSection,
    n: [usize; 3],
    dx: f64,
    file: &str,
) -> Result<(Vec<bool>, Vec<String>), SceneError> {
    let mut solid = vec![false; n[0] * n[1] * n[2]];
    let mut warnings = Vec::new();
    for (b, boxed) in lattice.solid_box.iter().enumerate() {
        let field = format!("lattice.solid_box[{b}]");
        finite3(file, &format!("{field}.min"), boxed.min, "m")?;
        finite3(file, &format!("{field}.max"), boxed.max, "m")?;
        let value = format!("min {} m, max {} m", vec3(boxed.min), vec3(boxed.max));
        if let Some(a) = (0..3).find(|&a| boxed.max[a] <= boxed.min[a]) {
            return Err(fail(
                file,
                &field,
                value,
                format!("max must exceed min along axis {a}"),
            ));
        }
        let mut covered = 0usize;
        for (k, cell) in solid.iter_mut().enumerate() {
            let idx = [k % n[0], (k / n[0]) % n[1], k / (n[0] * n[1])];
            let centre: [f64; 3] = std::array::from_fn(|a| scene.domain.min[a] + (idx[a] as f64 + 0.5) * dx);
            if (0..3).all(|a| centre[a] >= boxed.min[a] && centre[a] <= boxed.max[a]) {
                *cell = true;
                covered += 1;
            }
        }
        if covered == 0 {
            let (lo, hi) = (scene.domain.min, scene.domain.max);
            let problem = if (0..3).any(|a| boxed.max[a] <= lo[a] || boxed.min[a] >= hi[a]) {
                format!(
                    "lies wholly outside the domain (min {} m, max {} m): it makes no cell solid",
                    vec3(lo),
                    vec3(hi)
                )
            } else {
                format!("holds no cell centre (cells of {dx} m): it makes no cell solid")
            };
            warnings.push(fail(file, &field, value, problem).to_string());
        }
    }
    Ok((solid, warnings))
}

#[cfg(test)]
mod tests;
