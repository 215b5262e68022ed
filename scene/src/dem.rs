//! The DEM part of a scene (`[dem]`): materials, contact model, walls, insertion, DEM output.
//!
//! Every field has a default, so scenes written before the DEM existed stay valid. SI units.
//!
//! ```toml
//! [dem]
//! dt = 2.0e-6                 # s, optional: DEM step (default t_c / dt_divisor)
//! particle_material = "glass" # material of particles.sphere / particles.block (default: the first)
//!
//! [[dem.material]]
//! name = "glass"
//! young_modulus = 5.0e6       # Pa
//! poisson_ratio = 0.3
//! restitution = 0.9
//! friction = 0.5
//!
//! [dem.contact]
//! preset = "liggghts"         # or "yade"; switches below override the preset
//! normal = "hertz"            # or "linear"
//!
//! [[dem.plane]]
//! point = [0.0, 0.0, 0.0]
//! normal = [0.0, 0.0, 1.0]    # towards the particles
//!
//! [[dem.insert]]              # a lattice with jitter
//! origin = [0.01, 0.01, 0.01]
//! count = [10, 10, 20]
//! spacing = 0.005
//! radius = [0.0015, 0.002]    # uniform in [min, max]
//! jitter = 0.0004             # m
//! ```

use crate::numbers::{fail, finite3, positive, vec3};
use crate::{InitialParticle, SceneError};
use serde::Deserialize;

mod contact;
mod insert;
mod material;
mod placement;

pub use contact::{
    Contact, CoulombNormal, DampingLaw, LeverArm, NormalLaw, Preset, RollingLaw, TangentialLaw,
    TangentialSpring,
};
use insert::{lattice, read_csv, validate_insert};
pub use insert::{CsvInsert, Insert, Radius};
pub use material::Material;
pub(crate) use placement::idle_boxes;
pub use placement::{validate_placement, MAX_INITIAL_WALL_OVERLAP};

/// The `[dem]` section.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Dem {
    /// DEM time step [s]; default: contact time / `dt_divisor`.
    pub dt: Option<f64>,
    /// The default DEM step is the shortest contact time divided by this (default 50).
    #[serde(default = "default_dt_divisor")]
    pub dt_divisor: f64,
    /// Verlet skin [m]; default: half the smallest radius.
    pub skin: Option<f64>,
    /// Material of the particles of `particles.sphere` and `particles.block` (default: the first).
    pub particle_material: Option<String>,
    /// Materials; without any, [`Material::default`] named `default`.
    #[serde(default)]
    pub material: Vec<Material>,
    #[serde(default)]
    pub contact: Contact,
    /// The faces of `[domain]` act as walls (default: true when the scene defines no plane or box).
    pub domain_walls: Option<bool>,
    /// Material of the domain walls (default: the particle material).
    pub domain_wall_material: Option<String>,
    #[serde(default)]
    pub plane: Vec<Plane>,
    #[serde(rename = "box", default)]
    pub boxes: Vec<BoxWall>,
    /// Particles on a lattice with jitter.
    #[serde(default)]
    pub insert: Vec<Insert>,
    /// Particles read from CSV files.
    #[serde(default)]
    pub csv: Vec<CsvInsert>,
    #[serde(default)]
    pub output: DemOutput,
    /// Particles generated from `insert` and `csv`, filled by [`Dem::load`]: (sphere, material).
    #[serde(skip)]
    pub generated: Vec<(InitialParticle, String)>,
}

impl Default for Dem {
    fn default() -> Self {
        toml::from_str("").expect("every [dem] field has a default")
    }
}

/// An infinite plane wall; particles live on the side `normal` points to.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Plane {
    pub point: [f64; 3],
    pub normal: [f64; 3],
    pub material: Option<String>,
}

/// An axis-aligned box: a container (`inside = true`, particles inside) or a solid obstacle.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxWall {
    pub min: [f64; 3],
    pub max: [f64; 3],
    #[serde(default = "yes")]
    pub inside: bool,
    pub material: Option<String>,
}

/// What `dem-client run` writes besides particles.csv and energy.csv, and a coupled
/// `lbm-server run` besides particles.csv.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DemOutput {
    /// VTK polydata (particles_NNNNNN.vtp and particles.pvd) every `output.interval` steps (at
    /// the steps of particles.csv): velocity, angular velocity and, by dem-client alone, the
    /// contact force and torque, in a coupled run the fluid's force and torque.
    #[serde(default = "yes")]
    pub vtk: bool,
}

impl Default for DemOutput {
    fn default() -> Self {
        Self { vtk: true }
    }
}

fn default_dt_divisor() -> f64 {
    50.0
}
fn default_seed() -> u64 {
    1
}
fn yes() -> bool {
    true
}

impl Dem {
    /// Do the domain faces act as walls?
    pub fn uses_domain_walls(&self) -> bool {
        self.domain_walls
            .unwrap_or(self.plane.is_empty() && self.boxes.is_empty())
    }

    /// Checks the `[dem]` fields and reads the CSV files; fills [`Dem::generated`].
    pub fn load(&mut self, file: &str) -> Result<(), SceneError> {
        self.validate_settings(file)?;
        self.validate_materials(file)?;
        self.validate_contact(file)?;
        self.validate_walls(file)?;
        let mut generated = Vec::new();
        for (i, ins) in self.insert.iter().enumerate() {
            validate_insert(file, i, ins)?;
            let material = self.material_name(ins.material.as_deref());
            generated.extend(lattice(ins).into_iter().map(|p| (p, material.clone())));
        }
        for (i, csv) in self.csv.iter().enumerate() {
            let material = self.material_name(csv.material.as_deref());
            let spheres = read_csv(file, i, &csv.file)?;
            generated.extend(spheres.into_iter().map(|p| (p, material.clone())));
        }
        self.generated = generated;
        Ok(())
    }

    fn validate_settings(&self, file: &str) -> Result<(), SceneError> {
        if let Some(dt) = self.dt {
            positive(file, "dem.dt", dt, "s")?;
        }
        positive(file, "dem.dt_divisor", self.dt_divisor, "")?;
        if self.dt_divisor < 10.0 {
            return Err(fail(
                file,
                "dem.dt_divisor",
                self.dt_divisor,
                "must be at least 10 (a contact needs at least 10 steps)",
            ));
        }
        if let Some(skin) = self.skin {
            positive(file, "dem.skin", skin, "m")?;
        }
        Ok(())
    }

    fn validate_walls(&self, file: &str) -> Result<(), SceneError> {
        for (i, p) in self.plane.iter().enumerate() {
            finite3(file, &format!("dem.plane[{i}].point"), p.point, "m")?;
            let n = p.normal;
            if !n.iter().all(|x| x.is_finite()) || n.iter().map(|x| x * x).sum::<f64>() == 0.0 {
                return Err(fail(
                    file,
                    format!("dem.plane[{i}].normal"),
                    vec3(n),
                    "must be a finite, non-zero vector",
                ));
            }
        }
        for (i, b) in self.boxes.iter().enumerate() {
            finite3(file, &format!("dem.box[{i}].min"), b.min, "m")?;
            finite3(file, &format!("dem.box[{i}].max"), b.max, "m")?;
            if let Some(a) = (0..3).find(|&a| b.max[a] <= b.min[a]) {
                return Err(fail(
                    file,
                    format!("dem.box[{i}].max[{a}]"),
                    format!("{} m", b.max[a]),
                    format!("must be greater than min[{a}] = {} m", b.min[a]),
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::Scene;

    const BASE: &str = r#"name = "t"
[domain]
min = [0.0, 0.0, 0.0]
max = [0.1, 0.1, 0.1]
[fluid]
density = 1.2
dynamic_viscosity = 1.8e-5
[time]
dt = 1.0e-4
steps = 10
[particles]
density = 2500.0
"#;

    fn parse(extra: &str) -> Result<Scene, String> {
        Scene::parse(&format!("{BASE}{extra}"), "s.toml").map_err(|e| e.to_string())
    }

    #[test]
    fn a_scene_without_dem_section_gets_the_defaults() {
        let s = parse("[[particles.sphere]]\nposition = [0.05, 0.05, 0.05]\nradius = 0.001\n").unwrap();
        assert_eq!(s.dem.dt_divisor, 50.0);
        assert!(s.dem.uses_domain_walls());
        assert_eq!(s.dem.materials()[0].young_modulus, 5.0e6);
        assert!(s.dem.output.vtk);
    }

    #[test]
    fn lattice_with_jitter_is_reproducible_and_polydisperse() {
        let extra = "[[dem.insert]]\norigin = [0.01, 0.01, 0.01]\ncount = [4, 4, 4]\nspacing = 0.01\nradius = [0.002, 0.004]\njitter = 0.001\n";
        let a = parse(extra).unwrap();
        let b = parse(extra).unwrap();
        assert_eq!(a.particle_count(), 64);
        assert_eq!(a.initial_particles(), b.initial_particles());
        let radii: Vec<f64> = a.initial_particles().iter().map(|p| p.radius).collect();
        assert!(radii.iter().any(|r| *r > 0.003) && radii.iter().any(|r| *r < 0.003));
    }

    #[test]
    fn bad_dem_fields_are_named() {
        let e = parse("[[dem.insert]]\norigin = [0.01, 0.01, 0.01]\ncount = [2, 1, 1]\nspacing = 0.01\nradius = -0.001\n")
            .unwrap_err();
        assert_eq!(
            e,
            "s.toml: dem.insert[0].radius = -0.001 m: must be a finite number > 0"
        );
        let e = parse("[dem]\ndt = 0.0\n").unwrap_err();
        assert!(e.starts_with("s.toml: dem.dt = 0 s:"), "{e}");
        let e = parse("[[dem.material]]\nname = \"a\"\nrestitution = 1.5\n").unwrap_err();
        assert!(e.starts_with("s.toml: dem.material[0].restitution = 1.5:"), "{e}");
        let e = parse("[dem.contact]\nnormal = \"linear\"\n").unwrap_err();
        assert!(e.contains("dem.contact.normal"), "{e}");
        let e = parse("[dem]\nparticle_material = \"steel\"\n").unwrap_err();
        assert!(e.contains("no such material"), "{e}");
    }

    #[test]
    fn every_field_that_names_a_material_is_checked_against_the_materials() {
        let materials = "[[particles.sphere]]\nposition = [0.05, 0.05, 0.05]\nradius = 0.001\n\
                         [[dem.material]]\nname = \"sand\"\n[[dem.material]]\nname = \"smooth\"\nfriction = 0.0\n";
        let plane = |m: &str| {
            format!("[[dem.plane]]\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\nmaterial = \"{m}\"\n")
        };
        let ok = parse(&format!("{materials}{}", plane("smooth")));
        assert!(ok.is_ok(), "{ok:?}");
        let e = parse(&format!("{materials}{}{}", plane("smooth"), plane("smoth"))).unwrap_err();
        assert_eq!(
            e,
            "s.toml: dem.plane[1].material = \"smoth\": no such material (known: sand, smooth)"
        );
        let boxed = "[[dem.box]]\nmin = [0.0, 0.0, 0.0]\nmax = [0.1, 0.1, 0.1]\nmaterial = \"x\"\n";
        let e = parse(&format!("{materials}{boxed}")).unwrap_err();
        assert!(
            e.starts_with("s.toml: dem.box[0].material = \"x\": no such material"),
            "{e}"
        );
        let e = parse(&format!("{materials}[dem]\ndomain_wall_material = \"glass\"\n")).unwrap_err();
        assert!(
            e.starts_with("s.toml: dem.domain_wall_material = \"glass\":"),
            "{e}"
        );
        let e = parse("[[dem.material]]\nname = \"sand\"\n[[dem.material]]\nname = \"sand\"\n").unwrap_err();
        assert_eq!(
            e,
            "s.toml: dem.material[1].name = \"sand\": must be non-empty and unique"
        );
        let e = parse(&format!(
            "{materials}[[dem.material]]\nname = \"r\"\nrolling_friction = -0.1\n"
        ))
        .unwrap_err();
        assert!(
            e.starts_with("s.toml: dem.material[2].rolling_friction = -0.1:"),
            "{e}"
        );
    }

    #[test]
    fn sphere_in_a_wall_is_refused() {
        let e = parse(
            "[[particles.sphere]]\nposition = [0.05, 0.05, 0.0105]\nradius = 0.001\n[[dem.plane]]\npoint = [0.0, 0.0, 0.01]\nnormal = [0.0, 0.0, 1.0]\n",
        )
        .unwrap_err();
        assert!(e.contains("particles (id 0) against dem.plane[0]"), "{e}");
        assert!(e.contains("overlaps the wall"), "{e}");
    }

    #[test]
    fn csv_insertion_reads_columns() {
        let dir = std::env::temp_dir().join(format!("scene-dem-csv-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(
            dir.join("p.csv"),
            "x,y,z,r,vz\n0.05,0.05,0.05,0.002,-1.0\n0.02,0.02,0.02,0.003,0\n",
        )
        .unwrap();
        let text = format!("{BASE}[[dem.csv]]\nfile = \"p.csv\"\n");
        let path = dir.join("s.toml");
        std::fs::write(&path, text).unwrap();
        let s = Scene::load(&path).unwrap();
        let p = s.initial_particles();
        assert_eq!(p.len(), 2);
        assert_eq!(p[0].velocity, [0.0, 0.0, -1.0]);
        assert_eq!(p[1].radius, 0.003);
        std::fs::write(dir.join("p.csv"), "x,y,z,r\n0.05,0.05,0.05,0\n").unwrap();
        let e = Scene::load(&path).unwrap_err().to_string();
        assert!(e.contains("dem.csv[0].file line 2 column r = 0 m"), "{e}");
    }
}
