//! Insertion of the `[dem]` section: `[[dem.insert]]` lattices with jitter and `[[dem.csv]]`
//! files, their checks, and the reproducible random source of the jitter.

use super::default_seed;
use crate::numbers::{fail, finite3, non_negative, positive};
use crate::{InitialParticle, SceneError};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// Spheres on a simple cubic lattice, each moved by a random offset of at most `jitter` per axis,
/// radii uniform in `radius` = [min, max] (or one value).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Insert {
    pub origin: [f64; 3],
    pub count: [u64; 3],
    pub spacing: f64,
    pub radius: Radius,
    #[serde(default)]
    pub jitter: f64,
    #[serde(default)]
    pub velocity: [f64; 3],
    #[serde(default = "default_seed")]
    pub seed: u64,
    pub material: Option<String>,
}

/// One radius or a range [min, max].
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(untagged)]
pub enum Radius {
    One(f64),
    Range([f64; 2]),
}

impl Radius {
    pub fn bounds(self) -> [f64; 2] {
        match self {
            Radius::One(r) => [r, r],
            Radius::Range(b) => b,
        }
    }
}

/// Particles from a CSV file with a header naming at least `x,y,z,r` (or `radius`); optional
/// `vx,vy,vz,wx,wy,wz`. A relative path is taken from the scene file's folder, else the working
/// folder.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CsvInsert {
    pub file: PathBuf,
    pub material: Option<String>,
}

pub(super) fn validate_insert(file: &str, i: usize, ins: &Insert) -> Result<(), SceneError> {
    let field = |f: &str| format!("dem.insert[{i}].{f}");
    finite3(file, &field("origin"), ins.origin, "m")?;
    finite3(file, &field("velocity"), ins.velocity, "m/s")?;
    let product = ins.count.iter().try_fold(1u64, |acc, n| acc.checked_mul(*n));
    if ins.count.contains(&0) || product.is_none_or(|n| n > crate::MAX_PARTICLES) {
        let value = format!("[{}, {}, {}]", ins.count[0], ins.count[1], ins.count[2]);
        return Err(fail(
            file,
            field("count"),
            value,
            format!(
                "every count must be at least 1, at most {} particles",
                crate::MAX_PARTICLES
            ),
        ));
    }
    positive(file, &field("spacing"), ins.spacing, "m")?;
    let [lo, hi] = ins.radius.bounds();
    positive(file, &field("radius"), lo, "m")?;
    positive(file, &field("radius"), hi, "m")?;
    if hi < lo {
        return Err(fail(
            file,
            field("radius"),
            format!("[{lo}, {hi}] m"),
            "min must not exceed max",
        ));
    }
    non_negative(file, &field("jitter"), ins.jitter, "m")?;
    let gap = ins.spacing - 2.0 * hi;
    if ins.count.iter().any(|n| *n > 1) && 2.0 * ins.jitter > gap.max(0.0) + 1e-15 {
        return Err(fail(
            file,
            field("jitter"),
            format!("{} m", ins.jitter),
            format!(
                "spheres of radius up to {hi} m at spacing {} m may overlap: jitter must be at most (spacing - 2 r_max) / 2 = {} m",
                ins.spacing,
                gap.max(0.0) / 2.0
            ),
        ));
    }
    Ok(())
}

/// SplitMix64: a small, reproducible random source for jitter and radii.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The spheres of one lattice insertion (ids 0..; renumbered by the scene).
pub(super) fn lattice(ins: &Insert) -> Vec<InitialParticle> {
    let mut rng = SplitMix(ins.seed);
    let [lo, hi] = ins.radius.bounds();
    let [nx, ny, nz] = ins.count;
    let mut out = Vec::with_capacity((nx * ny * nz) as usize);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let ijk = [i, j, k];
                let position = std::array::from_fn(|a| {
                    ins.origin[a] + ijk[a] as f64 * ins.spacing + ins.jitter * (2.0 * rng.unit() - 1.0)
                });
                let radius = lo + (hi - lo) * rng.unit();
                out.push(InitialParticle {
                    id: 0,
                    position,
                    velocity: ins.velocity,
                    angular_velocity: [0.0; 3],
                    radius,
                });
            }
        }
    }
    out
}

/// Where a CSV path points: absolute as is; relative, next to the scene file, else the working folder.
fn resolve(scene_file: &str, path: &Path) -> PathBuf {
    if path.is_absolute() {
        return path.to_path_buf();
    }
    let beside = Path::new(scene_file).parent().map(|d| d.join(path));
    match beside {
        Some(p) if p.is_file() => p,
        _ => path.to_path_buf(),
    }
}

/// The particles of the scene `file`'s `[[dem.csv]]` number `i`, read from `path` (beside the scene
/// where it is found there): one a line under a header naming its columns.
pub(super) fn read_csv(file: &str, i: usize, path: &Path) -> Result<Vec<InitialParticle>, SceneError> {
    let field = format!("dem.csv[{i}].file");
    let resolved = resolve(file, path);
    let shown = format!("{:?}", path.display().to_string());
    let text = std::fs::read_to_string(&resolved).map_err(|e| {
        fail(
            file,
            &field,
            &shown,
            format!("cannot read {}: {e}", resolved.display()),
        )
    })?;
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty() && !l.starts_with('#'));
    let columns = match lines.next() {
        Some((_, h)) => CsvColumns::of(h).ok_or_else(|| {
            fail(
                file,
                &field,
                &shown,
                "the header must name the columns x, y, z and r (or radius)",
            )
        })?,
        None => return Err(fail(file, &field, &shown, "is empty (needs a header x,y,z,r)")),
    };
    lines
        .map(|(row, line)| columns.particle(line, row, file, &field))
        .collect()
}

/// The columns of a particle file, from its header: the required x, y, z and r (or radius), and
/// the optional velocity and angular velocity (0 where absent).
struct CsvColumns {
    /// The header's names, lower case.
    names: Vec<String>,
    x: usize,
    y: usize,
    z: usize,
    r: usize,
    /// vx, vy, vz, wx, wy, wz.
    optional: [Option<usize>; 6],
}

impl CsvColumns {
    /// The columns the header line `header` names; None where one of x, y, z and r is missing.
    fn of(header: &str) -> Option<CsvColumns> {
        let names: Vec<String> = header.split(',').map(|c| c.trim().to_ascii_lowercase()).collect();
        let col = |wanted: &[&str]| names.iter().position(|h| wanted.contains(&h.as_str()));
        let (x, y, z, r) = (col(&["x"])?, col(&["y"])?, col(&["z"])?, col(&["r", "radius"])?);
        let optional = ["vx", "vy", "vz", "wx", "wy", "wz"].map(|n| col(&[n]));
        Some(CsvColumns {
            names,
            x,
            y,
            z,
            r,
            optional,
        })
    }

    /// The particle of the line `line` (the file's line `row`, counted from 0) of the scene `file`'s
    /// particle file `field`.
    fn particle(
        &self,
        line: &str,
        row: usize,
        file: &str,
        field: &str,
    ) -> Result<InitialParticle, SceneError> {
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        let num = |c: Option<usize>| -> Result<f64, SceneError> {
            let Some(c) = c else { return Ok(0.0) };
            let cell = cells.get(c).copied().unwrap_or("");
            cell.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| {
                fail(
                    file,
                    format!("{field} line {} column {}", row + 1, self.names[c]),
                    format!("{cell:?}"),
                    "must be a finite number",
                )
            })
        };
        let radius = num(Some(self.r))?;
        if radius <= 0.0 {
            return Err(fail(
                file,
                format!("{field} line {} column r", row + 1),
                format!("{radius} m"),
                "must be a finite number > 0",
            ));
        }
        let optional = self.optional;
        Ok(InitialParticle {
            id: 0,
            position: [num(Some(self.x))?, num(Some(self.y))?, num(Some(self.z))?],
            velocity: [num(optional[0])?, num(optional[1])?, num(optional[2])?],
            angular_velocity: [num(optional[3])?, num(optional[4])?, num(optional[5])?],
            radius,
        })
    }
}
