//! `lbm-server validate --only bed-drag`: whether the immersed boundary's drag in a bed at the
//! fluidized bed's Reynolds numbers converges with the grid, and how far 6 cells per diameter
//! (validation/scenes/fluidized-bed.toml, which expands 30% more than Richardson & Zaki) is off.

use crate::lbm::gpu::Gpu;
use crate::lbm::validation::{self, schiller_naumann, WeightedArray};
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::sync::Arc;

/// The fluidized bed's grain: Archimedes number g d^3 (rho_p / rho_f - 1) / nu^2 of a 3 mm sand
/// grain (density ratio 2.65) in liquid of nu = 1.48e-6 m^2/s.
fn archimedes() -> f64 {
    9.81 * 0.003f64.powi(3) * (2.65 - 1.0) / 1.48e-6f64.powi(2)
}

/// Solid fractions: the 6-cell bed's (voidage 0.76 at Re 200). Richardson & Zaki's at Re 200
/// (voidage 0.585, 0.415) leaves 0.6 cells between neighbours at 8 cells a side, where the
/// sphere's box of cells would meet itself across the periodic box (a box of 2 x 2 x 2 spheres
/// would do; not built).
pub(super) const SOLID_FRACTIONS: [f64; 1] = [0.24];
/// Sphere diameters aimed at (cells); the box side is the nearest whole number that gives the
/// solid fraction (at least [`MIN_BOX`]), so the diameter run is near these.
pub(super) const DIAMETERS: [f64; 5] = [6.0, 9.0, 12.0, 18.0, 24.0];
/// The smallest box side: a sphere's box of cells must not meet itself across the periodic box.
const MIN_BOX: usize = 8;
/// The superficial velocity aimed at (lattice units): the bed scene's, Mach 0.1 at 1.52 U.
const VELOCITY: f64 = 0.038;
/// Steps a run may take at most.
const MAX_STEPS: u64 = 60_000;

/// Reynolds number U d / nu at which one grain settles alone (Schiller & Naumann's drag):
/// C_d Re^2 = 4 Ar / 3.
fn settling_reynolds(ar: f64) -> f64 {
    let (mut low, mut high) = (1e-3f64, 1e5f64);
    for _ in 0..200 {
        let mid = (low * high).sqrt();
        if schiller_naumann(mid) * mid * mid < 4.0 * ar / 3.0 {
            low = mid;
        } else {
            high = mid;
        }
    }
    low
}

/// Richardson & Zaki's (1954) superficial Reynolds number of a bed at voidage eps: Re_t eps^n,
/// n from Rowe (1987).
fn richardson_zaki(ar: f64, voidage: f64) -> f64 {
    let re_t = settling_reynolds(ar);
    let n = (4.7 + 0.41 * re_t.powf(0.75)) / (1.0 + 0.175 * re_t.powf(0.75));
    re_t * voidage.powf(n)
}

/// One row: the array of this solid fraction at about this diameter.
fn run(gpu: &Arc<Gpu>, phi: f64, diameter: f64, expected: f64) -> WeightedArray {
    let n = ((diameter / (6.0 * phi / PI).cbrt()).round() as usize).max(MIN_BOX);
    let d = n as f64 * (6.0 * phi / PI).cbrt();
    let nu = VELOCITY * d / expected;
    let weight = archimedes() * PI / 6.0;
    let mrt = super::operator_named("MRT", 0.5 + 3.0 * nu);
    validation::array_at_weight(gpu, n, phi, [nu, weight], mrt, VELOCITY, MAX_STEPS)
}

pub(super) fn section(gpu: &Arc<Gpu>) -> String {
    let ar = archimedes();
    let mut t = format!(
        "\n## Immersed moving boundary: drag in a bed at the fluidized bed's Reynolds numbers, by resolution\n\n\
         The fluidized bed of validation/imb/FLUIDIZED_BED.md (6 cells per diameter, MRT, tau 0.5034) \
         expands 30% more than Richardson & Zaki at Re 200: too much drag, or a bed unlike theirs? Here \
         a simple cubic array (one sphere in a periodic box) carries the bed's weight: the mean \
         pressure gradient on each unit cell equals a grain's buoyant weight, F / (rho nu^2) = Ar pi / 6 \
         with the bed's Archimedes number Ar = {ar:.3e} (3 mm sand in water), and the superficial \
         Reynolds number Re = U d / nu at which the array's drag carries it is measured at each \
         resolution. More drag, lower Re. MRT (d'Humieres' rates), Noble-Torczynski weighting, nu set \
         so that U is near {VELOCITY} (the bed scene's: Mach 0.1 at 1.52 U), so tau nears 1/2 on coarse \
         grids as in the bed. The fluid starts at U everywhere; a run stops when {} fluxes {} steps \
         apart agree to 1e-3 (\"steady\"), else after {MAX_STEPS} steps (mean and range of the last \
         {}). A simple cubic array is not a random bed (ordered arrays drag less at the same \
         voidage), so Richardson & Zaki's Re (n = 2.39, Re_t = {:.0}) is context; the finest grid is \
         the reference for the grid error.\n\n\
         | solid fraction | box n | d (cells) | tau | steps | outcome | Re mean | Re range | F / (3 pi mu d U) | grid error of Re vs finest | Richardson-Zaki Re |\n\
         |---:|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|\n",
        validation::WEIGHT_SAMPLES,
        validation::WEIGHT_CHECK,
        validation::WEIGHT_SAMPLES,
        settling_reynolds(ar),
    );
    for phi in SOLID_FRACTIONS {
        let expected = richardson_zaki(ar, 1.0 - phi);
        let runs: Vec<WeightedArray> = DIAMETERS
            .iter()
            .map(|&d| {
                let r = run(gpu, phi, d, expected);
                protocol::say!("lbm-server: bed-drag: phi {phi} {r:?}");
                r
            })
            .collect();
        let finest = runs.last().map_or(f64::NAN, |r| r.reynolds[0]);
        for r in &runs {
            let [mean, low, high] = r.reynolds;
            let outcome = match (&r.unhealthy, r.steps < MAX_STEPS) {
                (Some(bad), _) => format!(
                    "blew up at ({}, {}, {})",
                    bad.coords[0], bad.coords[1], bad.coords[2]
                ),
                (None, true) => "steady".into(),
                (None, false) => "not steady".into(),
            };
            let numbers = if r.unhealthy.is_some() {
                " | | | ".to_string()
            } else {
                format!(
                    "{mean:.1} | {low:.1}-{high:.1} | {:.2} | {:+.1}%",
                    ar * PI / 6.0 / (3.0 * PI * mean),
                    100.0 * (mean / finest - 1.0)
                )
            };
            let _ = writeln!(
                t,
                "| {phi} | {} | {:.2} | {:.4} | {} | {outcome} | {numbers} | {expected:.0} |",
                r.cells, r.diameter, r.tau, r.steps
            );
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::super::report_section;
    use super::{archimedes, richardson_zaki, settling_reynolds, DIAMETERS, SOLID_FRACTIONS};

    /// The report's section holds one row per solid fraction and diameter, in that order.
    #[test]
    fn the_bed_drag_section_holds_the_runs() {
        let section = report_section("## Immersed moving boundary: drag in a bed");
        let rows: Vec<&str> = section
            .lines()
            .filter(|l| l.starts_with("| 0."))
            .map(|l| l.split(" | ").next().unwrap_or(""))
            .collect();
        let runs: Vec<String> = SOLID_FRACTIONS
            .iter()
            .flat_map(|phi| DIAMETERS.iter().map(move |_| format!("| {phi}")))
            .collect();
        assert_eq!(rows, runs);
    }

    /// The grain and Richardson & Zaki's bed are those of validation/imb/FLUIDIZED_BED.md
    /// (fluidized_bed.py): Ar 2.0e5, Re_t 738, voidage 0.585 at Re 200 and 0.777 at Re 400.
    #[test]
    fn the_bed_is_the_fluidized_bed_reports() {
        let ar = archimedes();
        assert!((ar / 2.0e5 - 1.0).abs() < 0.01, "{ar}");
        let re_t = settling_reynolds(ar);
        assert!((re_t - 738.0).abs() < 1.0, "{re_t}");
        assert!((richardson_zaki(ar, 0.585) - 200.0).abs() < 1.0);
        assert!((richardson_zaki(ar, 0.777) - 400.0).abs() < 2.0);
    }
}
