//! `lbm-server validate --only moving-boundary`: whether the immersed boundary acts the same
//! moving as at rest (a sphere held in a stream and towed through fluid at rest; the Zick-Homsy
//! array moving through the lattice).

use super::operator_named;
use super::sphere_drag::E4_REYNOLDS;
use crate::lbm::cases;
use crate::lbm::gpu::Gpu;
use std::fmt::Write as _;
use std::sync::Arc;

/// One comparison of [`moving_boundary`]: the sphere of 6 cells per diameter held in a stream
/// and towed through fluid at rest at this Reynolds number, tau, operator and weighting; the held
/// one also moved downstream by each of `shifts` cells (its place against the lattice).
struct HeldAndTowed {
    operator: &'static str,
    reynolds: f64,
    tau: f64,
    seed_weighting: bool,
    shifts: &'static [f64],
}

/// The comparisons of [`moving_boundary`]: E4's Reynolds number first (its tau, twice its Mach
/// number and tau 0.6; the operators; TRT's magic parameter; the seed's weighting), then lower
/// Reynolds numbers.
const HELD_AND_TOWED: [HeldAndTowed; 15] = {
    const fn c(operator: &'static str, reynolds: f64, tau: f64) -> HeldAndTowed {
        HeldAndTowed {
            operator,
            reynolds,
            tau,
            seed_weighting: false,
            shifts: &[0.0],
        }
    }
    [
        HeldAndTowed {
            shifts: &[0.0, 0.5],
            ..c("TRT 3/16", E4_REYNOLDS, 0.533)
        },
        c("TRT 3/16", E4_REYNOLDS, 0.566),
        c("TRT 3/16", E4_REYNOLDS, 0.6),
        c("TRT 1/4", E4_REYNOLDS, 0.533),
        c("TRT 1/12", E4_REYNOLDS, 0.533),
        c("TRT 0.01", E4_REYNOLDS, 0.533),
        c("BGK", E4_REYNOLDS, 0.533),
        c("BGK", E4_REYNOLDS, 0.6),
        c("MRT", E4_REYNOLDS, 0.533),
        HeldAndTowed {
            seed_weighting: true,
            ..c("TRT 3/16", E4_REYNOLDS, 0.533)
        },
        c("TRT 3/16", 20.0, 0.55),
        c("TRT 3/16", 10.0, 0.533),
        c("TRT 3/16", 10.0, 0.6),
        c("BGK", 10.0, 0.6),
        c("TRT 3/16", 3.0, 0.6),
    ]
};

/// One measured row of [`moving_boundary`]: towed C_d against held C_d.
struct TowedRow {
    operator: &'static str,
    reynolds: f64,
    seed_weighting: bool,
    gap: f64,
}

/// Whether an immersed boundary acts the same moving as at rest: the sphere held in a stream
/// and towed through fluid at rest ([`cases::held_sphere`], [`cases::towed_sphere`])
/// at 6 cells per diameter, one thing changed at a time; then the Zick-Homsy array moving
/// through the lattice in Stokes flow ([`cases::moving_array_drag`]).
pub(super) fn moving_boundary(gpu: &Arc<Gpu>) -> String {
    let mut t = String::from(
        "\n## Immersed moving boundary: the sphere at rest and moving\n\n\
         A boundary that acts the same at rest and moving through the lattice gives a sphere held in a \
         stream and the same sphere towed through fluid at rest the same drag (the flows are one flow \
         seen from two frames). The towed sphere of the section above, at 6 cells per diameter (box 6 x 6 \
         x 24 diameters; the held one in 6 x 6 x 10), with one thing changed at a time: tau at E4's \
         Reynolds number (u0 = Re nu / d grows with it: Mach 0.1, 0.2, 0.31), the operator, TRT's magic \
         parameter Lambda (the antisymmetric relaxation time tau- = 1/2 + Lambda / (tau - 1/2): 6.2 for \
         3/16 at tau 0.533), the seed's weighting B = eps, the held sphere's place against the lattice \
         (moved half a cell downstream), and the Reynolds number. Boundary-layer cells = N / sqrt(Re): \
         the sphere's boundary layer, about d / sqrt(Re) thick, in cells.\n\n\
         | operator | weighting | Re | boundary-layer cells | tau | u0 | held moved by | held C_d | towed C_d 10-12 d | towed C_d 12-14 d | towed against held |\n\
         |---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    let mut rows = Vec::new();
    for c in &HELD_AND_TOWED {
        rows.extend(held_and_towed(gpu, c, &mut t));
    }
    t + &towed_summary(&rows) + &moving_arrays(gpu)
}

/// One comparison of [`HELD_AND_TOWED`]: its rows written to `t`, its gaps returned.
fn held_and_towed(gpu: &Arc<Gpu>, c: &HeldAndTowed, t: &mut String) -> Vec<TowedRow> {
    let mut rows = Vec::new();
    let towed = cases::towed_sphere(gpu, &sphere_case(c, 0.0));
    protocol::say!("lbm-server: moving-boundary: {} {towed:?}", c.operator);
    for &shift in c.shifts {
        let held = cases::held_sphere(gpu, &sphere_case(c, shift));
        protocol::say!("lbm-server: moving-boundary: {} {held:?}", c.operator);
        if let Some(gap) = write_towed_row(t, c, shift, &held, &towed) {
            rows.push(TowedRow {
                operator: c.operator,
                reynolds: c.reynolds,
                seed_weighting: c.seed_weighting,
                gap,
            });
        }
    }
    rows
}

/// The diameter of the sphere of [`HELD_AND_TOWED`], in cells.
const TOWED_DIAMETER: f64 = 6.0;

/// The sphere of the comparison `c`, moved downstream by `shift` cells.
fn sphere_case(c: &HeldAndTowed, shift: f64) -> cases::HeldSphere {
    cases::HeldSphere {
        reynolds: c.reynolds,
        diameter: TOWED_DIAMETER,
        width: 36,
        length: 60,
        tau: Some(c.tau),
        drawn_larger: 0.0,
        operator: operator_named(c.operator, c.tau),
        imb: crate::lbm::imb::ImbOptions {
            seed_weighting: c.seed_weighting,
            ..Default::default()
        },
        shift,
    }
}

/// Writes the row of the comparison `c` at `shift` to `t`: the held and towed drags and their
/// gap, which it returns; where either run failed, what failed, and None.
fn write_towed_row(
    t: &mut String,
    c: &HeldAndTowed,
    shift: f64,
    held: &Result<cases::SphereDrag, String>,
    towed: &Result<cases::TowedDrag, String>,
) -> Option<f64> {
    let weighting = if c.seed_weighting {
        "seed"
    } else {
        "Noble-Torczynski"
    };
    let layer = TOWED_DIAMETER / c.reynolds.sqrt();
    let (held, towed) = match (held, towed) {
        (Ok(h), Ok(t)) => (h, t),
        _ => {
            let _ = writeln!(
                t,
                "| {} | {weighting} | {} | {layer:.2} | {} | | {shift} | {held:?} | {towed:?} | | |",
                c.operator, c.reynolds, c.tau
            );
            return None;
        }
    };
    let gap = towed.cd / held.cd - 1.0;
    let _ = writeln!(
        t,
        "| {} | {weighting} | {} | {layer:.2} | {} | {:.4} | {shift} | {:.3} | {:.3} | {:.3} | {:+.1}% |",
        c.operator,
        c.reynolds,
        c.tau,
        held.u0,
        held.cd,
        towed.cd_early,
        towed.cd,
        100.0 * gap
    );
    Some(gap)
}

/// The figures of the held-and-towed table: the gap by operator at E4's Reynolds number and by
/// Reynolds number for TRT 3/16.
fn towed_summary(rows: &[TowedRow]) -> String {
    let list = |keep: &dyn Fn(&TowedRow) -> bool| -> String {
        let gaps: Vec<String> = rows
            .iter()
            .filter(|r| keep(r))
            .map(|r| format!("{:+.1}%", 100.0 * r.gap))
            .collect();
        gaps.join(", ")
    };
    let at_e4 = |op: &'static str| {
        move |r: &TowedRow| r.operator == op && r.reynolds == E4_REYNOLDS && !r.seed_weighting
    };
    let mut s = format!(
        "\nTowed against held at Re {E4_REYNOLDS}: TRT 3/16 {} (taus and places as listed), TRT 1/4 {}, \
         TRT 1/12 {}, TRT 0.01 {}, BGK {}, MRT {}; TRT 3/16 with the seed's weighting {}.\n",
        list(&at_e4("TRT 3/16")),
        list(&at_e4("TRT 1/4")),
        list(&at_e4("TRT 1/12")),
        list(&at_e4("TRT 0.01")),
        list(&at_e4("BGK")),
        list(&at_e4("MRT")),
        list(&|r| r.seed_weighting),
    );
    let mut by_re: Vec<f64> = rows.iter().map(|r| r.reynolds).collect();
    by_re.dedup();
    let trt: Vec<String> = by_re
        .iter()
        .map(|&re| {
            let gaps = list(&|r| r.operator == "TRT 3/16" && r.reynolds == re && !r.seed_weighting);
            format!("Re {re} ({:.2} boundary-layer cells) {gaps}", 6.0 / re.sqrt())
        })
        .collect();
    let _ = writeln!(s, "TRT 3/16 by Reynolds number: {}.", trt.join("; "));
    s
}

/// The Zick-Homsy array (solid fraction 0.125, radius 4.96 cells) with its sphere at rest and
/// moving through the lattice in Stokes flow, by operator and tau.
fn moving_arrays(gpu: &Arc<Gpu>) -> String {
    let mut t = String::from(
        "\nThe array of \"drag against tau\" (solid fraction 0.125, radius 4.96 cells, box 16^3) with its \
         sphere moving along x through the periodic lattice at 0.03 and 0.06 cells per step, the same body \
         force driving the fluid: Stokes flow depends only on the velocity relative to the sphere, so a \
         boundary that acts the same moving and at rest keeps K. K from the loads and the flux through \
         the plane farthest from the sphere averaged over the last 4 cells of travel.\n\n\
         | operator | tau | velocity | steps | K | K Zick-Homsy | error | against the array at rest |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    let (phi, k_ref) = cases::ZICK_HOMSY[1];
    let n = 16;
    let radius = cases::radius_for(phi, n);
    let runs = [
        ("TRT 3/16", 0.533),
        ("BGK", 0.533),
        ("MRT", 0.533),
        ("TRT 3/16", 0.6),
        ("BGK", 0.6),
        ("TRT 3/16", 0.85),
        ("BGK", 0.85),
        ("TRT 3/16", 1.2),
    ];
    let mut largest = 0.0f64;
    for (name, tau) in runs {
        let mut at_rest = f64::NAN;
        for velocity in [0.0, 0.03, 0.06] {
            let op = operator_named(name, tau);
            let drag =
                cases::moving_array_drag(gpu, n, [radius, radius], tau, op, Default::default(), velocity);
            protocol::say!("lbm-server: moving-boundary: {name} {tau} {velocity} {drag:?}");
            if velocity == 0.0 {
                at_rest = drag.k;
            }
            let change = drag.k / at_rest - 1.0;
            largest = largest.max(change.abs());
            let _ = writeln!(
                t,
                "| {name} | {tau} | {velocity} | {} | {:.3} | {k_ref:.3} | {:+.1}% | {:+.1}% |",
                drag.steps,
                drag.k,
                100.0 * (drag.k / k_ref - 1.0),
                100.0 * change
            );
        }
    }
    let _ = writeln!(
        t,
        "\nMoving changes the array's K by at most {:.1}% (every operator and tau above).",
        100.0 * largest
    );
    t
}

#[cfg(test)]
mod tests {
    use super::super::report_section;
    use super::{towed_summary, TowedRow, E4_REYNOLDS, HELD_AND_TOWED};

    /// The held-and-towed rows of the report's moving-boundary section are the comparisons of
    /// `HELD_AND_TOWED`, each held sphere's place in turn, in that order.
    #[test]
    fn the_moving_boundary_section_holds_the_comparisons_run() {
        let section = report_section("## Immersed moving boundary: the sphere at rest and moving");
        let rows: Vec<String> = section
            .lines()
            .filter(|l| l.split(" | ").count() == 11 && !l.starts_with("| operator"))
            .map(|l| {
                let cells: Vec<&str> = l.split(" | ").collect();
                [cells[0], cells[1], cells[2], cells[4], cells[6]].join(" | ")
            })
            .collect();
        let cases: Vec<String> = HELD_AND_TOWED
            .iter()
            .flat_map(|c| {
                let weighting = if c.seed_weighting {
                    "seed"
                } else {
                    "Noble-Torczynski"
                };
                c.shifts.iter().map(move |shift| {
                    format!(
                        "| {} | {weighting} | {} | {} | {shift}",
                        c.operator, c.reynolds, c.tau
                    )
                })
            })
            .collect();
        assert_eq!(rows, cases);
    }

    /// The summary lists each operator's gaps at E4's Reynolds number and TRT 3/16's by
    /// Reynolds number, with the boundary-layer cells at 6 cells per diameter.
    #[test]
    fn the_towed_summary_lists_the_gaps_by_operator_and_reynolds_number() {
        let row = |operator, reynolds, seed_weighting, gap| TowedRow {
            operator,
            reynolds,
            seed_weighting,
            gap,
        };
        let summary = towed_summary(&[
            row("TRT 3/16", E4_REYNOLDS, false, 0.064),
            row("TRT 3/16", E4_REYNOLDS, false, 0.065),
            row("BGK", E4_REYNOLDS, false, -0.004),
            row("TRT 3/16", E4_REYNOLDS, true, 0.063),
            row("TRT 3/16", 10.0, false, 0.009),
            row("BGK", 10.0, false, -0.008),
        ]);
        assert!(summary.contains("TRT 3/16 +6.4%, +6.5% (taus"), "{summary}");
        assert!(summary.contains("BGK -0.4%, MRT ;"), "{summary}");
        assert!(summary.contains("seed's weighting +6.3%"), "{summary}");
        assert!(
            summary.contains(
                "Re 32.2 (1.06 boundary-layer cells) +6.4%, +6.5%; Re 10 (1.90 boundary-layer cells) +0.9%."
            ),
            "{summary}"
        );
    }
}
