//! `lbm-server validate --only bed-drag`: whether the immersed boundary's drag in a bed at the
//! fluidized bed's Reynolds numbers converges with the grid, and how far 6 cells per diameter
//! (validation/scenes/fluidized-bed.toml, which expands 30% more than Richardson & Zaki) is off;
//! `--only random-drag` (and `random-drag-fine`, a GPU's grids): the same with the spheres at
//! random, against Tenneti et al.'s random arrays.

use crate::lbm::cases::{self, schiller_naumann, Array, Spheres, WeightedArray};
use crate::lbm::gpu::Gpu;
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
    reynolds_where(|re| schiller_naumann(re) * re * re, 4.0 * ar / 3.0)
}

/// The Reynolds number in [1e-3, 1e5] at which `rising(Re)`, growing with Re, reaches `target`.
fn reynolds_where(rising: impl Fn(f64) -> f64, target: f64) -> f64 {
    let (mut low, mut high) = (1e-3f64, 1e5f64);
    for _ in 0..200 {
        let mid = (low * high).sqrt();
        if rising(mid) < target {
            low = mid;
        } else {
            high = mid;
        }
    }
    low
}

/// Tenneti, Garg & Subramaniam (2011), particle-resolved simulations of fixed random arrays
/// (solid fraction 0.1-0.5, Re 0.01-300): the mean fluid force on a sphere, the mean pressure
/// gradient's share included, over 3 pi mu d U, at solid fraction phi and Re = U d / nu of the
/// superficial velocity U.
fn tenneti(phi: f64, re: f64) -> f64 {
    let eps = 1.0 - phi;
    let isolated = (1.0 + 0.15 * re.powf(0.687)) / eps.powi(3);
    let packing = 5.81 * phi / eps.powi(3) + 0.48 * phi.cbrt() / eps.powi(4);
    let inertia = phi.powi(3) * re * (0.95 + 0.61 * phi.powi(3) / eps.powi(2));
    isolated + packing + inertia
}

/// Tenneti et al.'s total force on a sphere at Re, in units of rho nu^2.
fn tenneti_force(phi: f64, re: f64) -> f64 {
    3.0 * PI * re * tenneti(phi, re)
}

/// Re at which a random array of solid fraction phi carries a grain of Archimedes number ar
/// (Tenneti et al.'s force 3 pi Re F = Ar pi / 6 in units of rho nu^2).
fn tenneti_reynolds(ar: f64, phi: f64) -> f64 {
    reynolds_where(|re| tenneti_force(phi, re), ar * PI / 6.0)
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
    let array = Array::simple_cubic(n, phi);
    at_weight(gpu, &array, (expected, Spheres::Immersed), MAX_STEPS)
}

/// `array` carrying the bed's grain weight, nu set so that U nears [`VELOCITY`] at Re `expected`,
/// for at most `max_steps`, its spheres meeting the fluid as `boundary` says.
fn at_weight(
    gpu: &Arc<Gpu>,
    array: &Array,
    (expected, boundary): (f64, Spheres),
    max_steps: u64,
) -> WeightedArray {
    let nu = VELOCITY * array.diameter / expected;
    let weight = archimedes() * PI / 6.0;
    let mrt = super::operator_named("MRT", 0.5 + 3.0 * nu);
    cases::array_at_weight(gpu, array, [nu, weight], (mrt, boundary), VELOCITY, max_steps)
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
        cases::WEIGHT_SAMPLES,
        cases::WEIGHT_CHECK,
        cases::WEIGHT_SAMPLES,
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
            let outcome = outcome(r, MAX_STEPS);
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

/// Spheres per random array, the arrays (seeds of their placement) and the diameters aimed at
/// (cells): the box side is the nearest whole number that gives the bed's solid fraction.
pub(super) const RANDOM_COUNT: usize = 32;
pub(super) const RANDOM_SEEDS: [u64; 2] = [1, 2];
pub(super) const RANDOM_DIAMETERS: [f64; 3] = [6.0, 9.0, 12.0];
/// The same on finer grids, for a GPU (`--only random-drag-fine`, validation/gpu/run.sh).
const FINE_DIAMETERS: [f64; 2] = [18.0, 24.0];
/// Steps a random array's run may take at most: its flow does not settle to 1e-3 (the wakes of 32
/// spheres), and the superficial velocity answers the force within about U n^3 / (f n^3) = 430
/// steps at 6 cells, 860 at 12 (growing as d).
const RANDOM_MAX_STEPS: u64 = 15_000;

/// The random arrays in Stokes flow, first: tau (where the boundary's radius deficit is under 0.03
/// cells, the "drag against tau" section), the superficial Reynolds number aimed at, steps at most.
const STOKES_TAU: f64 = 0.7;
const STOKES_RE: f64 = 0.5;
const STOKES_MAX_STEPS: u64 = 40_000;

/// `lbm-server validate --only random-drag`: the bed's grains at its voidage placed at random
/// instead of on a cubic lattice, against Tenneti et al.'s random arrays, in Stokes flow and
/// carrying the bed's weight.
pub(super) fn random_section(gpu: &Arc<Gpu>) -> String {
    random_arrays(gpu, "by resolution", &RANDOM_DIAMETERS, Spheres::Immersed)
}

/// `--only random-drag-staircase`: the same arrays as solid cells (half-way bounce-back on a
/// staircase of each sphere) instead of the immersed boundary: whether the excess drag at the bed's
/// Reynolds numbers is the immersed boundary's or the grid's.
pub(super) fn random_staircase_section(gpu: &Arc<Gpu>) -> String {
    random_arrays(
        gpu,
        "as solid cells (a staircase), by resolution",
        &RANDOM_DIAMETERS,
        Spheres::Staircase,
    )
}

/// `--only random-drag-fine`: the same at 18 and 24 cells per diameter (a GPU's).
pub(super) fn random_fine_section(gpu: &Arc<Gpu>) -> String {
    random_arrays(gpu, "finer grids", &FINE_DIAMETERS, Spheres::Immersed)
}

/// The random arrays' section at these diameters (cells), its heading ending in `grids`.
fn random_arrays(gpu: &Arc<Gpu>, grids: &str, diameters: &[f64], boundary: Spheres) -> String {
    let ar = archimedes();
    let phi = SOLID_FRACTIONS[0];
    let bed = tenneti_reynolds(ar, phi);
    let mut t = random_heading(grids, boundary, phi, [ar, bed]);
    let scale = (RANDOM_COUNT as f64 * PI / (6.0 * phi)).cbrt();
    let arrays = |seed: u64| -> Vec<Array> {
        diameters
            .iter()
            .map(|&d| Array::random((d * scale).round() as usize, RANDOM_COUNT, phi, seed))
            .collect()
    };
    let stokes = |array: &Array| {
        let nu = (STOKES_TAU - 0.5) / 3.0;
        let u = STOKES_RE * nu / array.diameter;
        let mrt = super::operator_named("MRT", STOKES_TAU);
        let force = tenneti_force(phi, STOKES_RE);
        cases::array_at_weight(gpu, array, [nu, force], (mrt, boundary), u, STOKES_MAX_STEPS)
    };
    let weight = |array: &Array| at_weight(gpu, array, (bed, boundary), RANDOM_MAX_STEPS);
    type Flow<'a> = (&'a str, &'a dyn Fn(&Array) -> WeightedArray, f64, u64);
    let flows: [Flow; 2] = [
        ("Stokes", &stokes, STOKES_RE, STOKES_MAX_STEPS),
        ("the bed's weight", &weight, bed, RANDOM_MAX_STEPS),
    ];
    for (flow, run, reference, max_steps) in flows {
        for seed in RANDOM_SEEDS {
            let runs: Vec<WeightedArray> = arrays(seed)
                .iter()
                .map(|array| {
                    let r = run(array);
                    protocol::say!("lbm-server: random-drag: {flow}, seed {seed} {r:?}");
                    r
                })
                .collect();
            random_rows(&mut t, [flow, &seed.to_string()], &runs, reference, max_steps);
        }
    }
    t
}

/// The heading and the text of a random-array section: its grids, how the spheres meet the fluid
/// (`boundary`), the bed's Archimedes number `ar` and Tenneti's Reynolds number `bed` there.
fn random_heading(grids: &str, boundary: Spheres, phi: f64, [ar, bed]: [f64; 2]) -> String {
    format!(
        "\n## Immersed moving boundary: a random array at the fluidized bed's voidage, {grids}\n\n\
         The simple cubic array of the section above carries the bed's weight at Re 476-491, where the \
         fluidized bed (validation/imb/FLUIDIZED_BED.md) stands at the same voidage at Re 200; but \
         spheres in line shelter each other in their wakes. Here {RANDOM_COUNT} spheres at the same \
         solid fraction {phi} lie at random in a periodic box (random sequential addition, none \
         overlapping; two placements), held, the fluid driven by a mean pressure gradient as above \
         ({}), and the superficial \
         Reynolds number Re = U d / nu at which the spheres carry the force is measured at each \
         resolution (U: the mean velocity over the box; the liquid inside a held sphere is at rest). \
         Reference: Tenneti, Garg & Subramaniam (2011), particle-resolved simulations of fixed random \
         arrays (solid fraction 0.1-0.5, Re up to 300): force per sphere 3 pi mu d U F with F = \
         F_isol / eps^3 + F_phi + F_phi,Re (the mean pressure gradient's share included); \"Tenneti \
         Re\": where that force is the one applied. Two flows: Stokes flow (tau {STOKES_TAU}, the force \
         Tenneti's at Re {STOKES_RE}; what the arrangement and the boundary give without inertia) and \
         the bed's weight (a grain's buoyant weight per sphere, Ar = {ar:.3e}; nu set so that U nears \
         {VELOCITY} as in the bed, so tau nears 1/2; Tenneti's random array carries it at Re \
         {bed:.0}, Richardson & Zaki's fluidized bed at Re {:.0}). A run stops when {} checks {} steps \
         apart agree to 1e-3 (steady), else after {STOKES_MAX_STEPS} (Stokes) or {RANDOM_MAX_STEPS} \
         steps (mean and range of the last checks). A higher Re than Tenneti's: less drag.\n\n\
         | flow | placement | box n | d (cells) | tau | steps | outcome | Re mean | Re range | Tenneti Re | error | grid error of Re vs finest |\n\
         |---|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|\n",
        match boundary {
            Spheres::Immersed => "MRT, the immersed boundary with Noble-Torczynski weighting, 2 particles per cell as in the bed",
            Spheres::Staircase => "MRT; here each sphere is the solid cells whose centre lies within it, with half-way \
                bounce-back, as a staircase: no solid fractions, no immersed boundary; the force acts on the \
                fluid cells, its total the same",
        },
        richardson_zaki(ar, 1.0 - phi),
        cases::WEIGHT_SAMPLES,
        cases::WEIGHT_CHECK,
    )
}

/// How an array's run ended: blew up (where), steady, or stopped at `max_steps` unsteady.
fn outcome(r: &WeightedArray, max_steps: u64) -> String {
    match &r.unhealthy {
        Some(bad) => format!(
            "blew up at ({}, {}, {})",
            bad.coords[0], bad.coords[1], bad.coords[2]
        ),
        None if r.steps < max_steps => "steady".into(),
        None => "not steady".into(),
    }
}

/// The rows of one placement's runs by resolution, labelled [flow, placement].
fn random_rows(
    t: &mut String,
    [flow, seed]: [&str; 2],
    runs: &[WeightedArray],
    reference: f64,
    max_steps: u64,
) {
    let finest = runs.last().map_or(f64::NAN, |r| r.reynolds[0]);
    for r in runs {
        let [mean, low, high] = r.reynolds;
        let numbers = if r.unhealthy.is_some() {
            format!("| | {reference:.3} | |")
        } else {
            format!(
                "{mean:.3} | {low:.3}-{high:.3} | {reference:.3} | {:+.1}% | {:+.1}%",
                100.0 * (mean / reference - 1.0),
                100.0 * (mean / finest - 1.0)
            )
        };
        let _ = writeln!(
            t,
            "| {flow} | {seed} | {} | {:.2} | {:.4} | {} | {} | {numbers} |",
            r.cells,
            r.diameter,
            r.tau,
            r.steps,
            outcome(r, max_steps)
        );
    }
}

#[cfg(test)]
mod tests {
    use super::super::report_rows;
    use super::{
        archimedes, richardson_zaki, settling_reynolds, tenneti, tenneti_reynolds, DIAMETERS,
        RANDOM_DIAMETERS, RANDOM_SEEDS, SOLID_FRACTIONS,
    };

    /// The report's section holds one row per solid fraction and diameter, in that order.
    #[test]
    fn the_bed_drag_section_holds_the_runs() {
        let rows = report_rows("## Immersed moving boundary: drag in a bed", &["0."], 1);
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

    /// The random-drag section holds one row per flow, placement and diameter, in that order.
    #[test]
    fn the_random_drag_section_holds_the_runs() {
        let rows = report_rows(
            "## Immersed moving boundary: a random array",
            &["Stokes", "the bed"],
            2,
        );
        let runs: Vec<String> = ["| Stokes", "| the bed's weight"]
            .iter()
            .flat_map(|flow| RANDOM_SEEDS.iter().map(move |seed| format!("{flow} | {seed}")))
            .flat_map(|row| RANDOM_DIAMETERS.iter().map(move |_| row.clone()))
            .collect();
        assert_eq!(rows, runs);
    }

    /// Tenneti et al.'s law: one sphere alone is Schiller-Naumann's, and the bed's grain is
    /// carried at Re 361 at voidage 0.76, within 5% of Richardson & Zaki's fluidized bed there
    /// (Re 379): two independent references agree where the random array is compared with them.
    #[test]
    fn tennetis_law_agrees_with_richardson_and_zaki() {
        let (phi, eps) = (0.24f64, 0.76f64);
        assert!((tenneti(0.0, 100.0) - (1.0 + 0.15 * 100f64.powf(0.687))).abs() < 1e-12);
        let re = tenneti_reynolds(archimedes(), phi);
        assert!((re - 361.1).abs() < 0.1, "{re}");
        assert!((re / richardson_zaki(archimedes(), eps) - 1.0).abs() < 0.05);
    }
}
