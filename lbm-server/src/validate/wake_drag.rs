//! `lbm-server validate --only wake-drag`: a sphere held in a stream at the fluidized bed's
//! Reynolds numbers, by resolution, tau, operator and weighting: does the immersed boundary
//! drag a lone sphere too much where its boundary layer is thinner than a cell, and does that
//! fall with the grid?

use super::operator_named;
use crate::lbm::cases::{self, schiller_naumann, Faces, HeldSphere};
use crate::lbm::gpu::Gpu;
use crate::lbm::imb::{ImbOptions, SolidCollision};
use std::fmt::Write as _;
use std::sync::Arc;

/// Box width and length in diameters (the stability section's box: 6 x 6 x 10).
const WIDTH: f64 = 6.0;
const LENGTH: f64 = 10.0;
/// Passes of the stream through the box; C_d is averaged over the last.
const PASSES: f64 = 4.0;
/// Steps between health checks (each reads every cell back): the stability section's on
/// lavapipe's grids, fewer on a GPU's.
const CHECK: u64 = cases::STABILITY_CHECK;
const FINE_CHECK: u64 = 100;

/// One held sphere: Reynolds number, diameter (cells), stream velocity, operator (by the names
/// of [`operator_named`]), the seed's weighting B = eps instead of Noble-Torczynski's.
#[derive(Debug, Clone, Copy)]
pub(super) struct Wake {
    pub re: f64,
    pub d: f64,
    pub u0: f64,
    pub operator: &'static str,
    pub seed: bool,
    /// The superposition solid term instead of Noble-Torczynski's (`SolidCollision`).
    pub superposition: bool,
}

const fn mrt(re: f64, d: f64) -> Wake {
    Wake {
        re,
        d,
        u0: cases::STREAM_VELOCITY,
        operator: "MRT",
        seed: false,
        superposition: false,
    }
}

/// `mrt` with the superposition solid term.
const fn superposed(re: f64, d: f64) -> Wake {
    Wake {
        superposition: true,
        ..mrt(re, d)
    }
}

/// The runs: MRT by resolution at Re 200 (a steady wake) and 300 (shedding); at 8 cells, one
/// thing changed at a time: the stream velocity (tau and Mach with it), the operator, the weighting.
pub(super) const WAKES: [Wake; 13] = [
    mrt(200.0, 6.0),
    mrt(200.0, 8.0),
    mrt(300.0, 6.0),
    mrt(300.0, 8.0),
    Wake {
        u0: 0.04,
        ..mrt(200.0, 8.0)
    },
    Wake {
        u0: 0.12,
        ..mrt(200.0, 8.0)
    },
    Wake {
        operator: "BGK",
        ..mrt(200.0, 8.0)
    },
    Wake {
        operator: "TRT 3/16 (tau- <= 1)",
        ..mrt(200.0, 8.0)
    },
    Wake {
        seed: true,
        ..mrt(200.0, 8.0)
    },
    mrt(200.0, 12.0),
    mrt(300.0, 12.0),
    mrt(200.0, 16.0),
    mrt(300.0, 16.0),
];

/// `--only wake-drag-fine`: the MRT series on a GPU's grids.
const FINE: [Wake; 3] = [mrt(200.0, 24.0), mrt(300.0, 24.0), mrt(200.0, 32.0)];

/// `--only wake-drag-superposition`: the MRT series with the superposition solid term.
pub(super) const SUPERPOSED: [Wake; 6] = [
    superposed(200.0, 6.0),
    superposed(200.0, 8.0),
    superposed(300.0, 6.0),
    superposed(300.0, 8.0),
    superposed(200.0, 12.0),
    superposed(200.0, 16.0),
];

/// What the superposition section says before its table.
const SUPERPOSED_NOTE: &str =
    "Every row here with the superposition solid term (`coupling.solid_collision = \
    \"superposition\"`, docs/imb.md \"The solid collision\"): the covered cell keeps the fluid's own \
    collision, its equilibrium moved to the solid's velocity, where Noble & Torczynski's term (the rows \
    above, and the default) bounces its non-equilibrium part back. Weighting B(eps, tau) as above.\n\n";

impl Wake {
    fn tau(&self) -> f64 {
        0.5 + 3.0 * self.u0 * self.d / self.re
    }

    fn held(&self) -> HeldSphere {
        let tau = self.tau();
        HeldSphere {
            reynolds: self.re,
            diameter: self.d,
            width: (WIDTH * self.d).round() as usize,
            length: (LENGTH * self.d).round() as usize,
            tau: Some(tau),
            drawn_larger: 0.0,
            operator: operator_named(self.operator, tau),
            imb: ImbOptions {
                seed_weighting: self.seed,
                solid_collision: if self.superposition {
                    SolidCollision::Superposition
                } else {
                    SolidCollision::NobleTorczynski
                },
                ..Default::default()
            },
            shift: 0.0,
        }
    }

    /// A row of the MRT series by resolution (the stream velocity, operator and weighting of the
    /// finest rows).
    fn is_series(&self) -> bool {
        self.operator == "MRT" && !self.seed && self.u0 == cases::STREAM_VELOCITY
    }

    fn weighting(&self) -> &'static str {
        if self.seed {
            "seed"
        } else {
            "Noble-Torczynski"
        }
    }
}

pub(super) fn section(gpu: &Arc<Gpu>) -> String {
    wakes(gpu, "", "", &WAKES, CHECK)
}

pub(super) fn fine_section(gpu: &Arc<Gpu>) -> String {
    wakes(gpu, ", finer grids", "", &FINE, FINE_CHECK)
}

pub(super) fn superposition_section(gpu: &Arc<Gpu>) -> String {
    wakes(
        gpu,
        ", the superposition term",
        SUPERPOSED_NOTE,
        &SUPERPOSED,
        CHECK,
    )
}

/// The held spheres' section for these runs, its heading ending in `grids`, `note` before the
/// description.
fn wakes(gpu: &Arc<Gpu>, grids: &str, note: &str, runs: &[Wake], check: u64) -> String {
    let mut t = wakes_heading(grids, note, runs, check);
    let mut series = Vec::new();
    for w in runs {
        let s = cases::sphere_stability(gpu, &w.held(), Faces::Open, PASSES, check);
        protocol::say!("lbm-server: wake-drag: {w:?}: {s:?}");
        let (outcome, drag) = outcome_and_drag(w, &s, &mut series);
        let _ = writeln!(
            t,
            "| {} | {} | {:.2} | {} | {} | {} | {:.4} | {} | {outcome} | {drag} |",
            w.re,
            w.d,
            w.d / w.re.sqrt(),
            w.operator,
            w.weighting(),
            w.u0,
            s.tau,
            s.steps,
        );
    }
    t + &convergence(&series)
}

/// The heading, description and table header of [`wakes`].
fn wakes_heading(grids: &str, note: &str, runs: &[Wake], check: u64) -> String {
    let varied = if runs.iter().all(Wake::is_series) {
        ""
    } else {
        ", then at 8 cells one thing changed at a time (u0, so tau and Mach; the operator; the weighting)"
    };
    format!(
        "\n## Immersed moving boundary: a held sphere at the fluidized bed's Reynolds numbers{grids}\n\n\
         {note}The random arrays at the fluidized bed's voidage (section \"a random array at the fluidized \
         bed's voidage\") drag 1.6-1.8 times Tenneti et al.'s at Re 250-360 and hardly less from 6 to 12 \
         cells per diameter. Here one sphere held in a stream at Re 200 (a steady wake) and 300 (a \
         shedding one), in the sphere-drag section's open box (velocity inlet, pressure outlet, side \
         faces moving with the stream) of {WIDTH} x {WIDTH} x {LENGTH} diameters at every resolution, the \
         sphere at L/3; impulsive start; {PASSES} passes of the stream, C_d over the last (mean and \
         range); the lattice checked every {check} steps. tau = 1/2 + 3 u0 d / Re, near 1/2 as in the \
         bed. MRT by resolution{varied}. Boundary-layer cells: d / sqrt(Re), the boundary layer's thickness \
         in cells. Reference: Schiller & Naumann (within about 5% of experiments; resolved simulations \
         lie a few percent below it at these Re); the box confines by about +2% (sphere-drag section, \
         Re 50, 6 diameters wide).\n\n\
         | Re | d (cells) | boundary-layer cells | operator | weighting | u0 | tau | steps | outcome | C_d mean | C_d range | C_d Schiller-Naumann | error |\n\
         |---:|---:|---:|---|---|---:|---:|---:|---|---:|---:|---:|---:|\n"
    )
}

/// The outcome and drag columns of the held sphere `w`'s row from its run `s`; a held run of
/// the MRT series adds (Re, d, C_d as the table shows it) to `series`.
fn outcome_and_drag(w: &Wake, s: &cases::Stability, series: &mut Vec<(f64, f64, f64)>) -> (String, String) {
    let sn = schiller_naumann(w.re);
    match (&s.unhealthy, s.cd) {
        (None, Some([mean, low, high])) => {
            // C_d as the table shows it: the error and the closing lines are the table's.
            let mean = (mean * 1e3).round() / 1e3;
            if w.is_series() {
                series.push((w.re, w.d, mean));
            }
            (
                "held".to_string(),
                format!(
                    "{mean:.3} | {low:.3}-{high:.3} | {sn:.3} | {:+.1}%",
                    100.0 * (mean / sn - 1.0)
                ),
            )
        }
        (bad, _) => (
            bad.as_ref()
                .map_or("no drag".into(), |b| format!("blew up at {:?}", b.coords)),
            format!(" | | {sn:.3} | "),
        ),
    }
}

/// Per Reynolds number of the MRT series (Re, d, C_d): C_d and its error against
/// Schiller-Naumann from the coarsest grid to the finest, and the change between the two finest.
pub(super) fn convergence(series: &[(f64, f64, f64)]) -> String {
    let mut res: Vec<f64> = series.iter().map(|r| r.0).collect();
    res.sort_by(f64::total_cmp);
    res.dedup();
    let mut t = String::new();
    for re in res {
        let mut rows: Vec<(f64, f64)> = series.iter().filter(|r| r.0 == re).map(|r| (r.1, r.2)).collect();
        rows.sort_by(|a, b| a.0.total_cmp(&b.0));
        let [.., (d1, c1), (d2, c2)] = rows[..] else {
            continue;
        };
        let (d0, c0) = rows[0];
        let sn = schiller_naumann(re);
        let error = |c: f64| 100.0 * (c / sn - 1.0);
        let _ = writeln!(
            t,
            "\nRe {re}, MRT, from {d0} to {d2} cells per diameter: C_d {c0:.3} -> {c2:.3} ({:+.1}%), \
             against Schiller-Naumann {:+.1}% -> {:+.1}%; from {d1} to {d2} cells {:+.1}%.",
            100.0 * (c2 / c0 - 1.0),
            error(c0),
            error(c2),
            100.0 * (c2 / c1 - 1.0),
        );
    }
    t
}

#[cfg(test)]
mod tests {
    use super::super::{report_rows, report_section};
    use super::{convergence, Wake, SUPERPOSED, WAKES};

    /// Each Reynolds number's series, whatever the order of its rows, is read from its coarsest
    /// grid to its finest.
    #[test]
    fn the_convergence_lines_read_each_series_from_coarsest_to_finest() {
        let c = |d: f64| 0.8 + 1.6 / d;
        let series = [
            (200.0, 12.0, c(12.0)),
            (300.0, 6.0, 0.9),
            (200.0, 6.0, c(6.0)),
            (300.0, 8.0, 0.8),
            (200.0, 8.0, c(8.0)),
        ];
        let text = convergence(&series);
        assert_eq!(text.matches("\nRe 200,").count(), 1, "{text}");
        assert!(
            text.contains("Re 200, MRT, from 6 to 12 cells per diameter: C_d 1.067 -> 0.933 (-12.5%)"),
            "{text}"
        );
        assert!(text.contains("from 8 to 12 cells -6.7%."), "{text}");
        assert!(
            text.contains("Re 300, MRT, from 6 to 8 cells per diameter: C_d 0.900 -> 0.800 (-11.1%)"),
            "{text}"
        );
    }

    const HEADING: &str =
        "## Immersed moving boundary: a held sphere at the fluidized bed's Reynolds numbers\n";

    /// The rows of the report's section are the runs, in order, and its closing lines are the
    /// series' as `convergence` writes them from those rows.
    #[test]
    fn the_wake_drag_section_holds_the_runs() {
        section_holds(HEADING, &WAKES);
    }

    #[test]
    fn the_superposition_section_holds_its_runs() {
        section_holds(
            "## Immersed moving boundary: a held sphere at the fluidized bed's Reynolds numbers, \
             the superposition term\n",
            &SUPERPOSED,
        );
    }

    fn section_holds(heading: &str, wakes: &[Wake]) {
        let rows = report_rows(heading, &["200 ", "300 "], 13);
        let runs: Vec<String> = wakes
            .iter()
            .map(|w| {
                format!(
                    "| {} | {} | {:.2} | {} | {} | {}",
                    w.re,
                    w.d,
                    w.d / w.re.sqrt(),
                    w.operator,
                    w.weighting(),
                    w.u0
                )
            })
            .collect();
        let heads: Vec<String> = rows
            .iter()
            .map(|r| r.split(" | ").take(6).collect::<Vec<_>>().join(" | "))
            .collect();
        assert_eq!(heads, runs);
        let series: Vec<(f64, f64, f64)> = wakes
            .iter()
            .zip(&rows)
            .filter(|(w, _)| w.is_series())
            .map(|(w, row)| {
                (
                    w.re,
                    w.d,
                    row.split(" | ")
                        .nth(9)
                        .expect("C_d mean")
                        .parse()
                        .expect("a number"),
                )
            })
            .collect();
        let section = report_section(heading);
        let lines = convergence(&series);
        assert!(section.contains(&lines), "{lines}");
    }
}
