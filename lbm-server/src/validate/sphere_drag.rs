//! `lbm-server validate --only sphere-drag`, `sphere-correction`: a sphere held in a uniform
//! stream against Schiller & Naumann, and at Ten Cate E4's Reynolds number drawn at its radius and
//! larger (the calibrated radius correction), held in boxes of several sizes and towed.

use super::TRT;
use crate::lbm::cases;
use crate::lbm::gpu::Gpu;
use std::fmt::Write as _;
use std::sync::Arc;

pub(super) fn sphere_drag(gpu: &Arc<Gpu>) -> String {
    let mut t = String::from(
        "\n## Immersed moving boundary: a sphere held in a uniform stream (Schiller & Naumann)\n\n\
         A sphere of d cells at rest in a stream u0 along x: velocity inlet at x = 0, pressure outlet \
         at x = L, the side faces (box width W) moving with the stream, the sphere at L/3. TRT, \
         Noble-Torczynski weighting; u0 = 0.08 or less (tau <= 1), run until the drag changes by less \
         than 1e-4 over 100 steps. C_d = F / (rho u0^2 pi d^2 / 8) against Schiller & Naumann (1933), \
         C_d = 24/Re (1 + 0.15 Re^0.687), itself within about 5% of experiments. The side faces make the \
         box a confined stream: where several W were run, the row \"W -> inf\" is the fit \
         C_d(W) = C_inf + a (d/W)^p through the three widest boxes (p in the steps column), the \
         sphere's drag without confinement at that resolution. Re 100 runs at 12 cells per diameter (tau \
         0.529): at 8 (tau 0.519) it blows up by step 1400, also with the start smoothed (the sphere \
         slowed from the stream's speed to rest over half a pass; 2026-12-01), while the same box without \
         the sphere runs steadily. It blows up at the velocity inlet, upstream of the sphere (section \
         \"Stability near tau = 1/2\": TRT 3/16 by step 1160 at tau 0.519; MRT and BGK hold there).\n\n\
         | Re | d | W | L | u0 | tau | steps | C_d measured | C_d Schiller-Naumann | error |\n\
         |---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for &(re, d, widths, l) in SPHERE_DRAG_CASES {
        let mut confined = Vec::new();
        for &w in widths {
            match cases::fixed_sphere(gpu, re, d, w, l) {
                Ok(s) => {
                    confined.push((d / w as f64, s.cd));
                    let _ = writeln!(
                        t,
                        "| {re} | {} | {} | {} | {:.4} | {:.3} | {} | {:.3} | {:.3} | {:+.1}% |",
                        s.diameter,
                        s.width,
                        s.length,
                        s.u0,
                        s.tau,
                        s.steps,
                        s.cd,
                        s.schiller_naumann(),
                        100.0 * (s.cd / s.schiller_naumann() - 1.0)
                    );
                }
                Err(e) => {
                    let _ = writeln!(t, "| {re} | {d} | {w} | {l} | | | | {e} | | |");
                }
            }
        }
        if let Some((cd, p)) = cases::unconfined_drag(&confined) {
            let reference = cases::schiller_naumann(re);
            let _ = writeln!(
                t,
                "| {re} | {d} | W -> inf | {l} | | | p = {p:.2} | {cd:.3} | {reference:.3} | {:+.1}% |",
                100.0 * (cd / reference - 1.0)
            );
        }
    }
    t
}

/// (Re, diameter, box widths, length) of the fixed-sphere cases.
const SPHERE_DRAG_CASES: &[(f64, f64, &[usize], usize)] = &[
    (1.0, 8.0, &[32, 48, 64], 80),
    (10.0, 8.0, &[32, 48, 64, 80], 80),
    (50.0, 8.0, &[48, 64, 80], 80),
    (100.0, 12.0, &[72], 120),
];

/// Ten Cate E4's Reynolds number and its lattice's tau at 6, 9 and 12 cells per diameter (Mach
/// 0.1; validation/imb/RADIUS_CORRECTION.md).
pub(super) const E4_REYNOLDS: f64 = 32.2;
const E4_TAUS: [(f64, f64); 3] = [(6.0, 0.533), (9.0, 0.549), (12.0, 0.565)];

/// The boxes (W, L in diameters) of [`sphere_correction`] at `d` cells per diameter: 6 x 6 x
/// 10 at every resolution, at 6 cells also 8 and 10 wide (confinement) and 8 x 8 x 15 (inlet and
/// outlet).
fn correction_boxes(d: f64) -> &'static [(f64, f64)] {
    if d == 6.0 {
        &[(6.0, 10.0), (8.0, 10.0), (10.0, 10.0), (8.0, 15.0)]
    } else {
        &[(6.0, 10.0)]
    }
}

/// The held sphere at E4's Reynolds number and taus, at its radius and drawn larger by the
/// calibrated correction, in the boxes of [`correction_boxes`].
pub(super) fn sphere_correction(gpu: &Arc<Gpu>) -> String {
    let mut t = String::from(
        "\n## Immersed moving boundary: the radius correction on a held sphere at Re 32\n\n\
         The sphere of the section above at Ten Cate E4's Reynolds number (32.2) and at the taus E4 ran \
         at with 6, 9 and 12 cells per diameter (Mach 0.1), in a box of 6 x 6 x 10 diameters (W x W x L, \
         the sphere L/3 from the inlet), drawn at its radius and drawn larger by \
         `coupling.radius_correction = \"calibrated\"` (the deficit of the Zick-Homsy array at that \
         tau, scaled as 1 / radius). C_d with the nominal diameter. A boundary whose deficit acts in this \
         flow makes C_d at the radius rise towards its limit as 1 / N^2 and the corrected C_d hold; a \
         deficit that does not act leaves C_d at the radius flat and the corrected C_d above it by the \
         correction's share. At 6 cells also boxes 8 and 10 diameters wide (confinement) and one of 8 x 8 \
         x 15 (the inlet 5 diameters upstream instead of 3.3). References: Schiller-Naumann and the \
         experiment's drag, C_d = 4/3 (rho_p / rho_f - 1) g d / u_inf^2 = 1.996 (E4's u_inf 0.128 m/s).\n\n\
         | d | W | L | tau | u0 | drawn larger by | steps | C_d | C_d Schiller-Naumann | error | against the experiment |\n\
         |---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    let experiment = e4_experiment_cd();
    let mut rows = Vec::new();
    for &(d, tau) in &E4_TAUS {
        for &(w, l) in correction_boxes(d) {
            for corrected in [false, true] {
                let case = correction_case(d, tau, (w, l), corrected);
                let drag = match case.and_then(|c| cases::held_sphere(gpu, &c)) {
                    Ok(s) => s,
                    Err(e) => {
                        let _ = writeln!(t, "| {d} | {w} d | {l} d | {tau} | | | | {e} | | | |");
                        continue;
                    }
                };
                protocol::say!("lbm-server: sphere-correction: {drag:?}");
                let _ = writeln!(
                    t,
                    "| {d} | {} | {} | {tau} | {:.4} | {:.3} | {} | {:.3} | {:.3} | {:+.1}% | {:+.1}% |",
                    drag.width,
                    drag.length,
                    drag.u0,
                    drag.drawn_larger,
                    drag.steps,
                    drag.cd,
                    drag.schiller_naumann(),
                    100.0 * (drag.cd / drag.schiller_naumann() - 1.0),
                    100.0 * (drag.cd / experiment - 1.0)
                );
                rows.push(drag);
            }
        }
    }
    t + &correction_summary(&rows, experiment) + &towed_spheres(gpu, &rows)
}

/// The held spheres of the 6 x 6 box at 6, 9 and 12 cells towed through fluid at rest instead
/// ([`cases::towed_sphere`]), against their held C_d.
fn towed_spheres(gpu: &Arc<Gpu>, held: &[cases::SphereDrag]) -> String {
    let mut t = String::from(
        "\nThe same spheres towed at u0 through fluid at rest between walls at rest (the held box seen \
         from the far fluid; box 6 x 6 x 24 diameters, the sphere from 19 to 5 diameters from the closed \
         end it moves towards, started impulsively), so that its cells are covered and uncovered as it \
         moves as a settling sphere's are. C_d averaged over its travel from 10 to 12 and 12 to 14 \
         diameters; against the held sphere's C_d in the 6 x 6 x 10 box.\n\n\
         | d | tau | u0 | drawn larger by | steps | C_d over 10-12 d | C_d over 12-14 d | held | towed against held |\n\
         |---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for &(d, tau) in &E4_TAUS {
        for corrected in [false, true] {
            let towed =
                correction_case(d, tau, (6.0, 10.0), corrected).and_then(|c| cases::towed_sphere(gpu, &c));
            let towed = match towed {
                Ok(towed) => towed,
                Err(e) => {
                    let _ = writeln!(t, "| {d} | {tau} | | | | {e} | | | |");
                    continue;
                }
            };
            protocol::say!("lbm-server: sphere-correction: {towed:?}");
            let held = held_drag(held, (6.0, 10.0), corrected, d).unwrap_or(f64::NAN);
            let _ = writeln!(
                t,
                "| {d} | {:.3} | {:.4} | {:.3} | {} | {:.3} | {:.3} | {held:.3} | {:+.1}% |",
                towed.tau,
                towed.u0,
                towed.case.drawn_larger,
                towed.steps,
                towed.cd_early,
                towed.cd,
                100.0 * (towed.cd / held - 1.0)
            );
        }
    }
    t
}

/// The held sphere of [`sphere_correction`]: `d` cells, a box (W, L) in diameters.
fn correction_case(
    d: f64,
    tau: f64,
    (w, l): (f64, f64),
    corrected: bool,
) -> Result<cases::HeldSphere, String> {
    let drawn_larger = if corrected {
        crate::coupled::calibrated_drawn_larger("trt", tau, d / 2.0)?
    } else {
        0.0
    };
    Ok(cases::HeldSphere {
        reynolds: E4_REYNOLDS,
        diameter: d,
        width: (w * d).round() as usize,
        length: (l * d).round() as usize,
        tau: Some(tau),
        drawn_larger,
        operator: TRT,
        imb: Default::default(),
        shift: 0.0,
    })
}

/// Ten Cate E4's drag from its terminal velocity: C_d = 4/3 (rho_p / rho_f - 1) g d / u_inf^2.
fn e4_experiment_cd() -> f64 {
    let (rho_p, rho_f, g, d, u_inf) = (1120.0, 960.0, 9.81, 0.015, 0.128);
    4.0 / 3.0 * (rho_p / rho_f - 1.0) * g * d / (u_inf * u_inf)
}

/// C_d of the rows in a box of (W, L) diameters, drawn larger or not, as (d, C_d) by resolution.
fn drag_in_box(rows: &[cases::SphereDrag], (w, l): (f64, f64), corrected: bool) -> Vec<(f64, f64)> {
    rows.iter()
        .filter(|r| (r.width as f64 - w * r.diameter).abs() < 0.5)
        .filter(|r| (r.length as f64 - l * r.diameter).abs() < 0.5)
        .filter(|r| (r.drawn_larger > 0.0) == corrected)
        .map(|r| (r.diameter, r.cd))
        .collect()
}

/// C_d of the row at `d` cells in a box of (W, L) diameters, drawn larger or not.
fn held_drag(rows: &[cases::SphereDrag], b: (f64, f64), corrected: bool, d: f64) -> Option<f64> {
    drag_in_box(rows, b, corrected)
        .into_iter()
        .find(|c| c.0 == d)
        .map(|c| c.1)
}

/// The limit N -> inf of a value that converges as 1 / N^2, from its two finest (N, value).
fn second_order_limit(v: &[(f64, f64)]) -> Option<f64> {
    let [.., (n1, c1), (n2, c2)] = *v else {
        return None;
    };
    Some(c2 + (c2 - c1) / ((n2 / n1).powi(2) - 1.0))
}

/// The rows of [`sphere_correction`] summed up: per resolution in the 6 x 6 x 10 box, C_d at the
/// radius (and its limit N -> inf) and corrected, with their spreads; at 6 cells the box's share.
fn correction_summary(rows: &[cases::SphereDrag], experiment: f64) -> String {
    let spread = |v: &[(f64, f64)]| {
        let (lo, hi) = v
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), &(_, c)| (a.min(c), b.max(c)));
        100.0 * (hi - lo) / experiment
    };
    let list = |v: &[(f64, f64)]| {
        v.iter()
            .map(|(d, c)| format!("{c:.3} ({d})"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let (plain, corrected) = (
        drag_in_box(rows, (6.0, 10.0), false),
        drag_in_box(rows, (6.0, 10.0), true),
    );
    let mut t = format!(
        "\nIn the 6 x 6 x 10 box, C_d (cells per diameter): at the radius {}, spread {:.1}% of the \
         experiment's C_d; corrected {}, spread {:.1}%.\n",
        list(&plain),
        spread(&plain),
        list(&corrected),
        spread(&corrected)
    );
    if let Some(limit) = second_order_limit(&plain) {
        let _ = writeln!(
            t,
            "C_d at the radius taken to N -> inf as 1 / N^2 from its two finest rows: {limit:.3} \
             ({:+.1}% of the finest corrected C_d).",
            100.0 * (limit / corrected.last().map_or(f64::NAN, |c| c.1) - 1.0)
        );
    }
    t + &box_share(rows)
}

/// At 6 cells, how C_d moves from the 6 x 6 x 10 box to wider and longer ones.
fn box_share(rows: &[cases::SphereDrag]) -> String {
    let mut t = String::new();
    for corrected in [false, true] {
        let at = |b| held_drag(rows, b, corrected, 6.0);
        let boxes = [(6.0, 10.0), (8.0, 10.0), (10.0, 10.0), (8.0, 15.0)].map(at);
        let [Some(base), Some(eight), Some(wide), Some(long)] = boxes else {
            continue;
        };
        let _ = writeln!(
            t,
            "At 6 cells {}: W 6 -> 10 diameters {:+.1}% (8: {:+.1}%), L 10 -> 15 diameters at W 8 {:+.1}%.",
            if corrected { "corrected" } else { "at the radius" },
            100.0 * (wide / base - 1.0),
            100.0 * (eight / base - 1.0),
            100.0 * (long / eight - 1.0)
        );
    }
    t
}

#[cfg(test)]
mod tests {
    use super::super::report_section;
    use super::{correction_boxes, correction_summary, second_order_limit, E4_TAUS};

    /// The held spheres of the report's sphere-correction section are the cases of
    /// `correction_boxes` at E4's taus, each at its radius and corrected, in that order.
    #[test]
    fn the_sphere_correction_section_holds_the_boxes_run() {
        let section = report_section("## Immersed moving boundary: the radius correction on a held sphere");
        let rows: Vec<String> = section
            .lines()
            .filter(|l| l.split(" | ").count() == 11 && l.starts_with("| ") && !l.starts_with("| d"))
            .map(|l| l.split(" | ").take(4).collect::<Vec<_>>().join(" | "))
            .collect();
        let cases: Vec<String> = E4_TAUS
            .iter()
            .flat_map(|&(d, tau)| correction_boxes(d).iter().map(move |&(w, l)| (d, tau, w, l)))
            .flat_map(|(d, tau, w, l)| {
                let row = format!("| {d} | {} | {} | {tau}", w * d, l * d);
                [row.clone(), row]
            })
            .collect();
        assert_eq!(rows, cases);
    }

    /// The summary reads each box's row: C_d chosen so that every figure is known.
    #[test]
    fn the_correction_summary_reads_the_rows_of_each_box() {
        let row = |d: f64, (w, l): (f64, f64), drawn_larger: f64, cd: f64| crate::lbm::cases::SphereDrag {
            reynolds: 32.2,
            diameter: d,
            width: (w * d) as usize,
            length: (l * d) as usize,
            u0: 0.06,
            tau: 0.55,
            drawn_larger,
            steps: 100,
            cd,
        };
        let mut rows = Vec::new();
        for (drawn, scale) in [(0.0, 1.0), (0.1, 1.1)] {
            rows.push(row(6.0, (6.0, 10.0), drawn, 2.0 * scale));
            rows.push(row(6.0, (8.0, 10.0), drawn, 1.9 * scale));
            rows.push(row(6.0, (10.0, 10.0), drawn, 1.8 * scale));
            rows.push(row(6.0, (8.0, 15.0), drawn, 1.71 * scale));
            rows.push(row(12.0, (6.0, 10.0), drawn, 2.3 * scale));
        }
        let summary = correction_summary(&rows, 2.0);
        assert!(
            summary.contains("at the radius 2.000 (6), 2.300 (12), spread 15.0%"),
            "{summary}"
        );
        assert!(
            summary.contains("corrected 2.200 (6), 2.530 (12), spread 16.5%"),
            "{summary}"
        );
        assert!(summary.contains("two finest rows: 2.400 (-5.1% of"), "{summary}");
        let boxes = "W 6 -> 10 diameters -10.0% (8: -5.0%), L 10 -> 15 diameters at W 8 -10.0%.";
        assert_eq!(summary.matches(boxes).count(), 2, "{summary}");
    }

    #[test]
    fn a_second_order_limit_is_exact_for_values_falling_as_one_over_n_squared() {
        let values: Vec<(f64, f64)> = [6.0, 9.0, 12.0]
            .iter()
            .map(|&n: &f64| (n, 2.0 - 3.0 / (n * n)))
            .collect();
        let limit = second_order_limit(&values).unwrap();
        assert!((limit - 2.0).abs() < 1e-12, "{limit}");
        assert_eq!(second_order_limit(&values[..1]), None);
    }
}
