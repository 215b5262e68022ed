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

use crate::fluid::{health_of, setup_of};
use crate::lbm::gpu::{Gpu, Lattice};
use crate::lbm::imb::{covered_fraction, CoveredCells, ImbOptions, Particles, SolidParticle};
use crate::lubrication::Lubrication;
use protocol::{ParticleReply, ParticleState, Physics};
use scene::lattice::{LatticeFace, LatticeUnits};
use scene::Scene;
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
    steps: u64,
}

/// Above this tau the immersed boundary's drag falls measurably (validation/imb/REPORT.md).
const IMB_TAU_MAX: f64 = 1.0;

/// The warning for a coupled lattice whose tau is above [`IMB_TAU_MAX`], if it is.
fn tau_warning(tau: f64) -> Option<String> {
    (tau > IMB_TAU_MAX).then(|| {
        format!(
            "lattice tau = {tau:.3}: above {IMB_TAU_MAX} the immersed boundary's drag depends on tau and falls \
             (Ten Cate E1 at 6 cells per diameter: +6.8% at tau 1.20, +1.5% at 0.85; Zick-Homsy at radius 5: \
             -10.9% at tau 1.0, -5.3% at 0.6); lower lattice.mach (or lattice.velocity_scale) or set \
             lattice.tau to keep tau at or below {IMB_TAU_MAX}"
        )
    })
}

/// The scene's `coupling.covered_cells`, "auto" made definite for this device and the scene's
/// initial particles (their covered fraction of the lattice).
fn covered_cells(
    scene: &Scene,
    units: &LatticeUnits,
    device: wgpu::DeviceType,
) -> Result<CoveredCells, String> {
    let mode = CoveredCells::from_name(&scene.coupling.covered_cells).ok_or_else(|| {
        format!(
            "coupling.covered_cells = {:?}: expected \"auto\", \"fused\" or \"redo\"",
            scene.coupling.covered_cells
        )
    })?;
    let radii = scene.initial_particles().into_iter().map(|p| p.radius / units.dx);
    let cells = units.n.iter().product();
    Ok(mode.for_scene(device, covered_fraction(radii, cells)))
}

impl FluidSide {
    /// The fluid a scene asks for.
    pub fn for_scene(scene: &Scene) -> Result<FluidSide, String> {
        let Some(units) = scene.lattice_units.clone() else {
            return Err(format!(
                "scene '{}' has particles but no [lattice]: the fluid needs one",
                scene.name
            ));
        };
        let gpu = Arc::new(Gpu::new()?);
        let options = ImbOptions {
            slots: scene.coupling.slots,
            seed_weighting: scene.coupling.weighting == "seed",
            covered_cells: covered_cells(scene, &units, gpu.adapter.device_type)?,
        };
        let lattice = Lattice::new(gpu, setup_of(&units), health_of(&units), Some(options))?;
        let lubrication = scene.coupling.lubrication.then(|| lubrication_of(scene, &units));
        if let Some(warning) = tau_warning(units.tau) {
            protocol::say!("lbm-server: warning: {warning}");
        }
        Ok(FluidSide {
            lattice,
            units,
            origin: scene.domain.min,
            fluid_density: scene.fluid.density,
            gravity: scene.gravity,
            lubrication,
            steps: 0,
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
             ({}){}",
            u.n[0],
            u.n[1],
            u.n[2],
            u.operator,
            u.tau,
            u.dx,
            u.dt,
            self.lattice.adapter(),
            if self.lattice.covered_cells_fused() {
                "solid term in the fluid kernels"
            } else {
                "covered cells redone"
            },
            if self.lubrication.is_some() {
                ", lubrication"
            } else {
                ""
            }
        )
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
        };
        let force_unit = self.fluid_density * dx.powi(4) / (dt * dt);
        let torque_unit = force_unit * dx;
        // What the lattice does not carry: the hydrostatic gradient (buoyancy) and the mean
        // pressure gradient that the body acceleration stands for, as -grad p / rho_f.
        let pressure_acceleration: [f64; 3] =
            std::array::from_fn(|a| self.units.force[a] * dx / (dt * dt) - self.gravity[a]);
        let fluid_density = self.fluid_density;
        self.lattice.step_coupled_with(&lattice_states, out, |j, l| {
            let s = &states[j];
            let volume = 4.0 / 3.0 * std::f64::consts::PI * s.radius.powi(3);
            ParticleReply {
                id: s.id,
                force: std::array::from_fn(|a| {
                    l.force[a] * force_unit + fluid_density * volume * pressure_acceleration[a]
                }),
                torque: l.torque.map(|t| t * torque_unit),
            }
        })?;
        if let Some(lubrication) = &self.lubrication {
            lubrication.apply(states, out);
        }
        self.steps += 1;
        if self.steps.is_multiple_of(self.units.check_interval) {
            self.check()?;
        }
        Ok(())
    }

    /// After the run's last step: the health check and the covers' warning, unless the last step
    /// was a check already (a run shorter than `lattice.check_interval`, or its tail beyond the
    /// last multiple, went unchecked).
    pub fn check_last_step(&self) -> Result<(), String> {
        if self.steps.is_multiple_of(self.units.check_interval) {
            return Ok(());
        }
        self.check()
    }

    /// The health check of the lattice, and a warning when cells had more particles than slots.
    fn check(&self) -> Result<(), String> {
        let (_, bad) = self.lattice.fields();
        if let Some(bad) = bad {
            let what = bad.describe(&health_of(&self.units));
            return Err(format!(
                "the fluid became unstable by step {}: {what}",
                self.steps
            ));
        }
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
}

impl Particles for LatticeStates<'_> {
    fn count(&self) -> usize {
        self.states.len()
    }

    fn particle(&self, j: usize) -> SolidParticle {
        let (s, dx) = (&self.states[j], self.dx);
        SolidParticle {
            position: std::array::from_fn(|a| (s.position[a] - self.origin[a]) / dx),
            radius: s.radius / dx,
            velocity: s.velocity.map(|v| v * self.dt / dx),
            angular_velocity: s.angular_velocity.map(|w| w * self.dt),
        }
    }

    fn radius(&self, j: usize) -> f64 {
        self.states[j].radius / self.dx
    }
}
