//! The checks of a scene's numbers, shared by every section's checks: each refusal names the
//! file, the field and the value (`FILE: FIELD = VALUE: PROBLEM`). Every number of the scene
//! format passes one of them or a range check of its own before anything runs
//! (`every_field.rs` tests that none escapes).

use crate::SceneError;

/// A refusal of `value` in `field` of `file`.
pub(crate) fn fail(
    file: &str,
    field: impl Into<String>,
    value: impl ToString,
    problem: impl Into<String>,
) -> SceneError {
    SceneError {
        file: file.to_string(),
        field: field.into(),
        value: value.to_string(),
        problem: problem.into(),
    }
}

/// A vector as messages show it: `[1, 0, NaN]`.
pub(crate) fn vec3(v: [f64; 3]) -> String {
    format!("[{}, {}, {}]", v[0], v[1], v[2])
}

/// `v` [`unit`] must be finite and above 0.
pub(crate) fn positive(file: &str, field: &str, v: f64, unit: &str) -> Result<(), SceneError> {
    let ok = v.is_finite() && v > 0.0;
    number(file, field, v, unit, ok, "must be a finite number > 0")
}

/// `v` [`unit`] must be finite and at least 0.
pub(crate) fn non_negative(file: &str, field: &str, v: f64, unit: &str) -> Result<(), SceneError> {
    let ok = v.is_finite() && v >= 0.0;
    number(file, field, v, unit, ok, "must be a finite number >= 0")
}

/// Refuses `v` [`unit`] with `problem` unless it is `ok`.
fn number(file: &str, field: &str, v: f64, unit: &str, ok: bool, problem: &str) -> Result<(), SceneError> {
    if ok {
        return Ok(());
    }
    Err(fail(file, field, format!("{v} {unit}").trim_end(), problem))
}

/// Every component of `v` [`unit`] must be finite.
pub(crate) fn finite3(file: &str, field: &str, v: [f64; 3], unit: &str) -> Result<(), SceneError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(fail(
            file,
            field,
            format!("{} {unit}", vec3(v)),
            "every component must be finite",
        ))
    }
}
