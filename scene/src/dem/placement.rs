//! Where a scene's DEM particles start: inside the domain, no sphere deep in a wall.

use super::BoxWall;
use crate::numbers::{fail, vec3};
use crate::{InitialParticle, Scene, SceneError};

/// Largest allowed initial overlap of a sphere with a wall, as a fraction of its radius.
pub const MAX_INITIAL_WALL_OVERLAP: f64 = crate::MAX_INITIAL_OVERLAP;

/// After the scene's own checks: generated particles inside the domain, no sphere deep in a wall.
pub fn validate_placement(scene: &Scene, file: &str) -> Result<(), SceneError> {
    let base = scene.particle_count() as usize - scene.dem.generated.len();
    let particles = scene.initial_particles();
    let periodic = scene.periodic_axes();
    for p in &particles[base..] {
        let (lo, hi) = (scene.domain.min, scene.domain.max);
        // Along a periodic axis the centre must lie in the domain, the body may cross the faces.
        let r = |a: usize| if periodic[a] { 0.0 } else { p.radius };
        if let Some(a) = (0..3).find(|&a| p.position[a] - r(a) < lo[a] || p.position[a] + r(a) > hi[a]) {
            return Err(fail(
                file,
                format!("dem particle id {}", p.id),
                format!("{} m", vec3(p.position)),
                format!(
                    "a sphere of radius {} m there leaves the domain [{}, {}] m along axis {a}",
                    p.radius, lo[a], hi[a]
                ),
            ));
        }
    }
    for p in &particles {
        for (field, depth) in wall_overlaps(scene, p) {
            if depth > MAX_INITIAL_WALL_OVERLAP * p.radius {
                return Err(fail(
                    file,
                    format!("particles (id {}) against {field}", p.id),
                    format!("overlap {depth:.3e} m"),
                    format!(
                        "the sphere overlaps the wall by more than {}% of its radius at the start",
                        MAX_INITIAL_WALL_OVERLAP * 100.0
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// A warning for each `dem.box` wholly outside the domain, which no particle can reach.
pub(crate) fn idle_boxes(scene: &Scene, file: &str) -> Vec<String> {
    let (lo, hi) = (scene.domain.min, scene.domain.max);
    let outside = |b: &BoxWall| (0..3).any(|a| b.max[a] <= lo[a] || b.min[a] >= hi[a]);
    let boxes = scene.dem.boxes.iter().enumerate().filter(|(_, b)| outside(b));
    boxes
        .map(|(i, b)| {
            let problem = format!(
                "lies wholly outside the domain (min {} m, max {} m): no particle can touch it",
                vec3(lo),
                vec3(hi)
            );
            let value = format!("min {} m, max {} m", vec3(b.min), vec3(b.max));
            fail(file, format!("dem.box[{i}]"), value, problem).to_string()
        })
        .collect()
}

/// (wall field, overlap depth [m]) of one sphere with each wall of the scene.
fn wall_overlaps(scene: &Scene, p: &InitialParticle) -> Vec<(String, f64)> {
    let x = p.position;
    let mut out = Vec::new();
    for (i, w) in scene.dem.plane.iter().enumerate() {
        let len = w.normal.iter().map(|v| v * v).sum::<f64>().sqrt();
        let dist: f64 = (0..3).map(|a| (x[a] - w.point[a]) * w.normal[a] / len).sum();
        out.push((format!("dem.plane[{i}]"), p.radius - dist));
    }
    for (i, b) in scene.dem.boxes.iter().enumerate() {
        let depth = if b.inside {
            (0..3)
                .map(|a| p.radius - (x[a] - b.min[a]).min(b.max[a] - x[a]))
                .fold(f64::MIN, f64::max)
        } else {
            let d2: f64 = (0..3)
                .map(|a| (x[a] - x[a].clamp(b.min[a], b.max[a])).powi(2))
                .sum();
            p.radius - d2.sqrt()
        };
        out.push((format!("dem.box[{i}]"), depth));
    }
    out
}
