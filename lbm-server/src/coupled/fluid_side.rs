//! [`FluidSide`]: what computes the particles' hydrodynamic loads in a coupled run.
//!
//! Gravity and buoyancy are each applied once: the DEM applies gravity to the particles; the fluid
//! has no gravity (so no hydrostatic pressure gradient) and this side adds the buoyancy
//! -rho_f V g to the hydrodynamic force computed on the lattice.
//!
//! A `lattice.body_acceleration` a drives the fluid like a mean pressure gradient -grad p = rho_f a
//! that the lattice does not carry either; the particles feel its share rho_f V a, added here too
//! (without it a fixed bed's drag is short by that share: the Zick-Homsy check in docs/imb.md).

use super::health::finite_load;
use super::radius_correction::radius_deficit_product;
use super::states::LatticeStates;
use super::warnings::lattice_warnings;
use super::ways::trial;
use crate::checkpoint::{Loaded, OutputPositions};
use crate::fields::{probe_cells, FieldOutput};
use crate::fluid::{health_of, setup_of};
use crate::lbm::geometry::Setup;
use crate::lbm::gpu::Gpu;
use crate::lbm::imb::{covered_fraction, ImbOptions, SolidCollision};
use crate::lubrication::HeldLubrication;
use crate::parallel::{resume_blocks, BlockLattice, Communicator, Decomposition, FieldPieces};
use crate::terminal::Warning;
use crate::trials::Trial;
use protocol::{ParticleReply, ParticleState, Physics};
use scene::lattice::LatticeUnits;
use scene::Scene;
use std::path::Path;
use std::rc::Rc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// What computes the particles' hydrodynamic loads: the lattice with its units, the buoyancy it
/// adds and the lubrication correction. On several ranks every rank holds one (its block of the
/// lattice), rank 0's leading the others step by step (`ranks.rs`).
pub struct FluidSide {
    pub(super) lattice: BlockLattice,
    /// The run's ranks.
    pub(super) comm: Rc<dyn Communicator>,
    pub(super) units: LatticeUnits,
    pub(super) origin: [f64; 3],
    fluid_density: f64,
    gravity: [f64; 3],
    lubrication: Option<HeldLubrication>,
    /// Each sphere of r cells is drawn r + this / max(r, 2) (`coupling.radius_correction`; 0
    /// without it).
    deficit_product: f64,
    pub(super) steps: u64,
    /// The start-up trial of the kernels and ways the scene leaves open (trials.rs).
    pub(super) trial: Trial,
    /// The fraction of the cells the initial particles cover (`covered_fraction`), for the log.
    covered: f64,
    /// When the fluid side was made: the trial's clock.
    pub(super) made: std::time::Instant,
    /// The run's field outputs: those the scene asks for (`output.fields_interval` above 0,
    /// `output.line`), and last_good.vti where the fluid blows up (rank 0's; none elsewhere).
    pub(super) fields: Option<FieldOutput>,
    /// On several ranks, every rank's pieces of the snapshots (and of last_good).
    pub(super) pieces: Option<FieldPieces>,
    /// The probe lines' cells (`output.line`; indices of the whole lattice), on every rank.
    pub(super) line_cells: Vec<usize>,
    /// The step of the last health check that passed (its fields kept on the device).
    pub(super) last_good: Option<u64>,
    /// `output.fields_interval` and `output.interval` (the probe lines'), in steps.
    pub(super) fields_every: u64,
    pub(super) lines_every: u64,
    /// Steps of the run (its last gets a snapshot and the lines).
    pub(super) run_steps: u64,
    /// What the scene's settings are warned of (`warnings.rs`), said after the run's header.
    warnings: Vec<Warning>,
    /// Whether the run said that covers were dropped (`health.rs`).
    pub(super) said_dropped: bool,
    /// Where the field outputs stood at the last step before those only a last step gets (a
    /// checkpoint there records these: a run resumed from it writes what an uninterrupted one
    /// does).
    pub(super) before_last: Option<OutputPositions>,
}

impl FluidSide {
    /// The fluid a scene asks for, for a run of `steps` steps writing its field outputs into `out`;
    /// resumed, in the state of the checkpoint `resumed` (rank 0's: it sends the other ranks
    /// theirs); on the ranks of `comm`, this rank's block of the lattice cut into `blocks` (the
    /// ranks agree that each made its own).
    pub fn for_scene(
        scene: &Scene,
        steps: u64,
        out: &Path,
        resumed: Option<&Loaded>,
        (comm, blocks): (Rc<dyn Communicator>, [usize; 3]),
    ) -> Result<FluidSide, String> {
        let made = Self::make(scene, steps, out, resumed, (comm.clone(), blocks));
        if !crate::parallel::all(&*comm, made.is_ok()) {
            return Err(made.err().unwrap_or_else(|| {
                "another rank could not start its block of the fluid (its error above)".into()
            }));
        }
        // Every rank, once all have made their block (rank 0 sends each its part).
        let mut fluid = made?;
        fluid.trial.agree_open(&*comm);
        resume_blocks(&mut fluid.lattice, &*comm, resumed)?;
        fluid.steps = fluid.lattice.time();
        Ok(fluid)
    }

    fn make(
        scene: &Scene,
        steps: u64,
        out: &Path,
        resumed: Option<&Loaded>,
        (comm, blocks): (Rc<dyn Communicator>, [usize; 3]),
    ) -> Result<FluidSide, String> {
        let units = lattice_units(scene)?;
        // The scene's coupling settings are checked before the device is opened.
        let deficit_product = radius_deficit_product(
            &scene.coupling.radius_correction,
            units.operator.name(),
            units.tau,
        )?;
        let radii: Vec<f64> = scene.initial_particles().iter().map(|p| p.radius).collect();
        let covered = covered_fraction(radii.iter().map(|&r| units.cells(r)), units.n.iter().product());
        let (lattice, trial) = coupled_block(scene, &units, steps, (&*comm, blocks))?;
        let (fields, pieces) = field_outputs(scene, &units, out, resumed, (&*comm, &lattice.decomposition))?;
        let lubrication = scene
            .coupling
            .lubrication
            .then(|| HeldLubrication::for_lattice(scene, &units));
        let warnings = lattice_warnings(scene, &units, &radii);
        Ok(FluidSide {
            lattice,
            comm,
            line_cells: probe_cells(scene, &units),
            units,
            origin: scene.domain.min,
            fluid_density: scene.fluid.density,
            gravity: scene.gravity,
            lubrication,
            deficit_product,
            // The checkpoint's, where the run resumes (`for_scene`).
            steps: 0,
            trial,
            covered,
            made: std::time::Instant::now(),
            fields,
            pieces,
            last_good: None,
            fields_every: scene.output.fields_interval,
            lines_every: scene.output.interval,
            run_steps: steps,
            warnings,
            said_dropped: false,
            before_last: None,
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

    /// Says what the scene's settings are warned of.
    pub fn say_warnings(&self) {
        for warning in &self.warnings {
            warning.say();
        }
    }

    /// The fluid in the run's short header: the lattice, its operator and tau, the coupling.
    pub fn brief(&self) -> String {
        let u = &self.units;
        format!(
            "lattice {}x{}x{} ({}, tau {:.3}), immersed moving boundary",
            u.n[0], u.n[1], u.n[2], u.operator, u.tau
        )
    }

    /// The device the lattice runs on.
    pub fn device(&self) -> &str {
        self.lattice.lattice.adapter()
    }

    /// On several ranks, "; ", the ranks and their blocks, and the halo exchange the steps take
    /// (`BlockLattice::exchange_said`); nothing on one.
    pub fn exchange(&self) -> String {
        let Some(exchange) = self.lattice.exchange_said() else {
            return String::new();
        };
        let b = self.lattice.decomposition.blocks;
        let ranks = self.comm.size();
        format!("; {ranks} ranks in {}x{}x{} blocks, {exchange}", b[0], b[1], b[2])
    }

    /// The fluid as `--verbose` describes it: the lattice's scales, the device, the way the
    /// covered cells are treated, the lubrication and the radius correction.
    pub fn describe(&self) -> String {
        let u = &self.units;
        format!(
            "lattice {}x{}x{} ({}, tau {:.4}, dx {:e} m, dt {:e} s) on {}, {}, immersed moving \
             boundary ({}, {:.1}% of the cells covered at the start{}){}{}{}",
            u.n[0],
            u.n[1],
            u.n[2],
            u.operator,
            u.tau,
            u.dx,
            u.dt,
            self.lattice.lattice.adapter(),
            self.lattice.lattice.kernel().describe(),
            self.lattice.lattice.covered_cells().describe(),
            100.0 * self.covered,
            match self.trial.open() {
                true => format!("; {}", self.trial.describe()),
                false => String::new(),
            },
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
            },
            self.exchange()
        )
    }

    /// The lattice, for summary.json.
    pub fn units(&self) -> &LatticeUnits {
        &self.units
    }

    /// Advances this rank's fluid one step with the particles `states` (SI) and returns their
    /// loads (SI; at rank 0, which alone has them): the lattice's, buoyancy added (`loads`), then
    /// the lubrication correction; then the health check where one is due, and the field outputs.
    /// The step starts at `now` on rank 0's clock (for the start-up trial). (`FluidSide::step`
    /// leads the other ranks into it: `ranks.rs`.)
    pub(super) fn step_here(
        &mut self,
        states: &[ParticleState],
        out: &mut Vec<ParticleReply>,
        now: f64,
    ) -> Result<(), String> {
        self.take_way(now);
        let not_finite = self.loads(states, out)?;
        if let (Some(lubrication), 0) = (&self.lubrication, self.comm.rank()) {
            lubrication.apply(states, out);
        }
        self.steps += 1;
        // The loads are rank 0's: the ranks agree whether one is not finite.
        if !crate::parallel::all(&*self.comm, !not_finite) {
            return Err(self.not_finite(out.iter().find(|r| !finite_load(r))));
        }
        if self.steps.is_multiple_of(self.units.check_interval) {
            self.check()?;
        }
        self.write_fields()
    }

    /// The lattice's step with the particles `states` (SI), their loads (SI) in `out`: the
    /// lattice's hydrodynamic force and torque, and the share of the pressure gradients it does
    /// not carry. Whether a load is not finite (found by the pass that converts the loads: no
    /// pass of its own).
    fn loads(&mut self, states: &[ParticleState], out: &mut Vec<ParticleReply>) -> Result<bool, String> {
        let units = &self.units;
        let lattice_states = LatticeStates {
            states,
            origin: self.origin,
            units,
            deficit_product: self.deficit_product,
        };
        let force_unit = units.force_unit(self.fluid_density);
        let torque_unit = units.torque_unit(self.fluid_density);
        // What the lattice does not carry: the hydrostatic gradient (buoyancy) and the mean
        // pressure gradient that the body acceleration stands for, as -grad p / rho_f.
        let pressure_acceleration: [f64; 3] =
            std::array::from_fn(|a| units.si_acceleration(units.force[a]) - self.gravity[a]);
        let fluid_density = self.fluid_density;
        let not_finite = AtomicBool::new(false);
        let comm = self.comm.clone();
        let load = |j: usize, l: crate::lbm::imb::Load| {
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
        };
        self.lattice
            .step_coupled_with(&lattice_states, out, load, &*comm)?;
        Ok(not_finite.into_inner())
    }
}

/// The immersed boundary's options of a scene (`coupling.*`): its slots, its weighting and its
/// solid collision (the way of its covered cells is the trial's).
fn imb_options(scene: &Scene) -> Result<ImbOptions, String> {
    let collision = &scene.coupling.solid_collision;
    Ok(ImbOptions {
        slots: scene.coupling.slots,
        seed_weighting: scene.coupling.weighting == "seed",
        solid_collision: SolidCollision::from_name(collision).ok_or_else(|| {
            format!("coupling.solid_collision = {collision:?}: expected \"noble-torczynski\" or \"superposition\"")
        })?,
        ..ImbOptions::default()
    })
}

/// The scene's lattice, which a coupled run needs.
fn lattice_units(scene: &Scene) -> Result<LatticeUnits, String> {
    scene.lattice_units.clone().ok_or_else(|| {
        format!(
            "scene '{}' has particles but no [lattice]: the fluid needs one",
            scene.name
        )
    })
}

/// The field files of the run into `out` (rank 0: the whole lattice's, continuing those of the
/// checkpoint `resumed` from), and on several ranks each rank's pieces of them (block `d`).
fn field_outputs(
    scene: &Scene,
    units: &LatticeUnits,
    out: &Path,
    resumed: Option<&Loaded>,
    (comm, d): (&dyn Communicator, &Decomposition),
) -> Result<(Option<FieldOutput>, Option<FieldPieces>), String> {
    let pieces = (comm.size() > 1).then(|| FieldPieces::new(scene, units, out.to_path_buf(), d, comm.rank()));
    let fields = match comm.rank() {
        0 => Some(FieldOutput::new(
            scene,
            units,
            out,
            resumed.map(|l| &l.header.outputs),
        )?),
        _ => None,
    };
    Ok((fields, pieces))
}

/// This rank's block of the scene's lattice cut into `blocks`, coupled to particles, on this rank's
/// device, with the start-up trial that chose its kernel and way of treating the covered cells.
fn coupled_block(
    scene: &Scene,
    units: &LatticeUnits,
    steps: u64,
    (comm, blocks): (&dyn Communicator, [usize; 3]),
) -> Result<(BlockLattice, Trial), String> {
    let gpu = Arc::new(Gpu::for_local_rank(comm.local_rank())?);
    let cpu = gpu.on_cpu();
    let trial = trial(scene, units.kernel, steps, cpu)?;
    let options = ImbOptions {
        covered_cells: trial.kept().way,
        ..imb_options(scene)?
    };
    let setup = Setup {
        kernel: trial.kept().kernel,
        ..setup_of(units)
    };
    let d = Decomposition::new(units.n, scene.periodic_axes(), blocks, comm.rank());
    let mut lattice = BlockLattice::with_coupling(gpu, setup, health_of(units), d, Some(options))?;
    lattice.set_overlap_asked(scene.parallel.overlap);
    Ok((lattice, trial))
}
