//! `lbm-server validate --only array-drag`, `array-drag-solid-collision`, `unresolved-drag`,
//! `drag-tau`, `radius-deficit`: the drag of simple cubic arrays of spheres in Stokes flow (Zick &
//! Homsy, Sangani & Acrivos) by operator, tau, weighting, solid term and resolution.

use super::TRT;
use crate::lbm::cases;
use crate::lbm::geometry::Operator;
use crate::lbm::gpu::Gpu;
use crate::lbm::imb::solid_reach;
use crate::lbm::mrt::Rates;
use std::fmt::Write as _;
use std::sync::Arc;

/// Zick & Homsy's arrays at their three solid fractions in boxes of 12 to 32 cells (TRT, tau 1),
/// then the middle one by operator, tau and weighting.
pub(super) fn array_drag(gpu: &Arc<Gpu>) -> String {
    let mut t = String::from(
        "\n## Immersed moving boundary: drag of a simple cubic array (Zick & Homsy 1982)\n\nOne sphere \
         fixed in a periodic n^3 box, flow driven by a body force f on the fluid (Re << 1), TRT, tau = 1, \
         Noble-Torczynski weighting. K = F / (6 pi mu a U), U the flux through a face of the box \
         divided by its area. Zick & Homsy's F is the total force on a sphere of an array driven by a \
         mean pressure gradient G, which balances the unit cell (F = G n^3); driven by a body force \
         f = G on the fluid instead, the flow is the same but the sphere misses the gradient's share \
         G V_s. So F = (momentum exchange) + f V_s, with V_s = 4/3 pi a^3. The column 'K balance' is \
         F = f n^3 with the measured U, which does not use the exchanged momentum: the two agree when \
         the exchange returns all the momentum the fluid receives.\n\n\
         | solid fraction | box n | radius (cells) | steps | K measured | K balance | K Zick-Homsy | error |\n\
         |---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for &(phi, k_ref) in &cases::ZICK_HOMSY {
        for n in [12, 16, 24, 32] {
            let d = cases::zick_homsy(gpu, n, cases::radius_for(phi, n), 1.0, TRT);
            let err = (d.k - k_ref) / k_ref;
            let _ = writeln!(
                t,
                "| {phi} | {n} | {:.2} | {} | {:.3} | {:.3} | {k_ref} | {:+.1}% |",
                d.radius,
                d.steps,
                d.k,
                d.k_balance,
                100.0 * err
            );
        }
    }
    t + &array_drag_by_operator(gpu)
}

/// The array of [`array_drag`] at solid fraction 0.125 in a 16^3 box, by operator, tau and
/// weighting.
fn array_drag_by_operator(gpu: &Arc<Gpu>) -> String {
    let mut t = String::from(
        "\nThe same at solid fraction 0.125, box 16 (radius 4.96), by operator, tau and weighting: the \
          immersed boundary's drag depends on tau (a known property of partially saturated cells).\n\n\
          | operator | tau | weighting | K | error |\n|---|---:|---|---:|---:|\n",
    );
    let (phi, k_ref) = cases::ZICK_HOMSY[1];
    for (op, tau, seed) in [
        (Operator::Bgk, 0.6, false),
        (Operator::Bgk, 0.6, true),
        (Operator::Bgk, 1.0, false),
        (TRT, 0.6, false),
        (TRT, 0.6, true),
        (TRT, 1.0, false),
        (TRT, 1.0, true),
    ] {
        let options = crate::lbm::imb::ImbOptions {
            slots: 2,
            seed_weighting: seed,
            ..Default::default()
        };
        let d = cases::zick_homsy_with(gpu, 16, cases::radius_for(phi, 16), tau, op, options);
        let name = if seed {
            "seed (B = eps)"
        } else {
            "Noble-Torczynski"
        };
        let _ = writeln!(
            t,
            "| {} | {tau} | {name} | {:.3} | {:+.1}% |",
            op.name(),
            d.k,
            100.0 * (d.k - k_ref) / k_ref
        );
    }
    t
}

/// Spheres of 0.5 to 6 cells per diameter in Stokes flow: a dilute simple cubic array in a 16^3
/// box against Sangani & Acrivos, each operator at tau 0.6 and 1, at rest (centre on a cell
/// corner) and, with TRT, moving through the lattice (averaged over 4 cells of travel); and the
/// volume the cells' solid fractions add up to.
pub(super) fn unresolved_drag(gpu: &Arc<Gpu>) -> String {
    let mut t = String::from(
        "\n## Immersed moving boundary: spheres of a few cells and less (Stokes flow)\n\n\
         One sphere of radius 0.25 to 3 cells fixed in a periodic 16^3 box (solid fraction 1.6e-5 \
         to 0.028), flow driven by a body force, Noble-Torczynski weighting; K as in \"drag of a simple \
         cubic array\" against Sangani & Acrivos's K of a dilute simple cubic array at that solid \
         fraction (their expansion matches Zick & Homsy's 2.008 and 4.292 within 0.1%). 'rest': the \
         centre on a cell corner; 'moving': the sphere moving through the lattice at 0.01 cells per \
         step, K averaged over its last 4 cells of travel (what a settling particle feels). A drag X% \
         low makes a particle settle about X% too fast in Stokes flow. 'volume': the cells' solid \
         fractions summed, against the sphere's volume, lowest and highest over 200 random centres.\n\n\
         | diameter (cells) | volume | K Sangani-Acrivos | BGK 0.6 | BGK 1 | TRT 0.6 rest | moving | TRT 1 rest | moving | MRT 0.6 | MRT 1 |\n\
         |---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    let mrt = |tau: f64| Operator::Mrt {
        rates: Rates::dhumieres(1.0 / tau),
    };
    let n = 16;
    for radius in [0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0] {
        let c = 4.0 / 3.0 * std::f64::consts::PI * radius * radius * radius / (n * n * n) as f64;
        let k_ref = cases::sangani_acrivos(c);
        let err = |k: f64| format!("{:+.1}%", 100.0 * (k - k_ref) / k_ref);
        let rest = |op: Operator, tau: f64| err(cases::zick_homsy(gpu, n, radius, tau, op).k);
        let moving = |tau: f64| {
            let options = crate::lbm::imb::ImbOptions::default();
            err(cases::moving_array_drag(gpu, n, [radius; 2], tau, TRT, options, 0.01).k)
        };
        let (low, high) = covered_volume_range(radius, 200);
        let _ = writeln!(
            t,
            "| {:.1} | {:+.1}% to {:+.1}% | {k_ref:.4} | {} | {} | {} | {} | {} | {} | {} | {} |",
            2.0 * radius,
            100.0 * low,
            100.0 * high,
            rest(Operator::Bgk, 0.6),
            rest(Operator::Bgk, 1.0),
            rest(TRT, 0.6),
            moving(0.6),
            rest(TRT, 1.0),
            moving(1.0),
            rest(mrt(0.6), 0.6),
            rest(mrt(1.0), 1.0)
        );
    }
    t + &unresolved_drag_calibrated(gpu)
}

/// The spheres of [`unresolved_drag`] from 1 cell per diameter, moving, with TRT, drawn larger
/// as `coupling.radius_correction = "calibrated"` draws them.
fn unresolved_drag_calibrated(gpu: &Arc<Gpu>) -> String {
    let mut t = String::from(
        "\nThe same spheres moving (TRT), drawn larger as `coupling.radius_correction = \
         \"calibrated\"` draws them (the deficit of the Zick-Homsy array at 4.96 cells radius at that \
         tau, scaled as 1 / radius, from 2 cells of radius down as at 2); K with the nominal radius:\n\n\
         | diameter (cells) | drawn larger by (tau 0.6 / 1, cells) | TRT 0.6 moving | TRT 1 moving |\n\
         |---:|---:|---:|---:|\n",
    );
    let n = 16;
    for radius in [0.5, 0.75, 1.0, 1.5, 2.0, 3.0] {
        let c = 4.0 / 3.0 * std::f64::consts::PI * radius * radius * radius / (n * n * n) as f64;
        let k_ref = cases::sangani_acrivos(c);
        let larger =
            |tau: f64| crate::coupled::calibrated_drawn_larger("trt", tau, radius).expect("calibrated");
        let moving = |tau: f64| {
            let options = crate::lbm::imb::ImbOptions::default();
            let drawn = [radius + larger(tau), radius];
            let k = cases::moving_array_drag(gpu, n, drawn, tau, TRT, options, 0.01).k;
            format!("{:+.1}%", 100.0 * (k - k_ref) / k_ref)
        };
        let _ = writeln!(
            t,
            "| {:.1} | {:.3} / {:.3} | {} | {} |",
            2.0 * radius,
            larger(0.6),
            larger(1.0),
            moving(0.6),
            moving(1.0)
        );
    }
    t
}

/// The lowest and highest relative error of the volume the cells' solid fractions add up to
/// (imb.wgsl's ramp) against the sphere's, over `centres` centres spread
/// evenly over a cell (the R3 sequence: multiples of 1/phi3, 1/phi3^2, 1/phi3^3, wrapped).
fn covered_volume_range(radius: f64, centres: usize) -> (f64, f64) {
    const PHI3: f64 = 1.220_744_084_605_759_5;
    let exact = 4.0 / 3.0 * std::f64::consts::PI * radius.powi(3);
    let m = radius.ceil() as i64 + 2;
    let mut range = (f64::INFINITY, f64::NEG_INFINITY);
    for k in 0..centres {
        let centre: [f64; 3] = std::array::from_fn(|a| (0.5 + k as f64 / PHI3.powi(a as i32 + 1)).fract());
        let mut volume = 0.0;
        for x in -m..=m {
            for y in -m..=m {
                for z in -m..=m {
                    let d2: f64 = [x, y, z]
                        .into_iter()
                        .zip(centre)
                        .map(|(v, c)| (v as f64 + 0.5 - c).powi(2))
                        .sum();
                    volume += (solid_reach(radius) - d2.sqrt()).clamp(0.0, 1.0);
                }
            }
        }
        let error = volume / exact - 1.0;
        range = (range.0.min(error), range.1.max(error));
    }
    range
}

/// The solid collision terms side by side in Stokes flow: Zick & Homsy's arrays at solid fraction
/// 0.125 and 0.343 (box 16), each operator at tau 0.6 and 1.0, Noble-Torczynski weighting.
pub(super) fn array_drag_solid_collision(gpu: &Arc<Gpu>) -> String {
    use crate::lbm::imb::{ImbOptions, SolidCollision};
    let mut t = String::from(
        "\n## Immersed moving boundary: the solid collision term in Stokes flow (Zick & Homsy)\n\n\
         The arrays of the section \"drag of a simple cubic array\" in a 16^3 box at solid fractions \
         0.125 (radius 4.96) and 0.343 (radius 6.95), by operator and tau, with Noble & Torczynski's \
         solid term (the default) and the superposition term (`coupling.solid_collision`, docs/imb.md \
         \"The solid collision\"); Noble-Torczynski weighting B(eps, tau) both. K as in that section \
         (F = momentum exchange + f V_s); 'K balance' from the driving alone.\n\n\
         | solid fraction | operator | tau | solid term | K | K balance | K Zick-Homsy | error |\n\
         |---:|---|---:|---|---:|---:|---:|---:|\n",
    );
    let mrt = |tau: f64| Operator::Mrt {
        rates: Rates::dhumieres(1.0 / tau),
    };
    for &(phi, k_ref) in &cases::ZICK_HOMSY[1..] {
        for tau in [0.6, 1.0] {
            for op in [Operator::Bgk, TRT, mrt(tau)] {
                for (term, name) in [
                    (SolidCollision::NobleTorczynski, "Noble-Torczynski"),
                    (SolidCollision::Superposition, "superposition"),
                ] {
                    let options = ImbOptions {
                        solid_collision: term,
                        ..Default::default()
                    };
                    let d = cases::zick_homsy_with(gpu, 16, cases::radius_for(phi, 16), tau, op, options);
                    let _ = writeln!(
                        t,
                        "| {phi} | {} | {tau} | {name} | {:.3} | {:.3} | {k_ref} | {:+.1}% |",
                        op.name(),
                        d.k,
                        d.k_balance,
                        100.0 * (d.k - k_ref) / k_ref
                    );
                }
            }
        }
    }
    t
}

/// The relaxation times of the tau sections (the coarse array's; the fine one skips 0.7).
const TAUS: [f64; 7] = [0.55, 0.6, 0.7, 0.8, 1.0, 1.5, 2.0];

/// The array runs of the tau sections: (box n, tau, operator), the three operators in a 16^3 box at
/// [`TAUS`], TRT in a 24^3 box at the same taus but 0.7.
fn runs_over_tau() -> Vec<(usize, f64, Operator)> {
    let mrt = |tau: f64| Operator::Mrt {
        rates: Rates::dhumieres(1.0 / tau),
    };
    let coarse = TAUS
        .into_iter()
        .flat_map(|tau| [(16, tau, Operator::Bgk), (16, tau, TRT), (16, tau, mrt(tau))]);
    let fine = TAUS
        .into_iter()
        .filter(|&tau| tau != 0.7)
        .map(|tau| (24, tau, TRT));
    coarse.chain(fine).collect()
}

/// The array's drag against tau for each operator (Noble-Torczynski weighting), at two resolutions.
pub(super) fn drag_against_tau(gpu: &Arc<Gpu>) -> String {
    let mut t = String::from(
        "\n## Immersed moving boundary: drag against tau (Zick & Homsy array, solid fraction 0.125)\n\n\
         The array of the section above at solid fraction 0.125, Noble-Torczynski weighting, by operator \
         and relaxation time. In a scene tau follows from the resolution and the Mach number (tau = 1/2 + \
         sqrt(3) nu Ma / (U dx)): a low-Re case (Ten Cate E1, E2) at a Mach number that keeps the step \
         count low runs at tau 1-2.5. A drag error of x % makes a sphere's Stokes settling speed about \
         -x % off. MRT: d'Humieres' rates for the non-hydrodynamic moments.\n\n\
         | box n | radius (cells) | tau | operator | steps | K | K Zick-Homsy | error |\n\
         |---:|---:|---:|---|---:|---:|---:|---:|\n",
    );
    let (phi, k_ref) = cases::ZICK_HOMSY[1];
    for (n, tau, op) in runs_over_tau() {
        let options = crate::lbm::imb::ImbOptions {
            slots: 2,
            ..Default::default()
        };
        let d = cases::zick_homsy_with(gpu, n, cases::radius_for(phi, n), tau, op, options);
        let _ = writeln!(
            t,
            "| {n} | {:.2} | {tau} | {} | {} | {:.3} | {k_ref} | {:+.1}% |",
            d.radius,
            op.name(),
            d.steps,
            d.k,
            100.0 * (d.k - k_ref) / k_ref
        );
    }
    t
}

/// The hydrodynamic radius deficit against tau (the drag-against-tau array drawn larger until its
/// drag is Zick & Homsy's).
pub(super) fn radius_deficit(gpu: &Arc<Gpu>) -> String {
    let mut t = String::from(
        "\n## Immersed moving boundary: hydrodynamic radius deficit against tau\n\n\
         The array of \"drag against tau\" (solid fraction 0.125, Noble-Torczynski weighting) with the \
         sphere drawn on the lattice delta cells larger than its nominal radius, K normalised with the \
         nominal radius and the pressure-gradient share of the nominal sphere: delta from the secant \
         through delta = 0 and 0.25, then run. delta is how much smaller than the nominal sphere the \
         immersed boundary acts at that tau and resolution (`coupling.radius_correction`, docs/imb.md).\n\n\
         | box n | nominal radius (cells) | tau | operator | steps per run | K nominal | delta (cells) | K drawn + delta | K Zick-Homsy | error drawn |\n\
         |---:|---:|---:|---|---:|---:|---:|---:|---:|---:|\n",
    );
    let (phi, k_ref) = cases::ZICK_HOMSY[1];
    for (n, tau, op) in runs_over_tau() {
        let radius = cases::radius_for(phi, n);
        let d = cases::radius_deficit(gpu, n, radius, k_ref, tau, op);
        let _ = writeln!(
            t,
            "| {n} | {radius:.2} | {tau} | {} | {} | {:.3} | {:+.3} | {:.3} | {k_ref} | {:+.1}% |",
            op.name(),
            d.steps,
            d.k_nominal,
            d.delta,
            d.k_drawn,
            100.0 * (d.k_drawn - k_ref) / k_ref
        );
    }
    t
}

#[cfg(test)]
mod tests {
    use super::super::report_section;
    use super::runs_over_tau;

    /// The tau sections of validation/lbm/REPORT.md list their runs in the order of
    /// `runs_over_tau` (box n, tau, operator), row by row.
    #[test]
    fn the_tau_sections_of_the_report_are_the_runs_over_tau() {
        let runs: Vec<String> = runs_over_tau()
            .into_iter()
            .map(|(n, tau, op)| format!("| {n} | {tau} | {} |", op.name()))
            .collect();
        for heading in ["drag against tau", "hydrodynamic radius deficit against tau"] {
            let section = report_section(&format!("## Immersed moving boundary: {heading}"));
            let rows: Vec<String> = section
                .lines()
                .filter(|l| l.starts_with("| 16 |") || l.starts_with("| 24 |"))
                .map(|l| {
                    let cells: Vec<&str> = l.split(" | ").collect();
                    format!("{} | {} | {} |", cells[0], cells[2], cells[3])
                })
                .collect();
            assert_eq!(rows, runs, "{heading}");
        }
    }
}
