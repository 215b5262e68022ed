//! `[dem.contact]`: the contact model, its laws and the switches that select a reference
//! code's variant of each.

use super::Dem;
use crate::numbers::{fail, positive};
use crate::SceneError;
use serde::Deserialize;

/// The contact model: normal, tangential and rolling parts and the switches that select a
/// reference code's variant of each.
#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct Contact {
    /// `liggghts` (default) or `yade`.
    #[serde(default)]
    pub preset: Preset,
    #[serde(default)]
    pub normal: NormalLaw,
    #[serde(default)]
    pub tangential: TangentialLaw,
    #[serde(default)]
    pub rolling: RollingLaw,
    /// Linear law: normal stiffness k_n [N/m].
    pub normal_stiffness: Option<f64>,
    /// Linear law: normal damping gamma_n [N s/m] (default: from the restitution).
    pub normal_damping: Option<f64>,
    /// Linear law: tangential stiffness k_t [N/m] (default k_n).
    pub tangential_stiffness: Option<f64>,
    /// Linear law: tangential damping gamma_t [N s/m] (default gamma_n).
    pub tangential_damping: Option<f64>,
    /// Linear law: contact time t_c [s]; k_n and gamma_n follow from it and the restitution.
    pub contact_time: Option<f64>,
    /// Hertz law: impact velocity for the contact time of the time-step rule [m/s]
    /// (default sqrt(2 |g| H) + the fastest initial speed, H the domain height).
    pub impact_velocity: Option<f64>,
    pub damping_law: Option<DampingLaw>,
    /// Normal force clamped to >= 0 (no attraction at the end of a damped contact).
    pub clamp_normal_force: Option<bool>,
    pub tangential_spring: Option<TangentialSpring>,
    /// Effective radius of a sphere-wall contact = factor * r (LIGGGHTS 1, YADE 0.5).
    pub wall_radius_factor: Option<f64>,
    pub coulomb_normal: Option<CoulombNormal>,
    pub lever_arm: Option<LeverArm>,
}

#[derive(Debug, Clone, Copy, Deserialize, Default, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Preset {
    #[default]
    Liggghts,
    Yade,
}

#[derive(Debug, Clone, Copy, Deserialize, Default, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum NormalLaw {
    /// F = 4/3 E* sqrt(R*) d^(3/2) + damping.
    #[default]
    Hertz,
    /// F = k_n d + gamma_n v_n (the seed paper's spring-dashpot).
    Linear,
}

#[derive(Debug, Clone, Copy, Deserialize, Default, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum TangentialLaw {
    /// Spring-dashpot with Coulomb slider and contact history.
    #[default]
    History,
    /// Frictionless.
    None,
}

#[derive(Debug, Clone, Copy, Deserialize, Default, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum RollingLaw {
    #[default]
    None,
    /// Constant directional torque: M_r = -mu_r R* |F_n| w_rel / |w_rel|.
    ConstantTorque,
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum DampingLaw {
    /// gamma = 2 sqrt(5/6) |beta| sqrt(S m*), beta = ln e / sqrt(ln^2 e + pi^2).
    Liggghts,
    /// gamma = 2 beta sqrt(m* S), beta from e by Thornton et al. 2013 (B6/B7).
    Thornton,
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum TangentialSpring {
    /// F_t = -k_t xi, xi the total shear displacement (LIGGGHTS).
    Total,
    /// F_t += -k_t v_t dt, the force rotated with the contact (YADE).
    Incremental,
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum CoulombNormal {
    /// mu |F_n| of the total normal force, damping included (LIGGGHTS).
    Absolute,
    /// mu max(F_n, 0) (YADE).
    Clamped,
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum LeverArm {
    /// r - d/2: the contact point in the middle of the overlap (LIGGGHTS).
    ContactPoint,
    /// r (YADE).
    Radius,
}

impl Dem {
    pub(super) fn validate_contact(&self, file: &str) -> Result<(), SceneError> {
        let c = &self.contact;
        let optional = [
            ("dem.contact.normal_stiffness", c.normal_stiffness, "N/m"),
            ("dem.contact.normal_damping", c.normal_damping, "N s/m"),
            ("dem.contact.tangential_stiffness", c.tangential_stiffness, "N/m"),
            ("dem.contact.tangential_damping", c.tangential_damping, "N s/m"),
            ("dem.contact.contact_time", c.contact_time, "s"),
            ("dem.contact.impact_velocity", c.impact_velocity, "m/s"),
            ("dem.contact.wall_radius_factor", c.wall_radius_factor, ""),
        ];
        for (field, v, unit) in optional {
            match v {
                Some(v) if field.ends_with("damping") && v.is_finite() && v >= 0.0 => {}
                Some(v) => positive(file, field, v, unit)?,
                None => {}
            }
        }
        let linear_only = [
            ("normal_stiffness", c.normal_stiffness),
            ("normal_damping", c.normal_damping),
            ("tangential_stiffness", c.tangential_stiffness),
            ("tangential_damping", c.tangential_damping),
            ("contact_time", c.contact_time),
        ];
        match c.normal {
            NormalLaw::Hertz => {
                if let Some((name, v)) = linear_only.iter().find(|(_, v)| v.is_some()) {
                    return Err(fail(
                        file,
                        format!("dem.contact.{name}"),
                        v.unwrap(),
                        "applies to normal = \"linear\" only (Hertz takes its stiffness from the materials)",
                    ));
                }
            }
            NormalLaw::Linear => {
                if c.normal_stiffness.is_some() == c.contact_time.is_some() {
                    return Err(fail(
                        file,
                        "dem.contact.normal",
                        "\"linear\"",
                        "needs exactly one of normal_stiffness [N/m] or contact_time [s]",
                    ));
                }
                if let (Some(_), Some(damping)) = (c.contact_time, c.normal_damping) {
                    return Err(fail(
                        file,
                        "dem.contact.normal_damping",
                        damping,
                        "cannot be given with contact_time (the damping follows from it and the restitution)",
                    ));
                }
            }
        }
        Ok(())
    }
}
