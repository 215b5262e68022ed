//! Scene files: TOML in SI units, parsed with serde, validated before anything runs.
//!
//! Every mistake is reported as `FILE: FIELD = VALUE: PROBLEM`, so the user can find and fix it.

pub use coupling::Coupling;
pub use particles::{Block, InitialParticle, Particles, Sphere, MAX_INITIAL_OVERLAP, MAX_PARTICLES};
use serde::Deserialize;
use std::fmt;
use std::path::Path;

/// The default scene, shipped as a file too (`validation/scenes/default.toml`).
pub const DEFAULT_SCENE: &str = include_str!("../../validation/scenes/default.toml");

/// Name given to the built-in scene in messages.
pub const DEFAULT_SCENE_FILE: &str = "<built-in default scene>";

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Short name, used for output folders (letters, digits, `-`, `_`, `.`).
    pub name: String,
    pub domain: Domain,
    pub fluid: Fluid,
    /// Gravitational acceleration [m/s^2].
    #[serde(default = "default_gravity")]
    pub gravity: [f64; 3],
    pub time: Time,
    #[serde(default)]
    pub output: Output,
    #[serde(default)]
    pub coupling: Coupling,
    /// The particles (optional for a fluid-only scene with a `[lattice]`).
    #[serde(default)]
    pub particles: Particles,
    /// The lattice-Boltzmann discretisation of the fluid (`[lattice]`, optional).
    #[serde(default)]
    pub lattice: Option<lattice::LatticeSection>,
    /// The lattice in lattice units, derived from `lattice` when the scene is loaded.
    #[serde(skip)]
    pub lattice_units: Option<lattice::LatticeUnits>,
    /// The DEM: materials, contact model, walls, insertion, DEM output (every field has a default).
    #[serde(default)]
    pub dem: dem::Dem,
    /// How `lbm-server` cuts the lattice over MPI ranks (`[parallel]`, optional).
    #[serde(default)]
    pub parallel: parallel::Parallel,
    /// What the checks found odd but harmless (a box that does nothing), each as
    /// `FILE: FIELD = VALUE: PROBLEM`; the program that loaded the scene says them, once per run
    /// (lbm-server for a coupled run, not the dem-client it starts).
    #[serde(skip)]
    pub warnings: Vec<String>,
}

/// The fluid box [m].
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Domain {
    pub min: [f64; 3],
    pub max: [f64; 3],
    /// Axes ("x", "y", "z") along which a granular scene alone (no `[lattice]`) is periodic; with
    /// a lattice its periodic faces decide, and this list, if given, must name the same axes.
    #[serde(default)]
    pub periodic: Vec<String>,
}

impl Domain {
    /// The axes `periodic` names (unknown names are refused by the scene's checks).
    pub fn periodic_axes(&self) -> [bool; 3] {
        std::array::from_fn(|a| self.periodic.iter().any(|name| name == AXES[a]))
    }
}

/// The names of the axes in scene fields.
pub const AXES: [&str; 3] = ["x", "y", "z"];

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fluid {
    /// [kg/m^3]
    pub density: f64,
    /// [Pa s]
    pub dynamic_viscosity: f64,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Time {
    /// Fluid (coupling) time step [s]: `time.dt`, or with a `[lattice]` derived from it.
    #[serde(skip, default = "unset")]
    pub dt: f64,
    /// `time.dt` as given; with a `[lattice]` it must not be.
    #[serde(rename = "dt", default)]
    pub(crate) given_dt: Option<f64>,
    /// Number of coupled steps, as given (`time.steps`).
    #[serde(rename = "steps", default)]
    pub(crate) given_steps: Option<u64>,
    /// Simulated time [s], instead of `steps`: the run takes the whole steps that cover it.
    #[serde(default)]
    pub duration: Option<f64>,
    /// Number of coupled steps: `time.steps`, or those of `time.duration` (times.rs).
    #[serde(skip)]
    pub steps: u64,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Output {
    /// `output.interval` as given.
    #[serde(rename = "interval", default)]
    pub(crate) given_interval: Option<u64>,
    /// Time between two rows [s], instead of `interval`: the nearest whole number of steps.
    #[serde(default)]
    pub time_interval: Option<f64>,
    /// Steps between two rows of particles.csv per particle, and between two rows of the line
    /// probes (the last step is always written): `output.interval` (default 100) or those of
    /// `output.time_interval`.
    #[serde(skip)]
    pub interval: u64,
    /// `output.fields_interval` as given.
    #[serde(rename = "fields_interval", default)]
    pub(crate) given_fields_interval: Option<u64>,
    /// Time between two snapshots [s], instead of `fields_interval`: the nearest whole number
    /// of steps.
    #[serde(default)]
    pub fields_time_interval: Option<f64>,
    /// Steps between two VTK snapshots of the fluid (fields/*.vti + fields.pvd), the last step's
    /// always among them; 0: a fluid run writes the last step's only, a coupled run (particles)
    /// none (its field is large and seldom wanted). `output.fields_interval` (default 0) or those
    /// of `output.fields_time_interval`.
    #[serde(skip)]
    pub fields_interval: u64,
    /// Probe lines through the fluid, written as line<N>.csv.
    #[serde(default)]
    pub line: Vec<ProbeLine>,
    /// `output.checkpoint_interval` as given.
    #[serde(rename = "checkpoint_interval", default)]
    pub(crate) given_checkpoint_interval: Option<u64>,
    /// Simulated time between two checkpoints [s], instead of `checkpoint_interval`: the nearest
    /// whole number of steps.
    #[serde(default)]
    pub checkpoint_time_interval: Option<f64>,
    /// Steps between two checkpoints (OUT/checkpoint/, docs/checkpoint.md); 0: none but the run's
    /// end. `output.checkpoint_interval` (default 0) or those of `output.checkpoint_time_interval`.
    #[serde(skip)]
    pub checkpoint_interval: u64,
    /// Wall-clock minutes between two checkpoints (none where not given), whatever the steps.
    #[serde(default)]
    pub checkpoint_wall_interval: Option<f64>,
}

impl Default for Output {
    fn default() -> Self {
        Self {
            given_interval: None,
            time_interval: None,
            interval: default_interval(),
            given_fields_interval: None,
            fields_time_interval: None,
            fields_interval: 0,
            line: Vec::new(),
            given_checkpoint_interval: None,
            checkpoint_time_interval: None,
            checkpoint_interval: 0,
            checkpoint_wall_interval: None,
        }
    }
}

/// The cells along `axis` ("x", "y" or "z") through the point `through` [m].
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProbeLine {
    pub axis: String,
    pub through: [f64; 3],
}

/// Marks a number the file did not give.
pub(crate) fn unset() -> f64 {
    f64::NAN
}

fn default_gravity() -> [f64; 3] {
    [0.0, 0.0, -9.81]
}
pub(crate) fn default_interval() -> u64 {
    100
}
/// A scene that cannot run: which file, which field, which value, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneError {
    pub file: String,
    pub field: String,
    pub value: String,
    pub problem: String,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.field.is_empty() {
            write!(f, "{}: {}", self.file, self.problem)
        } else {
            write!(
                f,
                "{}: {} = {}: {}",
                self.file, self.field, self.value, self.problem
            )
        }
    }
}

impl std::error::Error for SceneError {}

impl Scene {
    /// Reads and validates a scene file; its warnings are kept in [`Scene::warnings`].
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| SceneError {
            file: file.clone(),
            field: String::new(),
            value: String::new(),
            problem: format!("cannot read the scene file: {e}"),
        })?;
        Scene::parse(&text, &file)
    }

    /// The built-in default scene.
    pub fn default_scene() -> Scene {
        Scene::parse(DEFAULT_SCENE, DEFAULT_SCENE_FILE).expect("the default scene is valid")
    }

    /// Parses and validates scene text; `file` names it in errors and warnings (kept in
    /// [`Scene::warnings`]).
    pub fn parse(text: &str, file: &str) -> Result<Scene, SceneError> {
        let mut scene: Scene = toml::from_str(text).map_err(|e| SceneError {
            file: file.to_string(),
            field: String::new(),
            value: String::new(),
            problem: e.to_string().trim_end().replace('\n', "\n  "),
        })?;
        scene.resolve_lattice(file)?;
        scene.resolve_steps(file)?;
        scene.dem.load(file)?;
        scene.validate(file)?;
        scene.validate_parallel(file)?;
        dem::validate_placement(&scene, file)?;
        scene.warnings.extend(dem::idle_boxes(&scene, file));
        Ok(scene)
    }

    /// Derives the lattice (and with it the time step) when the scene has a `[lattice]`.
    fn resolve_lattice(&mut self, file: &str) -> Result<(), SceneError> {
        let Some(lattice) = &self.lattice else {
            let Some(dt) = self.time.given_dt else {
                return Err(SceneError {
                    file: file.into(),
                    field: "time.dt".into(),
                    value: "missing".into(),
                    problem: "add a [lattice] section, which derives the time step (lbm-server runs the \
                              particles coupled to it), or give time.dt [s] for a granular scene alone \
                              (dem-client run)"
                        .into(),
                });
            };
            self.time.dt = dt;
            return Ok(());
        };
        if let Some(dt) = self.time.given_dt {
            return Err(SceneError {
                file: file.into(),
                field: "time.dt".into(),
                value: format!("{dt} s"),
                problem: "the [lattice] section derives the time step: remove time.dt".into(),
            });
        }
        self.validate_domain(file)?;
        let (units, warnings) = lattice::LatticeUnits::derive(self, lattice, file)?;
        self.time.dt = units.dt;
        self.lattice_units = Some(units);
        self.warnings.extend(warnings);
        Ok(())
    }

    /// The axes (x, y, z) along which the domain is periodic: those whose lattice faces are
    /// periodic, or without a `[lattice]` those `domain.periodic` names. Both physics wrap along
    /// them: the lattice's links and particle covers, the DEM's spheres and pairs.
    pub fn periodic_axes(&self) -> [bool; 3] {
        match self.lattice_units.as_ref().map(|u| u.faces) {
            Some(faces) => std::array::from_fn(|a| faces[2 * a] == lattice::LatticeFace::Periodic),
            None => self.domain.periodic_axes(),
        }
    }

    /// The periodic axes' lower faces and lengths (length 0 along the others).
    pub fn periods(&self) -> overlap::Periods {
        let axes = self.periodic_axes();
        let (min, max) = (self.domain.min, self.domain.max);
        overlap::Periods {
            lo: min,
            len: std::array::from_fn(|a| if axes[a] { max[a] - min[a] } else { 0.0 }),
        }
    }
}

pub mod checkpoint;
mod checks;
pub mod checksum;
mod coupling;
pub mod dem;
#[cfg(test)]
mod every_field;
pub mod lattice;
mod numbers;
pub mod output_lock;
pub mod outputs;
pub mod overlap;
pub mod parallel;
mod particles;
pub mod row_file;
mod times;
pub mod vtp;

#[cfg(test)]
mod shipped_scenes {
    use super::Scene;

    /// Every scene under validation/scenes loads (parsed, derived and validated as `lbm-server run`
    /// and `dem-client run` load it); the suspension is the seed's 32^3 beads on the coupled
    /// sweep's 256 x 256 x 512 grid.
    #[test]
    fn every_shipped_scene_is_valid() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../validation/scenes");
        let mut loaded = Vec::new();
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "toml") {
                let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                loaded.push((scene.name.clone(), scene));
            }
        }
        assert!(loaded.len() >= 6, "{} scenes", loaded.len());
        let (_, suspension) = loaded
            .iter()
            .find(|(n, _)| n == "suspension")
            .expect("suspension.toml");
        assert_eq!(suspension.particle_count(), 32768);
        assert_eq!(suspension.lattice_units.as_ref().unwrap().n, [256, 256, 512]);
        assert!(suspension.coupling.free_flight);
    }
}
