//! The fluid side of a run with particles: the GPU lattice coupled to them by the immersed moving
//! boundary (a scene with particles must have a `[lattice]`; `run.rs` refuses one without).
//!
//! Gravity and buoyancy are each applied once: the DEM applies gravity to the particles; the fluid
//! has no gravity (so no hydrostatic pressure gradient) and this side adds the buoyancy
//! -rho_f V g to the hydrodynamic force computed on the lattice.
//!
//! A `lattice.body_acceleration` a drives the fluid like a mean pressure gradient -grad p = rho_f a
//! that the lattice does not carry either; the particles feel its share rho_f V a, added here too
//! (without it a fixed bed's drag is short by that share: the Zick-Homsy check in docs/imb.md).

use crate::fields::FieldOutput;
use crate::fluid::{health_of, setup_of, stability_warning};
use crate::lbm::gpu::{Gpu, Lattice, Unhealthy};
use crate::lbm::imb::{covered_fraction, CoveredCells, ImbOptions, Particles, SolidCollision, SolidParticle};
use crate::lubrication::Lubrication;
use crate::trials::{WayTrials, AUTO_MIN_SECONDS};
use protocol::{ParticleReply, ParticleState, Physics};
use scene::lattice::{LatticeFace, LatticeUnits};
use scene::Scene;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// What computes the particles' hydrodynamic loads: the lattice with its units, the buoyancy it
/// adds and the lubrication correction.
pub struct FluidSide {
    lattice: Lattice,
    units: LatticeUnits,
    origin: [f64; 3],
    fluid_density: f64,
    gravity: [f64; 3],
    lubrication: Option<Lubrication>,
    /// Each sphere of r cells is drawn r + this / max(r, 2) (`coupling.radius_correction`; 0
    /// without it).
    deficit_product: f64,
    steps: u64,
    /// With `coupling.covered_cells = "timed"`, and "auto" on a GPU: the ways timed on the run's
    /// steps (trials.rs).
    trials: Option<WayTrials>,
    /// When the fluid side was made: the trials' clock.
    made: std::time::Instant,
    /// The run's field outputs: those the scene asks for (`output.fields_interval` above 0,
    /// `output.line`), and last_good.vti where the fluid blows up.
    fields: FieldOutput,
    /// The step of the last health check that passed (its fields kept on the device).
    last_good: Option<u64>,
    /// `output.fields_interval` and `output.interval` (the probe lines'), in steps.
    fields_every: u64,
    lines_every: u64,
    /// Steps of the run (its last gets a snapshot and the lines).
    run_steps: u64,
}

/// The immersed boundary's drag error against tau, measured (validation/lbm/REPORT.md, "drag
/// against tau": the Zick-Homsy array at solid fraction 0.125, sphere radius 4.96 cells,
/// Noble-Torczynski weighting): (tau, [BGK, TRT, MRT] in %). TRT at 7.44 cells: about half.
const DRAG_AGAINST_TAU: [(f64, [f64; 3]); 7] = [
    (0.55, [1.9, -4.0, 2.4]),
    (0.6, [0.1, -5.1, 0.5]),
    (0.7, [-3.1, -6.7, -2.0]),
    (0.8, [-6.1, -8.2, -3.9]),
    (1.0, [-11.8, -10.7, -7.0]),
    (1.5, [-25.1, -16.1, -13.5]),
    (2.0, [-36.8, -20.7, -19.0]),
];

/// A measured drag error beyond this (in %) makes a coupled lattice warn.
const DRAG_ERROR_WARN: f64 = 8.0;

/// The immersed boundary's hydrodynamic radius deficit against tau, measured
/// (validation/lbm/REPORT.md, "hydrodynamic radius deficit against tau": the array of
/// [`DRAG_AGAINST_TAU`] drawn larger until its drag is Zick & Homsy's, nominal radius
/// [`deficit_radius`] cells): (tau, [BGK, TRT, MRT] in cells). At 7.44 cells TRT's deficit is
/// 0.56-0.66 of these: the deficit falls as 1 / radius (second-order convergence).
const RADIUS_DEFICIT: [(f64, [f64; 3]); 7] = [
    (0.55, [-0.029, 0.068, -0.036]),
    (0.6, [-0.001, 0.086, -0.008]),
    (0.7, [0.051, 0.116, 0.031]),
    (0.8, [0.102, 0.142, 0.063]),
    (1.0, [0.215, 0.192, 0.118]),
    (1.5, [0.566, 0.308, 0.247]),
    (2.0, [1.023, 0.423, 0.374]),
];

/// The nominal radius (cells) of [`RADIUS_DEFICIT`]: solid fraction 0.125 in a 16^3 box.
fn deficit_radius() -> f64 {
    (0.125 * 4096.0 * 3.0 / (4.0 * std::f64::consts::PI)).cbrt()
}

/// The smallest radius (cells) whose deficit the correction scales to (1 / radius).
const MIN_DEFICIT_RADIUS: f64 = 2.0;

/// Largest tau of the calibration per operator (BGK, TRT, MRT): BGK's deficit grows too fast
/// beyond tau 1 for the calibration's one secant step (drawn with it, the array's drag is 5.3%
/// high at tau 1.5 and 14.3% at 2; TRT and MRT within 1.8%).
const CALIBRATED_TAU: [f64; 3] = [1.0, 2.0, 2.0];

/// The column of `operator` in the measured tables (BGK, TRT, MRT).
fn operator_index(operator: &str) -> Option<usize> {
    ["bgk", "trt", "mrt"].iter().position(|o| *o == operator)
}

/// A measured table's value for `operator` at `tau`, interpolated linearly between the measured
/// taus (the first one's below them); None beyond the last measured tau.
fn measured_at(table: &[(f64, [f64; 3])], operator: &str, tau: f64) -> Option<f64> {
    let k = operator_index(operator)?;
    let (first, last) = (table[0], table[table.len() - 1]);
    if tau <= first.0 {
        return Some(first.1[k]);
    }
    if tau > last.0 {
        return None;
    }
    let upper = table.iter().position(|&(t, _)| t >= tau)?;
    let ((t0, e0), (t1, e1)) = (table[upper - 1], table[upper]);
    if t1 == tau {
        return Some(e1[k]);
    }
    Some(e0[k] + (e1[k] - e0[k]) * (tau - t0) / (t1 - t0))
}

/// The measured drag error of `operator` at `tau` ([`DRAG_AGAINST_TAU`], in %).
fn drag_error_at(operator: &str, tau: f64) -> Option<f64> {
    measured_at(&DRAG_AGAINST_TAU, operator, tau)
}

/// Stokes drag of spheres of a few cells, by diameter in cells (validation/lbm/REPORT.md,
/// "spheres of a few cells and less": a dilute array against Sangani & Acrivos; TRT moving
/// through the lattice, BGK and MRT at rest): (diameter, [BGK, TRT, MRT] x [tau 0.6, tau 1]) in %.
const SMALL_SPHERE_DRAG: [(f64, [[f64; 2]; 3]); 7] = [
    (0.5, [[-100.0, -100.0], [-100.1, -100.0], [-100.0, -100.0]]),
    (1.0, [[-100.0, -100.0], [-91.9, -94.1], [-100.0, -100.0]]),
    (1.5, [[-61.5, -72.3], [-63.8, -73.0], [-61.5, -71.3]]),
    (2.0, [[-41.0, -58.2], [-44.9, -57.1], [-40.9, -55.1]]),
    (3.0, [[-10.3, -33.2], [-22.4, -34.0], [-9.5, -26.4]]),
    (4.0, [[-10.5, -26.0], [-15.8, -22.2], [-10.2, -20.9]]),
    (6.0, [[-4.5, -16.6], [-9.5, -15.3], [-4.2, -11.7]]),
];

/// The spheres of [`SMALL_SPHERE_DRAG`] moving with TRT, drawn larger as
/// `coupling.radius_correction = "calibrated"` draws them (the same section of the report):
/// (diameter, [tau 0.6, tau 1]) in %.
const SMALL_SPHERE_DRAG_CALIBRATED: [(f64, [f64; 2]); 6] = [
    (1.0, [-51.8, -10.4]),
    (1.5, [-29.3, -0.3]),
    (2.0, [-14.9, 7.8]),
    (3.0, [-4.3, 10.4]),
    (4.0, [1.7, 12.7]),
    (6.0, [-0.7, 4.2]),
];

/// Cells per diameter from which the small spheres' drag is left to the tau warning.
const SMALL_SPHERE_RESOLVED: f64 = 6.0;

/// A table's values (tau 0.6, tau 1) at `d` cells per diameter, linear between its diameters and
/// its end rows' beyond them.
fn at_diameter(table: &[(f64, [f64; 2])], d: f64) -> [f64; 2] {
    let upper = table
        .iter()
        .position(|r| r.0 >= d)
        .unwrap_or(table.len() - 1)
        .max(1);
    let ((d0, e0), (d1, e1)) = (table[upper - 1], table[upper]);
    let w = ((d - d0) / (d1 - d0)).clamp(0.0, 1.0);
    std::array::from_fn(|t| e0[t] + (e1[t] - e0[t]) * w)
}

/// Where the smallest particles span fewer cells than the immersed boundary resolves: the drag
/// measured for their diameter (`diameter` in m), drawn at their radius or, with TRT and
/// `calibrated`, larger by the radius correction; warned of where it is off by more than
/// [`DRAG_ERROR_WARN`] at the measured tau nearer the lattice's.
fn small_sphere_warning(units: &LatticeUnits, diameter: f64, calibrated: bool) -> Option<String> {
    let k = operator_index(&units.operator)?;
    let cells = diameter / units.dx;
    if cells >= SMALL_SPHERE_RESOLVED {
        return None;
    }
    let plain: Vec<(f64, [f64; 2])> = SMALL_SPHERE_DRAG.iter().map(|&(d, e)| (d, e[k])).collect();
    let trt = units.operator == "trt";
    let corrected = at_diameter(&SMALL_SPHERE_DRAG_CALIBRATED, cells);
    let error = if calibrated && trt {
        corrected
    } else {
        at_diameter(&plain, cells)
    };
    if error[usize::from(units.tau > 0.8)].abs() <= DRAG_ERROR_WARN {
        return None;
    }
    let drawn = match (calibrated, trt) {
        (true, true) => ", drawn larger by coupling.radius_correction = \"calibrated\",",
        (true, false) => ", drawn at its radius (the correction is not measured at this size but with trt),",
        (false, _) => "",
    };
    let hint = if trt && !calibrated {
        format!(
            "; drawn larger by coupling.radius_correction = \"calibrated\": {:+.0}% and {:+.0}%",
            corrected[0], corrected[1]
        )
    } else {
        String::new()
    };
    Some(format!(
        "the smallest particles are {cells:.1} cells across (diameter {diameter:e} m / lattice.dx): \
         the immersed boundary under-resolves spheres of a few cells: in Stokes flow a sphere of this \
         size{drawn} measured {:+.0}% at tau 0.6 and {:+.0}% at tau 1 ({}; this lattice's tau \
         {:.3}){hint}; at a cell or less one that sits on a cell corner covers no cell's centre and \
         feels no drag (validation/lbm/REPORT.md, \"spheres of a few cells and less\"). A particle \
         with too little drag settles too fast, with too much too slowly. Refine lattice.dx to \
         {:.3e} m ({SMALL_SPHERE_RESOLVED} cells per diameter) or less",
        error[0],
        error[1],
        units.operator,
        units.tau,
        diameter / SMALL_SPHERE_RESOLVED,
    ))
}

/// `coupling.radius_correction` as the product deficit x radius (cells^2): a sphere of r cells is
/// drawn r + product / max(r, 2). 0 for "none"; for "calibrated" the measured deficit at the lattice's
/// tau times its radius (refused beyond the operator's calibrated taus).
fn radius_deficit_product(correction: &str, operator: &str, tau: f64) -> Result<f64, String> {
    if correction != "calibrated" {
        return Ok(0.0);
    }
    let k = operator_index(operator);
    let limit = k.map_or(0.0, |k| CALIBRATED_TAU[k]);
    match measured_at(&RADIUS_DEFICIT, operator, tau) {
        Some(deficit) if tau <= limit => Ok(deficit * deficit_radius()),
        _ => Err(format!(
            "coupling.radius_correction = \"calibrated\": lattice tau = {tau:.3} is beyond the \
             calibrated taus of {operator} (up to {limit}; validation/lbm/REPORT.md, \"hydrodynamic \
             radius deficit against tau\"): lower lattice.mach (or raise lattice.velocity_scale) or set \
             lattice.tau"
        )),
    }
}

/// How much larger (cells) a sphere of `radius` cells is drawn for the deficit product
/// `product` (cells^2, [`radius_deficit_product`]); below [`MIN_DEFICIT_RADIUS`], where nothing
/// was measured, the deficit of that radius.
fn drawn_larger_by(product: f64, radius: f64) -> f64 {
    if product == 0.0 {
        return 0.0;
    }
    product / radius.max(MIN_DEFICIT_RADIUS)
}

/// How much larger (cells) `coupling.radius_correction = "calibrated"` draws a sphere of
/// `radius` cells on a lattice of `operator` at `tau`.
pub(crate) fn calibrated_drawn_larger(operator: &str, tau: f64, radius: f64) -> Result<f64, String> {
    Ok(drawn_larger_by(
        radius_deficit_product("calibrated", operator, tau)?,
        radius,
    ))
}

/// The warning for a coupled lattice whose tau makes the immersed boundary's drag measurably
/// low (more than [`DRAG_ERROR_WARN`] at 5 cells radius, or beyond the measured taus), if it does.
fn tau_warning(operator: &str, tau: f64) -> Option<String> {
    let error = drag_error_at(operator, tau);
    if error.is_some_and(|e| e.abs() <= DRAG_ERROR_WARN) {
        return None;
    }
    let k = operator_index(operator)?;
    let (best_tau, best) = DRAG_AGAINST_TAU
        .iter()
        .map(|&(t, e)| (t, e[k]))
        .min_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))?;
    let measured = match error {
        Some(e) => format!("{e:+.1}% at this tau"),
        None => format!(
            "beyond the measured taus ({:+.1}% at tau {})",
            DRAG_AGAINST_TAU[DRAG_AGAINST_TAU.len() - 1].1[k],
            DRAG_AGAINST_TAU[DRAG_AGAINST_TAU.len() - 1].0
        ),
    };
    Some(format!(
        "lattice tau = {tau:.3} ({operator}): the immersed boundary's drag falls as tau grows: a sphere \
         of 5 cells radius in the Zick-Homsy array measured {measured}, about half of it at 7.4 cells \
         (validation/lbm/REPORT.md, \"drag against tau\"); a settling sphere falls about that much too \
         fast. Lower lattice.mach (or raise lattice.velocity_scale) or set lattice.tau: {operator} at tau \
         {best_tau} measured {best:+.1}%; or coupling.radius_correction = \"calibrated\" (docs/imb.md)"
    ))
}

/// The boundary-layer cells (cells per diameter / sqrt(particle Reynolds number)) below which a
/// moving sphere with TRT has less of the deficit the calibrated correction draws away than a
/// sphere at rest (validation/lbm/REPORT.md, "the sphere at rest and moving": towed against
/// held at 6 cells per diameter, +6.4% at 1.06 cells, +0.6 to +0.9% at 1.90).
const CORRECTION_BOUNDARY_LAYER_CELLS: f64 = 2.0;

/// The warning for a calibrated radius correction where a moving sphere's boundary layer is
/// resolved by fewer than [`CORRECTION_BOUNDARY_LAYER_CELLS`] cells with TRT: the particle
/// Reynolds number of the lattice's velocity scale and the largest sphere (`diameter`, m).
fn correction_warning(units: &LatticeUnits, diameter: f64) -> Option<String> {
    let (reynolds, cells, layer) = boundary_layer(units, diameter);
    (units.operator == "trt" && layer < CORRECTION_BOUNDARY_LAYER_CELLS).then(|| {
        format!(
            "coupling.radius_correction = \"calibrated\" with TRT at particle Reynolds number \
             {reynolds:.1} (lattice.velocity_scale x the largest diameter / viscosity) and {cells:.1} \
             cells per diameter: the sphere's boundary layer (about d / sqrt(Re)) spans {layer:.2} \
             cells. Below {CORRECTION_BOUNDARY_LAYER_CELLS} cells a moving sphere lacks much of the \
             deficit that a sphere at rest has and the correction draws away: towed through fluid at \
             rest it had +6.4% more drag than held in a stream at 1.06 cells (Re 32, 6 cells per \
             diameter), +0.6 to +0.9% at 1.90 (validation/lbm/REPORT.md, \"the sphere at rest and \
             moving\"), and Ten Cate E4 (Re 32) settled -7.0% off corrected against -3.5% at its \
             radius. For moving spheres compare with coupling.radius_correction = \"none\", refine \
             to {:.0} cells per diameter, or use lattice.operator = \"bgk\" or \"mrt\" (held and \
             towed within 2%; E4 at 6 cells settled -2.6% corrected with BGK, -2.2% with MRT)",
            (CORRECTION_BOUNDARY_LAYER_CELLS * reynolds.sqrt()).ceil()
        )
    })
}

/// The boundary-layer cells below which the immersed boundary's drag was measured well above the
/// drag laws at the Reynolds numbers of fluidized beds (validation/lbm/REPORT.md, "a held sphere
/// at the fluidized bed's Reynolds numbers": +5.7 to +6.5% at 0.92-1.13 cells, +25 to +29% at
/// 0.35-0.42).
const DRAG_BOUNDARY_LAYER_CELLS: f64 = 1.0;

/// The particle Reynolds number of the lattice's velocity scale and a sphere of `diameter` (m),
/// with its cells per diameter and boundary-layer cells (d / sqrt(Re), in cells).
fn boundary_layer(units: &LatticeUnits, diameter: f64) -> (f64, f64, f64) {
    let speed = units.mach / 3f64.sqrt();
    let cells = diameter / units.dx;
    let reynolds = speed * cells / units.nu;
    (reynolds, cells, cells / reynolds.sqrt())
}

/// The warning for spheres whose boundary layer spans fewer than [`DRAG_BOUNDARY_LAYER_CELLS`]
/// cells at the particle Reynolds number of the lattice's velocity scale and the largest sphere
/// (`diameter`, m): their drag comes out too high on such a grid, whatever the operator or tau.
fn resolution_warning(units: &LatticeUnits, diameter: f64) -> Option<String> {
    let (reynolds, cells, layer) = boundary_layer(units, diameter);
    (layer < DRAG_BOUNDARY_LAYER_CELLS).then(|| {
        format!(
            "particle Reynolds number {reynolds:.0} (lattice.velocity_scale x the largest diameter / \
             viscosity) at {cells:.1} cells per diameter: the sphere's boundary layer (about d / \
             sqrt(Re)) spans {layer:.2} cells, and the drag comes out too high. A sphere held in a \
             stream at Re 200-300 (MRT) dragged +25 to +29% above Schiller & Naumann at 0.35-0.42 \
             cells, +12% at 0.69-0.85 and +6% at 0.92-1.13, whatever the tau, Mach number or \
             operator; a random array at solid fraction 0.24 carried its weight at 1.5-1.7 times \
             Tenneti et al.'s drag at 6 to 18 cells per diameter, and solid cells instead of the \
             immersed boundary drag more still (validation/lbm/REPORT.md; docs/imb.md, \
             \"Stability near tau = 1/2\"). Refine to {:.0} cells per diameter for one cell",
            (DRAG_BOUNDARY_LAYER_CELLS * reynolds.sqrt()).ceil()
        )
    })
}

/// The scene's `coupling.covered_cells`, "auto" and "timed" made definite for the scene's initial
/// particles (their covered fraction of the lattice; `radii` in m): the way the run starts with.
fn covered_cells(scene: &Scene, units: &LatticeUnits, radii: &[f64]) -> Result<CoveredCells, String> {
    let name = match scene.coupling.covered_cells.as_str() {
        "timed" => "auto",
        name => name,
    };
    let mode = CoveredCells::from_name(name).ok_or_else(|| {
        format!(
            "coupling.covered_cells = {:?}: expected \"auto\", \"timed\", \"fused\", \"redo\" or \"skip\"",
            scene.coupling.covered_cells
        )
    })?;
    let radii = radii.iter().map(|r| r / units.dx);
    let cells = units.n.iter().product();
    Ok(mode.for_scene(covered_fraction(radii, cells)))
}

/// Whether the run times its ways of treating the covered cells (trials.rs), and how long the
/// steps left must take for a trial to start: "timed" on every device, always; "auto" on all but
/// CPU drivers, where building the other two ways' kernels costs more than a short run gains
/// (lavapipe, 2 cores: about 1 s each, against a default scene of 4.5 s) and
/// `CoveredCells::for_scene`'s rule was measured, and only with [`AUTO_MIN_SECONDS`] ahead.
fn way_trials(scene: &Scene, gpu: &Gpu) -> Option<f64> {
    match scene.coupling.covered_cells.as_str() {
        "timed" => Some(0.0),
        "auto" if gpu.adapter.device_type != wgpu::DeviceType::Cpu => Some(AUTO_MIN_SECONDS),
        _ => None,
    }
}

impl FluidSide {
    /// The fluid a scene asks for, for a run of `steps` steps writing its field outputs into `out`.
    pub fn for_scene(scene: &Scene, steps: u64, out: &Path) -> Result<FluidSide, String> {
        let Some(units) = scene.lattice_units.clone() else {
            return Err(format!(
                "scene '{}' has particles but no [lattice]: the fluid needs one",
                scene.name
            ));
        };
        // The scene's coupling settings are checked before the device is opened.
        let deficit_product =
            radius_deficit_product(&scene.coupling.radius_correction, &units.operator, units.tau)?;
        let gpu = Arc::new(Gpu::new()?);
        let radii: Vec<f64> = scene.initial_particles().iter().map(|p| p.radius).collect();
        let options = ImbOptions {
            slots: scene.coupling.slots,
            seed_weighting: scene.coupling.weighting == "seed",
            solid_collision: SolidCollision::from_name(&scene.coupling.solid_collision).ok_or_else(|| {
                format!(
                    "coupling.solid_collision = {:?}: expected \"noble-torczynski\" or \"superposition\"",
                    scene.coupling.solid_collision
                )
            })?,
            covered_cells: covered_cells(scene, &units, &radii)?,
        };
        let trials = way_trials(scene, &gpu).map(|least| WayTrials::new(options.covered_cells, steps, least));
        let lattice = Lattice::new(gpu, setup_of(&units), health_of(&units), Some(options))?;
        let lubrication = scene.coupling.lubrication.then(|| lubrication_of(scene, &units));
        let diameter = 2.0 * radii.iter().fold(0.0, |a, &r| r.max(a));
        let smallest = 2.0 * radii.iter().fold(f64::INFINITY, |a, &r| r.min(a));
        let warning = if scene.coupling.radius_correction == "none" {
            tau_warning(&units.operator, units.tau)
        } else {
            correction_warning(&units, diameter)
        };
        let warnings = [
            warning,
            resolution_warning(&units, diameter),
            small_sphere_warning(&units, smallest, scene.coupling.radius_correction == "calibrated"),
            stability_warning(&units, true),
        ];
        for warning in warnings.into_iter().flatten() {
            protocol::say!("lbm-server: warning: {warning}");
        }
        let fields = FieldOutput::new(scene, &units, out)?;
        Ok(FluidSide {
            lattice,
            units,
            origin: scene.domain.min,
            fluid_density: scene.fluid.density,
            gravity: scene.gravity,
            lubrication,
            deficit_product,
            steps: 0,
            trials,
            made: std::time::Instant::now(),
            fields,
            last_good: None,
            fields_every: scene.output.fields_interval,
            lines_every: scene.output.interval,
            run_steps: steps,
        })
    }

    /// The Physics bits this side applies.
    pub fn physics(&self) -> u64 {
        let lubrication = if self.lubrication.is_some() {
            Physics::LUBRICATION
        } else {
            0
        };
        Physics::LATTICE_BOLTZMANN | Physics::IMMERSED_BOUNDARY | Physics::BUOYANCY | lubrication
    }

    /// Leaves the lubrication correction to the DEM (which declared it in its Hello).
    pub fn leave_lubrication(&mut self) {
        self.lubrication = None;
    }

    /// How the fluid is described in logs.
    pub fn describe(&self) -> String {
        let u = &self.units;
        format!(
            "lattice {}x{}x{} ({}, tau {:.4}, dx {:e} m, dt {:e} s) on {}, immersed moving boundary \
             ({}{}){}{}",
            u.n[0],
            u.n[1],
            u.n[2],
            u.operator,
            u.tau,
            u.dx,
            u.dt,
            self.lattice.adapter(),
            self.lattice.covered_cells().describe(),
            self.trials
                .as_ref()
                .map_or(String::new(), |t| format!("; {}", t.describe())),
            if self.lubrication.is_some() {
                ", lubrication"
            } else {
                ""
            },
            if self.deficit_product != 0.0 {
                format!(
                    ", spheres drawn larger by {:.3} cells^2 / radius (radius correction)",
                    self.deficit_product
                )
            } else {
                String::new()
            }
        )
    }

    /// The way the covered cells take their solid term (when timed: the one the last trial kept),
    /// for summary.json.
    pub fn covered_cells(&self) -> CoveredCells {
        self.trials
            .as_ref()
            .map_or(self.lattice.covered_cells(), WayTrials::kept)
    }

    /// The lattice, for summary.json.
    pub fn units(&self) -> &LatticeUnits {
        &self.units
    }

    /// Advances the fluid one step with the particles `states` (SI) and returns their loads (SI).
    pub fn step(&mut self, states: &[ParticleState], out: &mut Vec<ParticleReply>) -> Result<(), String> {
        let (dx, dt) = (self.units.dx, self.units.dt);
        let lattice_states = LatticeStates {
            states,
            origin: self.origin,
            dx,
            dt,
            deficit_product: self.deficit_product,
        };
        let force_unit = self.fluid_density * dx.powi(4) / (dt * dt);
        let torque_unit = force_unit * dx;
        // What the lattice does not carry: the hydrostatic gradient (buoyancy) and the mean
        // pressure gradient that the body acceleration stands for, as -grad p / rho_f.
        let pressure_acceleration: [f64; 3] =
            std::array::from_fn(|a| self.units.force[a] * dx / (dt * dt) - self.gravity[a]);
        let fluid_density = self.fluid_density;
        self.take_way();
        // Set where a load is not finite, by the pass that converts the loads (no pass of its own).
        let not_finite = AtomicBool::new(false);
        self.lattice.step_coupled_with(&lattice_states, out, |j, l| {
            let s = &states[j];
            let volume = 4.0 / 3.0 * std::f64::consts::PI * s.radius.powi(3);
            let reply = ParticleReply {
                id: s.id,
                force: std::array::from_fn(|a| {
                    l.force[a] * force_unit + fluid_density * volume * pressure_acceleration[a]
                }),
                torque: l.torque.map(|t| t * torque_unit),
            };
            if !finite_load(&reply) {
                not_finite.store(true, Ordering::Relaxed);
            }
            reply
        })?;
        if let Some(lubrication) = &self.lubrication {
            lubrication.apply(states, out);
        }
        self.steps += 1;
        if not_finite.into_inner() {
            let reply = *out.iter().find(|r| !finite_load(r)).expect("a load not finite");
            return Err(self.not_finite(&reply));
        }
        if self.steps.is_multiple_of(self.units.check_interval) {
            self.check()?;
        }
        self.write_fields()
    }

    /// The field outputs due after this step: a snapshot every `output.fields_interval` steps
    /// (where it is above 0) and after the run's last step, the probe lines every
    /// `output.interval` steps and after the last (fields/, fields.pvd, line<N>.csv).
    fn write_fields(&mut self) -> Result<(), String> {
        let (step, last) = (self.steps, self.steps == self.run_steps);
        let due = |every: u64| every > 0 && (step.is_multiple_of(every) || last);
        self.write_outputs(due(self.fields_every), due(self.lines_every), last)
    }

    /// Where a run ends before its last step (Ctrl-C, the DEM's STOP): the field outputs a last
    /// step gets, less those this step wrote already.
    pub fn write_fields_of_early_end(&mut self) -> Result<(), String> {
        let step = self.steps;
        let left = |every: u64| every > 0 && !step.is_multiple_of(every);
        self.write_outputs(left(self.fields_every), left(self.lines_every), true)
    }

    /// Writes a snapshot and the probe lines (where the scene has any) of this step; `last`
    /// flushes the lines.
    fn write_outputs(&mut self, snapshot: bool, lines: bool, last: bool) -> Result<(), String> {
        let lines = lines && self.fields.has_lines();
        if snapshot || lines {
            let (fields, bad) = self.lattice.fields();
            if let Some(bad) = bad {
                return Err(self.unstable(bad));
            }
            if lines {
                self.fields.write_lines(self.steps, &fields)?;
            }
            if snapshot {
                self.fields.write_snapshot(self.steps, &fields)?;
            }
        }
        if last {
            self.fields.flush()?;
        }
        Ok(())
    }

    /// When the run times its ways: the one this step takes (and the last trial's line in the
    /// log); a way the device does not build is left out of the trials (this step keeps the
    /// lattice's way).
    fn take_way(&mut self) {
        let Some(trials) = &mut self.trials else {
            return;
        };
        let way = trials.way_for(self.steps, self.made.elapsed().as_secs_f64());
        if let Some(report) = trials.take_report() {
            protocol::say!("lbm-server: {report}");
        }
        if let Err(e) = self.lattice.set_covered_cells(way) {
            protocol::say!("lbm-server: warning: {e}; the run times the other ways without it");
            trials.refuse(way);
        }
    }

    /// After the run's last step: the health check and the covers' warning, unless the last step
    /// was a check already (a run shorter than `lattice.check_interval`, or its tail beyond the
    /// last multiple, went unchecked).
    pub fn check_last_step(&mut self) -> Result<(), String> {
        if self.steps.is_multiple_of(self.units.check_interval) {
            return Ok(());
        }
        self.check()
    }

    /// The health check of the lattice (a pass keeps its fields on the device for
    /// last_good.vti), and a warning when cells had more particles than slots.
    fn check(&mut self) -> Result<(), String> {
        if let Some(bad) = self.lattice.health() {
            return Err(self.unstable(bad));
        }
        self.lattice.keep_fields();
        self.last_good = Some(self.steps);
        let lost = self.lattice.lost_covers();
        let (unlisted, dropped) = (lost.unlisted, lost.dropped);
        if unlisted > 0 {
            return Err(format!(
                "by step {}, {unlisted} covered cells did not fit the list of covered cells (room for {} \
                 on this device: its storage binding limit / 80 bytes), so their solid term was missing: \
                 use fewer or smaller particles, or a device with a larger binding limit",
                self.steps,
                self.lattice.covered_cell_capacity()
            ));
        }
        if dropped > 0 {
            protocol::say!(
                "lbm-server: warning: by step {}, {dropped} particle-cell covers did not fit coupling.slots = {}",
                self.steps,
                self.lattice.slots()
            );
        }
        Ok(())
    }

    /// The error of a blow-up found at this step: the step, the cell and its quantities, and
    /// the fields of the last check that passed written as last_good.vti.
    fn unstable(&mut self, bad: Unhealthy) -> String {
        let what = bad.describe(&health_of(&self.units));
        let mut msg = format!("the fluid became unstable by step {}: {what}", self.steps);
        if let Some((good, fields)) = self.last_good.take().zip(self.lattice.kept_fields()) {
            msg += &self.fields.write_last_good(good, &fields);
        }
        let _ = self.fields.flush();
        msg
    }

    /// The fluid's blow-up, where the health check finds one now (run when the particles' states
    /// went wrong: the fluid's forces may be why).
    pub fn unstable_now(&mut self) -> Option<String> {
        let bad = self.lattice.health()?;
        Some(self.unstable(bad))
    }

    /// The error where a particle's load is not a finite number: the fluid's blow-up where the
    /// health check finds one now (before a NaN reaches the DEM, which would otherwise be
    /// blamed for the state it integrates from it), else the particle and its load.
    fn not_finite(&mut self, reply: &ParticleReply) -> String {
        if let Some(cause) = self.unstable_now() {
            return cause;
        }
        format!(
            "the fluid's load on particle id {} at step {} is not finite (force {:?} N, torque {:?} N m), \
             though the fluid passed its health check",
            reply.id, self.steps, reply.force, reply.torque
        )
    }
}

/// Whether a particle's force and torque are finite numbers.
fn finite_load(reply: &ParticleReply) -> bool {
    reply.force.iter().chain(&reply.torque).all(|v| v.is_finite())
}

/// Lubrication with the lattice's cut-off (one cell) and the domain faces that are walls.
fn lubrication_of(scene: &Scene, units: &LatticeUnits) -> Lubrication {
    let walls = units
        .faces
        .iter()
        .enumerate()
        .filter(|(_, f)| matches!(f, LatticeFace::Wall | LatticeFace::MovingWall(_)))
        .map(|(k, _)| {
            let axis = k / 2;
            if k % 2 == 0 {
                (axis, scene.domain.min[axis], 1.0)
            } else {
                (axis, scene.domain.max[axis], -1.0)
            }
        })
        .collect();
    Lubrication {
        viscosity: scene.fluid.dynamic_viscosity,
        cutoff: units.dx,
        walls,
        periods: std::array::from_fn(|axis| {
            if units.faces[2 * axis] == LatticeFace::Periodic {
                scene.domain.max[axis] - scene.domain.min[axis]
            } else {
                0.0
            }
        }),
        density: scene.particles.density,
        dt: units.dt,
    }
}

/// The DEM's states (SI) as the lattice reads them: each converted to lattice units where the
/// coupled step reads it.
struct LatticeStates<'a> {
    states: &'a [ParticleState],
    origin: [f64; 3],
    dx: f64,
    dt: f64,
    /// Each radius of r cells is drawn r + this / max(r, 2) (`coupling.radius_correction`).
    deficit_product: f64,
}

impl LatticeStates<'_> {
    /// The radius particle j is drawn with (cells): below 2 cells, where nothing was measured,
    /// the deficit of 2 cells.
    fn drawn_radius(&self, j: usize) -> f64 {
        let r = self.states[j].radius / self.dx;
        r + drawn_larger_by(self.deficit_product, r)
    }
}

impl Particles for LatticeStates<'_> {
    fn count(&self) -> usize {
        self.states.len()
    }

    fn particle(&self, j: usize) -> SolidParticle {
        let (s, dx) = (&self.states[j], self.dx);
        SolidParticle {
            position: std::array::from_fn(|a| (s.position[a] - self.origin[a]) / dx),
            radius: self.drawn_radius(j),
            velocity: s.velocity.map(|v| v * self.dt / dx),
            angular_velocity: s.angular_velocity.map(|w| w * self.dt),
        }
    }

    fn radius(&self, j: usize) -> f64 {
        self.drawn_radius(j)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_drag_error_is_the_measured_one_between_the_measured_taus() {
        assert_eq!(drag_error_at("trt", 1.0), Some(-10.7));
        assert_eq!(
            drag_error_at("bgk", 0.3),
            Some(1.9),
            "below the table: its first row"
        );
        let mid = drag_error_at("mrt", 1.25).unwrap();
        assert!((mid - (-7.0 - 13.5) / 2.0).abs() < 1e-12, "{mid}");
        assert_eq!(drag_error_at("trt", 2.5), None, "beyond the table");
        assert_eq!(drag_error_at("lbgk", 1.0), None);
    }

    /// The rows of the 16^3 box in a section of validation/lbm/REPORT.md: (tau, operator, the
    /// number in column `column` without its % sign).
    fn report_rows(heading: &str, column: usize) -> Vec<(f64, String, f64)> {
        let section = crate::validate::report_section(heading);
        let rows = section.lines().filter(|l| l.starts_with("| 16 |")).map(|line| {
            let cells: Vec<&str> = line.split('|').map(str::trim).collect();
            let number = cells[column].trim_end_matches('%').parse().unwrap();
            (cells[3].parse().unwrap(), cells[4].to_string(), number)
        });
        rows.collect()
    }

    #[test]
    fn the_drag_table_is_the_reports() {
        let rows = report_rows("## Immersed moving boundary: drag against tau", 8);
        for (tau, op, error) in &rows {
            assert_eq!(drag_error_at(op, *tau), Some(*error), "{op} at tau {tau}");
        }
        assert_eq!(rows.len(), 3 * DRAG_AGAINST_TAU.len());
    }

    #[test]
    fn the_radius_deficit_table_is_the_reports() {
        let heading = "## Immersed moving boundary: hydrodynamic radius deficit against tau";
        let rows = report_rows(heading, 7);
        for (tau, op, delta) in &rows {
            assert_eq!(
                measured_at(&RADIUS_DEFICIT, op, *tau),
                Some(*delta),
                "{op} at tau {tau}"
            );
        }
        assert_eq!(rows.len(), 3 * RADIUS_DEFICIT.len());
    }

    #[test]
    fn the_calibrated_correction_draws_the_measured_deficit() {
        let product = |op, tau| radius_deficit_product("calibrated", op, tau);
        assert_eq!(radius_deficit_product("none", "trt", 1.7), Ok(0.0));
        let trt = product("trt", 1.0).unwrap();
        assert!((trt / deficit_radius() - 0.192).abs() < 1e-12, "{trt}");
        let below = product("mrt", 0.52).unwrap();
        assert!(
            (below / deficit_radius() + 0.036).abs() < 1e-12,
            "below the table: its first row"
        );
        let err = product("mrt", 2.4).unwrap_err();
        assert!(
            err.contains("coupling.radius_correction") && err.contains("tau = 2.400"),
            "{err}"
        );
        assert!(product("bgk", 1.2).unwrap_err().contains("of bgk (up to 1;"));
        let held = calibrated_drawn_larger("trt", 1.0, 4.0).unwrap();
        assert!(
            (held - trt / 4.0).abs() < 1e-12,
            "a held sphere of 4 cells: {held}"
        );
        let states = [0.003, 0.006].map(|radius| ParticleState {
            radius,
            ..Default::default()
        });
        let lattice = LatticeStates {
            states: &states,
            origin: [0.0; 3],
            dx: 0.001,
            dt: 1e-3,
            deficit_product: 0.75,
        };
        assert_eq!(lattice.particle(0).radius, 3.25, "3 cells + 0.75 / 3");
        assert_eq!(lattice.radius(1), 6.125, "the deficit falls as 1 / radius");
        let small = [ParticleState {
            radius: 0.001,
            ..Default::default()
        }];
        let lattice = LatticeStates {
            states: &small,
            ..lattice
        };
        assert_eq!(lattice.radius(0), 1.375, "below 2 cells, the deficit of 2");
    }

    const TEN_CATE_E1: &str = include_str!("../../validation/scenes/ten-cate-e1.toml");

    /// Ten Cate E4 (Re 32) at 6 cells per diameter: E1's scene with E4's fluid.
    fn ten_cate_e4() -> String {
        TEN_CATE_E1
            .replace("density = 970.0", "density = 960.0")
            .replace("dynamic_viscosity = 0.373", "dynamic_viscosity = 0.058")
            .replace("velocity_scale = 0.038", "velocity_scale = 0.128")
    }

    /// The lattice units of a scene's text.
    fn units(text: &str) -> LatticeUnits {
        let scene = scene::Scene::parse(text, "e1.toml").expect("scene");
        scene.lattice_units.expect("lattice")
    }

    #[test]
    fn the_correction_warns_where_a_moving_spheres_boundary_layer_is_under_two_cells() {
        let e1 = TEN_CATE_E1;
        assert_eq!(
            correction_warning(&units(e1), 0.015),
            None,
            "E1: Re 1.5, 6 cells per diameter: 4.9 cells"
        );
        let e4 = ten_cate_e4();
        let warning = correction_warning(&units(&e4), 0.015).expect("E4: Re 32, 6 cells: 1.06");
        assert!(
            warning.contains("Reynolds number 31.8")
                && warning.contains("spans 1.06 cells")
                && warning.contains("refine to 12 cells per diameter"),
            "{warning}"
        );
        let e4_12 = e4.replace("dx = 0.0025", "dx = 0.00125");
        assert_eq!(
            correction_warning(&units(&e4_12), 0.015),
            None,
            "E4 at 12 cells per diameter: 2.13 cells"
        );
        let e4_bgk = e4.replace("operator = \"trt\"", "operator = \"bgk\"");
        assert_eq!(
            correction_warning(&units(&e4_bgk), 0.015),
            None,
            "BGK's held and towed sphere agree"
        );
    }

    /// SMALL_SPHERE_DRAG holds the runs of validation/lbm/REPORT.md's section, row by row: BGK
    /// and MRT at rest, TRT moving.
    #[test]
    fn the_small_sphere_drag_is_the_reports() {
        let section =
            crate::validate::report_section("## Immersed moving boundary: spheres of a few cells and less");
        for (d, [bgk, trt, mrt]) in SMALL_SPHERE_DRAG {
            let row = section
                .lines()
                .find(|l| l.starts_with(&format!("| {d:.1} |")))
                .unwrap_or_else(|| panic!("no row for {d} cells"));
            let cells: Vec<&str> = row.split(" | ").collect();
            let pct = |e: f64| format!("{e:+.1}%");
            let expected = [bgk[0], bgk[1], trt[0], trt[1], mrt[0], mrt[1]].map(pct);
            let found = [
                cells[3],
                cells[4],
                cells[6],
                cells[8],
                cells[9],
                cells[10].trim_end_matches(" |"),
            ];
            assert_eq!(found, expected.each_ref().map(|s| s.as_str()), "{row}");
        }
    }

    /// SMALL_SPHERE_DRAG_CALIBRATED holds the runs of the report's table of the same spheres drawn
    /// larger by the radius correction.
    #[test]
    fn the_calibrated_small_sphere_drag_is_the_reports() {
        let section =
            crate::validate::report_section("## Immersed moving boundary: spheres of a few cells and less");
        let table = section
            .split("drawn larger by (tau 0.6 / 1, cells)")
            .nth(1)
            .expect("the table");
        for (d, [tau_06, tau_1]) in SMALL_SPHERE_DRAG_CALIBRATED {
            let row = table
                .lines()
                .find(|l| l.starts_with(&format!("| {d:.1} |")))
                .unwrap_or_else(|| panic!("no row for {d} cells"));
            let cells: Vec<&str> = row.split(" | ").collect();
            assert_eq!(
                [cells[2], cells[3].trim_end_matches(" |")],
                [format!("{tau_06:+.1}%"), format!("{tau_1:+.1}%")]
                    .each_ref()
                    .map(|s| s.as_str()),
                "{row}"
            );
        }
    }

    /// E1's lattice (TRT, tau 1.2, dx 2.5 mm): its 15 mm sphere (6 cells) is not warned of; a 10
    /// mm one (4 cells) is, with the measured -16% / -22%, 5 mm (2 cells) -45% / -57%; MRT at tau
    /// 0.6 drags enough at 5 cells (-7%) but not at 4 (-10%).
    #[test]
    fn particles_of_a_few_cells_are_warned_of_too_little_drag() {
        let e1 = units(TEN_CATE_E1);
        assert_eq!(small_sphere_warning(&e1, 0.015, false), None, "6 cells");
        let four = small_sphere_warning(&e1, 0.010, false).expect("4 cells");
        assert!(
            four.contains("are 4.0 cells across")
                && four.contains("measured -16% at tau 0.6 and -22% at tau 1 (trt")
                && four.contains("Refine lattice.dx to 1.667e-3 m (6 cells per diameter)")
                && four.contains("\"calibrated\": +2% and +13%"),
            "{four}"
        );
        let two = small_sphere_warning(&e1, 0.005, false).expect("2 cells");
        assert!(
            two.contains("measured -45% at tau 0.6 and -57% at tau 1"),
            "{two}"
        );
        let mrt = units(
            &TEN_CATE_E1
                .replace("operator = \"trt\"", "operator = \"mrt\"")
                .replace("mach = 0.1", "mach = 0.1\ntau = 0.6"),
        );
        assert_eq!(
            small_sphere_warning(&mrt, 0.0125, false),
            None,
            "MRT, 5 cells, tau 0.6: -7.4%"
        );
        assert!(
            small_sphere_warning(&mrt, 0.010, false).is_some(),
            "MRT, 4 cells, tau 0.6: -10.2%"
        );
        // Drawn larger by the radius correction (TRT): over-corrected at tau 1.2 and 4 cells
        // (+13%), within 2% at tau 0.6; the correction is not measured at this size with MRT.
        let four_drawn = small_sphere_warning(&e1, 0.010, true).expect("TRT, tau 1.2, 4 cells");
        assert!(
            four_drawn.contains("drawn larger by coupling.radius_correction = \"calibrated\", measured +2% at tau 0.6 and +13% at tau 1"),
            "{four_drawn}"
        );
        let trt_06 = units(&TEN_CATE_E1.replace("mach = 0.1", "mach = 0.1\ntau = 0.6"));
        assert_eq!(
            small_sphere_warning(&trt_06, 0.010, true),
            None,
            "TRT, tau 0.6, 4 cells: +1.7%"
        );
        assert!(small_sphere_warning(&mrt, 0.010, true)
            .is_some_and(|w| w.contains("not measured at this size but with trt")));
    }

    #[test]
    fn spheres_whose_boundary_layer_spans_under_a_cell_are_warned_of_too_much_drag() {
        let e1 = TEN_CATE_E1;
        assert_eq!(resolution_warning(&units(e1), 0.015), None, "E1: Re 1.5");
        let e4 = ten_cate_e4();
        assert_eq!(
            resolution_warning(&units(&e4), 0.015),
            None,
            "E4: Re 32, 6 cells: 1.06"
        );
        // Water and a 3 mm grain at 0.1 m/s: Re 300 (the fluidized bed's).
        let bed = e4
            .replace("density = 960.0", "density = 1000.0")
            .replace("dynamic_viscosity = 0.058", "dynamic_viscosity = 0.001")
            .replace("velocity_scale = 0.128", "velocity_scale = 0.1")
            .replace("dx = 0.0025", "dx = 0.0005");
        let warning = resolution_warning(&units(&bed), 0.003).expect("Re 300, 6 cells: 0.35");
        assert!(
            warning.contains("Reynolds number 300")
                && warning.contains("spans 0.35 cells")
                && warning.contains("Refine to 18 cells per diameter"),
            "{warning}"
        );
        let slow = bed.replace("velocity_scale = 0.1", "velocity_scale = 0.008");
        assert_eq!(
            resolution_warning(&units(&slow), 0.003),
            None,
            "Re 24, 6 cells: 1.22"
        );
    }

    #[test]
    fn a_lattice_warns_near_tau_one_half_where_its_operator_blew_up() {
        let at = |tau: f64, operator: &str, faces: &str| {
            units(
                &TEN_CATE_E1
                    .replace("mach = 0.1", &format!("mach = 0.1\ntau = {tau}\n{faces}"))
                    .replace("operator = \"trt\"", &format!("operator = \"{operator}\"")),
            )
        };
        let inlet = "[lattice.faces]\nz_min = { type = \"velocity_inlet\", velocity = [0.0, 0.0, 0.01] }\n\
                     z_max = { type = \"pressure_outlet\", pressure = 0.0 }";
        let particles = stability_warning(&at(0.505, "trt", ""), true).expect("0.505 with particles");
        assert!(
            particles.contains("tau = 0.5050")
                && particles.contains("= 38.0")
                && particles.contains("periodic box"),
            "{particles}"
        );
        assert_eq!(
            stability_warning(&at(0.512, "trt", ""), true),
            None,
            "held at 0.5096"
        );
        assert_eq!(
            stability_warning(&at(0.505, "trt", ""), false),
            None,
            "no particles, no inlet"
        );
        let with_inlet = stability_warning(&at(0.525, "trt", inlet), false).expect("0.525 with an inlet");
        assert!(with_inlet.contains("velocity inlet"), "{with_inlet}");
        assert_eq!(
            stability_warning(&at(0.54, "trt", inlet), true),
            None,
            "held at 0.538"
        );
        assert_eq!(
            stability_warning(&at(0.505, "mrt", inlet), true),
            None,
            "MRT held"
        );
        assert_eq!(stability_warning(&at(0.511, "bgk", inlet), true), None, "BGK");
        let bgk = stability_warning(&at(0.505, "bgk", inlet), false).expect("BGK at 0.505");
        assert!(
            bgk.contains("with BGK") && bgk.contains("where it blew up at 0.5024"),
            "{bgk}"
        );
        assert_eq!(
            stability_warning(&at(0.505, "bgk", ""), false),
            None,
            "BGK, no particles, no inlet"
        );
        let bounded = |tau: f64, faces: &str| {
            let mut u = at(tau, "trt", faces);
            u.magic = scene::lattice::bounded_magic(u.magic, tau, 1.0);
            u
        };
        let trt = stability_warning(&bounded(0.505, ""), true).expect("bounded TRT at 0.505");
        assert!(
            trt.contains("TRT with tau- = 1.00") && trt.contains("tau- <= 1 held to tau 0.5048"),
            "{trt}"
        );
        assert_eq!(
            stability_warning(&bounded(0.52, inlet), true),
            None,
            "bounded TRT above 0.51: the inlet held"
        );
        assert!(
            particles.contains("lattice.max_tau_minus = 1"),
            "the unbounded TRT warning names the bound: {particles}"
        );
    }

    #[test]
    fn a_lattice_warns_where_the_drag_falls_more_than_the_limit() {
        assert!(tau_warning("trt", 0.6).is_none());
        assert!(tau_warning("mrt", 0.9).is_none(), "MRT -5.5% at 0.9");
        let trt = tau_warning("trt", 1.2).expect("TRT at 1.2: -12.9%");
        assert!(
            trt.contains("-12.9% at this tau") && trt.contains("trt at tau 0.55 measured -4.0%"),
            "{trt}"
        );
        let bgk = tau_warning("bgk", 0.9).expect("BGK at 0.9: -9.0%");
        assert!(bgk.contains("bgk at tau 0.6 measured +0.1%"), "{bgk}");
        let far = tau_warning("trt", 2.25).expect("beyond the table");
        assert!(
            far.contains("beyond the measured taus (-20.7% at tau 2)"),
            "{far}"
        );
    }
}
