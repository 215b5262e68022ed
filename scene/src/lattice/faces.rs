//! The faces of the lattice: each face's boundary in lattice units, and the checks of its
//! numbers (a finite velocity below the operator's Mach limit, a finite pressure above -rho c_s^2)
//! and of the periodic pairs.

use super::{mach_limit, CollisionOperator, FaceSpec, FaceTable, LatticeFace, LatticeSection};
use crate::numbers::{fail, finite3};
use crate::{Scene, SceneError};

pub(super) fn lattice_faces(
    scene: &Scene,
    lattice: &LatticeSection,
    operator: CollisionOperator,
    [dx, dt]: [f64; 2],
    file: &str,
) -> Result<[LatticeFace; 6], SceneError> {
    let mut out = [LatticeFace::Wall; 6];
    for (k, (name, spec)) in lattice.faces.all().into_iter().enumerate() {
        out[k] = lattice_face(scene, spec, [dx, dt], &format!("lattice.faces.{name}"), file)?;
    }
    check_face_speeds(lattice, operator, &out, [dx, dt], file)?;
    check_periodic_pairs(&out, file)?;
    Ok(out)
}

/// The face that `spec` (the scene's field `field`) describes, in lattice units of cell size and
/// time step `[dx, dt]`.
fn lattice_face(
    scene: &Scene,
    spec: &FaceSpec,
    [dx, dt]: [f64; 2],
    field: &str,
    file: &str,
) -> Result<LatticeFace, SceneError> {
    let to_lattice = |u: [f64; 3]| u.map(|v| v * dt / dx);
    if let FaceSpec::Table(t) = spec {
        check_face_numbers(scene, t, [dx, dt], field, file)?;
    }
    Ok(match spec {
        FaceSpec::Name(s) if s == "periodic" => LatticeFace::Periodic,
        FaceSpec::Name(s) if s == "wall" => LatticeFace::Wall,
        FaceSpec::Table(t) => match (t.kind.as_str(), t.velocity, t.pressure) {
            ("moving_wall", Some(u), None) => LatticeFace::MovingWall(to_lattice(u)),
            ("velocity_inlet", Some(u), None) => LatticeFace::VelocityInlet(to_lattice(u)),
            ("pressure_outlet", None, Some(p)) => {
                LatticeFace::PressureOutlet(outlet_density(scene, p, [dx, dt]))
            }
            (kind, ..) => {
                return Err(fail(
                    file,
                    field,
                    format!("{t:?}"),
                    format!(
                        "type {kind:?} needs: moving_wall or velocity_inlet with velocity, \
                         pressure_outlet with pressure"
                    ),
                ))
            }
        },
        FaceSpec::Name(s) => {
            return Err(fail(
                file,
                field,
                format!("{s:?}"),
                "expected \"periodic\", \"wall\" or a table",
            ))
        }
    })
}

/// The lattice density of a pressure outlet at gauge pressure `p` [Pa]:
/// rho_lattice = 1 + p / (rho c_s^2), c_s^2 = dx^2 / (3 dt^2).
fn outlet_density(scene: &Scene, p: f64, [dx, dt]: [f64; 2]) -> f64 {
    1.0 + 3.0 * p * dt * dt / (scene.fluid.density * dx * dx)
}

/// A face table's velocity finite, its pressure finite and above -rho c_s^2 (a density of 0).
fn check_face_numbers(
    scene: &Scene,
    t: &FaceTable,
    [dx, dt]: [f64; 2],
    field: &str,
    file: &str,
) -> Result<(), SceneError> {
    if let Some(u) = t.velocity {
        finite3(file, &format!("{field}.velocity"), u, "m/s")?;
    }
    let Some(p) = t.pressure else {
        return Ok(());
    };
    let field = format!("{field}.pressure");
    if !p.is_finite() {
        return Err(fail(file, &field, format!("{p} Pa"), "must be a finite number"));
    }
    if outlet_density(scene, p, [dx, dt]) <= 0.0 {
        let least = -scene.fluid.density * dx * dx / (3.0 * dt * dt);
        return Err(fail(
            file,
            &field,
            format!("{p} Pa"),
            format!("must be above -rho c_s^2 = {least:e} Pa (the outlet's density would be 0 or less)"),
        ));
    }
    Ok(())
}

/// Refuses a moving wall or inlet faster than the operator's lattice Mach limit.
fn check_face_speeds(
    lattice: &LatticeSection,
    operator: CollisionOperator,
    faces: &[LatticeFace; 6],
    [dx, dt]: [f64; 2],
    file: &str,
) -> Result<(), SceneError> {
    let limit = mach_limit(operator);
    for (k, (name, _)) in lattice.faces.all().into_iter().enumerate() {
        if let LatticeFace::MovingWall(u) | LatticeFace::VelocityInlet(u) = faces[k] {
            let mach = u.iter().map(|v| v * v).sum::<f64>().sqrt() * 3f64.sqrt();
            if mach > limit {
                let si = u.map(|v| v * dx / dt);
                return Err(fail(
                    file,
                    format!("lattice.faces.{name}.velocity"),
                    format!("[{}, {}, {}] m/s", si[0], si[1], si[2]),
                    format!("is lattice Mach {mach:.3}, above {limit} for {operator}"),
                ));
            }
        }
    }
    Ok(())
}

/// Refuses an axis with one periodic face: periodic faces come in pairs.
fn check_periodic_pairs(faces: &[LatticeFace; 6], file: &str) -> Result<(), SceneError> {
    for (a, axis) in ["x", "y", "z"].iter().enumerate() {
        let (lo, hi) = (
            faces[2 * a] == LatticeFace::Periodic,
            faces[2 * a + 1] == LatticeFace::Periodic,
        );
        if lo != hi {
            return Err(fail(
                file,
                format!("lattice.faces.{axis}_min / {axis}_max"),
                "one periodic",
                "periodic faces come in pairs",
            ));
        }
    }
    Ok(())
}
