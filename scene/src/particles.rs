//! The `[particles]` section: explicit spheres and blocks of spheres, and the particles a scene
//! starts with (with those `[dem]` inserts).

use crate::{unset, Scene};
use serde::Deserialize;

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Particles {
    /// Solid density [kg/m^3].
    pub density: f64,
    /// Whether the scene has a `[particles]` section (whose density is checked even where it
    /// creates no particle).
    #[serde(skip, default = "given")]
    pub(crate) given: bool,
    #[serde(default)]
    pub sphere: Vec<Sphere>,
    #[serde(default)]
    pub block: Vec<Block>,
}

/// No `[particles]` section: no particles (a fluid-only scene).
impl Default for Particles {
    fn default() -> Self {
        Self {
            density: unset(),
            given: false,
            sphere: Vec::new(),
            block: Vec::new(),
        }
    }
}

/// One sphere [m, m/s, rad/s].
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sphere {
    pub position: [f64; 3],
    pub radius: f64,
    #[serde(default)]
    pub velocity: [f64; 3],
    #[serde(default)]
    pub angular_velocity: [f64; 3],
}

/// Spheres on a simple cubic lattice: `count` per axis, `spacing` between centres, first centre at
/// `origin` [m, m/s].
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Block {
    pub origin: [f64; 3],
    pub count: [u64; 3],
    pub spacing: f64,
    pub radius: f64,
    #[serde(default)]
    pub velocity: [f64; 3],
}

fn given() -> bool {
    true
}

/// A particle at the start of a run, in SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InitialParticle {
    pub id: u64,
    pub position: [f64; 3],
    pub velocity: [f64; 3],
    pub angular_velocity: [f64; 3],
    pub radius: f64,
}

/// Most particles a scene may create (a block of 1000^3 is a typo, not a scene).
pub const MAX_PARTICLES: u64 = 50_000_000;

/// Largest allowed initial overlap of two spheres, as a fraction of the smaller radius.
pub const MAX_INITIAL_OVERLAP: f64 = 0.01;

impl Scene {
    /// All particles of the scene with ids 0, 1, 2, ... (spheres first, then blocks).
    pub fn initial_particles(&self) -> Vec<InitialParticle> {
        let spheres = self
            .particles
            .sphere
            .iter()
            .map(|s| (s.position, s.velocity, s.angular_velocity, s.radius));
        let blocks = self
            .particles
            .block
            .iter()
            .flat_map(|b| block_centres(b).map(move |p| (p, b.velocity, [0.0; 3], b.radius)));
        let generated = self
            .dem
            .generated
            .iter()
            .map(|(p, _)| (p.position, p.velocity, p.angular_velocity, p.radius));
        spheres
            .chain(blocks)
            .chain(generated)
            .enumerate()
            .map(
                |(i, (position, velocity, angular_velocity, radius))| InitialParticle {
                    id: i as u64,
                    position,
                    velocity,
                    angular_velocity,
                    radius,
                },
            )
            .collect()
    }

    /// Number of particles the scene creates (at most u64::MAX, where the counts a scene gives,
    /// before its checks refuse them, would overflow).
    pub fn particle_count(&self) -> u64 {
        let blocks = self.particles.block.iter().fold(0u64, |sum, b| {
            let count = b.count.iter().fold(1u64, |n, c| n.saturating_mul(*c));
            sum.saturating_add(count)
        });
        (self.particles.sphere.len() as u64)
            .saturating_add(blocks)
            .saturating_add(self.dem.generated.len() as u64)
    }

    /// Most particles a step may carry.
    pub fn capacity(&self) -> u64 {
        self.coupling.capacity.unwrap_or(self.particle_count()).max(1)
    }
}

fn block_centres(b: &Block) -> impl Iterator<Item = [f64; 3]> + '_ {
    let [nx, ny, nz] = b.count;
    (0..nz).flat_map(move |k| {
        (0..ny).flat_map(move |j| {
            (0..nx).map(move |i| {
                [
                    b.origin[0] + i as f64 * b.spacing,
                    b.origin[1] + j as f64 * b.spacing,
                    b.origin[2] + k as f64 * b.spacing,
                ]
            })
        })
    })
}
