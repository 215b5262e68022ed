//! `[[dem.material]]`: a solid's elastic and frictional properties, and the fields that name a
//! material.

use super::Dem;
use crate::numbers::{fail, non_negative, positive};
use crate::SceneError;
use serde::Deserialize;

/// A solid's elastic and frictional properties.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    pub name: String,
    /// Young's modulus E [Pa].
    #[serde(default = "default_young")]
    pub young_modulus: f64,
    /// Poisson's ratio nu [-], in [0, 0.5).
    #[serde(default = "default_poisson")]
    pub poisson_ratio: f64,
    /// Coefficient of restitution e [-], in (0, 1].
    #[serde(default = "default_restitution")]
    pub restitution: f64,
    /// Coulomb friction coefficient mu [-] (>= 0).
    #[serde(default = "default_friction")]
    pub friction: f64,
    /// Rolling friction coefficient mu_r [-] (>= 0), used by `contact.rolling`.
    #[serde(default)]
    pub rolling_friction: f64,
    /// Solid density [kg/m^3] (default: `particles.density`).
    pub density: Option<f64>,
}

impl Default for Material {
    /// A soft glass-like solid, E = 5 MPa as in the LIGGGHTS examples (real glass, 60 GPa, would
    /// need a time step 100x smaller for the same result in a dense granular flow).
    fn default() -> Self {
        Self {
            name: "default".into(),
            young_modulus: default_young(),
            poisson_ratio: default_poisson(),
            restitution: default_restitution(),
            friction: default_friction(),
            rolling_friction: 0.0,
            density: None,
        }
    }
}

fn default_young() -> f64 {
    5.0e6
}
fn default_poisson() -> f64 {
    0.3
}
fn default_restitution() -> f64 {
    0.9
}
fn default_friction() -> f64 {
    0.5
}

impl Dem {
    /// The materials, with the built-in default when the scene names none.
    pub fn materials(&self) -> Vec<Material> {
        if self.material.is_empty() {
            vec![Material::default()]
        } else {
            self.material.clone()
        }
    }

    /// Index into [`Dem::materials`] of a material name (`None`: the particle material).
    pub fn material_index(&self, name: Option<&str>) -> usize {
        let name = name.or(self.particle_material.as_deref());
        name.and_then(|n| self.materials().iter().position(|m| m.name == n))
            .unwrap_or(0)
    }

    pub(super) fn material_name(&self, name: Option<&str>) -> String {
        self.materials()[self.material_index(name)].name.clone()
    }
    pub(super) fn validate_materials(&self, file: &str) -> Result<(), SceneError> {
        for (i, m) in self.material.iter().enumerate() {
            self.validate_material(file, i, m)?;
        }
        let known: Vec<String> = self.materials().into_iter().map(|m| m.name).collect();
        for (field, name) in self.material_references() {
            if let Some(name) = name.filter(|n| !known.contains(n)) {
                return Err(fail(
                    file,
                    field,
                    format!("{name:?}"),
                    format!("no such material (known: {})", known.join(", ")),
                ));
            }
        }
        Ok(())
    }

    /// Material `m`, the scene's `i`-th: a unique name, its moduli, restitution, frictions and
    /// density in range.
    fn validate_material(&self, file: &str, i: usize, m: &Material) -> Result<(), SceneError> {
        let field = |f: &str| format!("dem.material[{i}].{f}");
        if m.name.is_empty() || self.material[..i].iter().any(|o| o.name == m.name) {
            return Err(fail(
                file,
                field("name"),
                format!("{:?}", m.name),
                "must be non-empty and unique",
            ));
        }
        positive(file, &field("young_modulus"), m.young_modulus, "Pa")?;
        if !(0.0..0.5).contains(&m.poisson_ratio) {
            return Err(fail(
                file,
                field("poisson_ratio"),
                m.poisson_ratio,
                "must lie in [0, 0.5)",
            ));
        }
        if !(m.restitution > 0.0 && m.restitution <= 1.0) {
            return Err(fail(
                file,
                field("restitution"),
                m.restitution,
                "must lie in (0, 1]",
            ));
        }
        for (name, v) in [("friction", m.friction), ("rolling_friction", m.rolling_friction)] {
            non_negative(file, &field(name), v, "")?;
        }
        if let Some(rho) = m.density {
            positive(file, &field("density"), rho, "kg/m^3")?;
        }
        Ok(())
    }

    /// Every field that names a material, with the name it gives (None: the default).
    fn material_references(&self) -> Vec<(String, Option<&String>)> {
        let mut names = vec![
            (
                "dem.particle_material".to_string(),
                self.particle_material.as_ref(),
            ),
            (
                "dem.domain_wall_material".to_string(),
                self.domain_wall_material.as_ref(),
            ),
        ];
        let listed: [(&str, Vec<&Option<String>>); 4] = [
            ("plane", self.plane.iter().map(|p| &p.material).collect()),
            ("box", self.boxes.iter().map(|b| &b.material).collect()),
            ("insert", self.insert.iter().map(|b| &b.material).collect()),
            ("csv", self.csv.iter().map(|b| &b.material).collect()),
        ];
        for (kind, materials) in listed {
            for (i, m) in materials.into_iter().enumerate() {
                names.push((format!("dem.{kind}[{i}].material"), m.as_ref()));
            }
        }
        names
    }
}
