//! `lbm-server validate --only stability`: where each collision operator stops holding a
//! sphere's wake as tau nears 1/2 (the seed paper's fluidized bed diverged at Re 400 with BGK).

use super::operator_named;
use crate::lbm::cases::{self, schiller_naumann, Faces, HeldSphere, Stability};
use crate::lbm::geometry::{tau_minus, Operator};
use crate::lbm::gpu::Gpu;
use std::fmt::Write as _;
use std::sync::Arc;

/// The operators compared, by the names of [`operator_named`].
pub(super) const OPERATORS: [&str; 6] = [
    "BGK",
    "TRT 3/16",
    "TRT 1/4",
    "TRT 0.01",
    "TRT 3/16 (tau- <= 1)",
    "MRT",
];
/// The Reynolds numbers (u0 d / nu) of the held sphere.
pub(super) const REYNOLDS: [f64; 4] = [100.0, 200.0, 400.0, 800.0];
/// Sphere diameter, box width and length (cells): the sphere-drag section's box at Re 50.
const DIAMETER: f64 = 8.0;
const WIDTH: usize = 48;
const LENGTH: usize = 80;
/// Passes of the stream through the box each run lasts.
const PASSES: f64 = 3.0;
/// The faces of each set of runs: the periodic box (the operator and the sphere alone), then
/// the box with inlet and outlet (the boundaries of a fluidized bed too).
pub(super) const FACES: [(Faces, &str); 2] = [(Faces::Periodic, "periodic"), (Faces::Open, "inlet-outlet")];

/// The held sphere of one row: Re, operator (by name), at [`cases::STREAM_VELOCITY`].
fn case(reynolds: f64, operator: &str) -> HeldSphere {
    let tau = 0.5 + 3.0 * cases::STREAM_VELOCITY * DIAMETER / reynolds;
    HeldSphere {
        reynolds,
        diameter: DIAMETER,
        width: WIDTH,
        length: LENGTH,
        tau: Some(tau),
        drawn_larger: 0.0,
        operator: operator_named(operator, tau),
        imb: Default::default(),
        shift: 0.0,
    }
}

/// TRT's antisymmetric relaxation time tau- = 1/2 + Lambda / (tau - 1/2), or "".
fn tau_minus_column(operator: &str, tau: f64) -> String {
    match operator_named(operator, tau) {
        Operator::Trt { magic } => format!("{:.2}", tau_minus(magic, tau)),
        _ => String::new(),
    }
}

/// Cells from a face within which an unhealthy cell is said to be at it.
const NEAR: usize = 2;

/// Where a run ended: held, or the place of the first unhealthy cell: the faces it lies within
/// [`NEAR`] cells of, and x from the sphere's centre in diameters.
fn outcome(s: &Stability, faces: Faces) -> String {
    let Some(bad) = s.unhealthy else {
        return "held".into();
    };
    let [x, y, z] = bad.coords;
    let from_sphere = (x as f64 + 0.5 - LENGTH as f64 / 3.0) / DIAMETER;
    let mut on = Vec::new();
    if faces == Faces::Open {
        let near = |q: usize, n: usize| q < NEAR || q + NEAR >= n;
        if x < NEAR {
            on.push("inlet");
        }
        if x + NEAR >= LENGTH {
            on.push("outlet");
        }
        if near(y, WIDTH) || near(z, WIDTH) {
            on.push("side");
        }
    }
    let on = if on.is_empty() {
        String::new()
    } else {
        format!(" ({})", on.join(" + "))
    };
    format!("blew up: ({x}, {y}, {z}){on}, x {from_sphere:+.1} d")
}

pub(super) fn section(gpu: &Arc<Gpu>) -> String {
    let mut t = format!(
        "\n## Stability near tau = 1/2: a held sphere's wake by operator\n\n\
         The seed paper's fluidized bed (BGK, 10 cells per diameter) ran at Re 200 and diverged at Re 400. \
         Here one sphere of {DIAMETER} cells held in a stream in a box of {LENGTH} x {WIDTH} x {WIDTH} \
         cells, its centre at L/3, u0 = {} (Mach 0.14), Noble-Torczynski weighting, tau = 1/2 + 3 u0 d / \
         Re; impulsive start (the fluid everywhere at u0, the sphere at rest). Two sets of faces: \
         **periodic** on all six (no boundary but the sphere: the operator alone; the wake comes round \
         again, a row of spheres 10 d apart, and the stream, not driven, slows as the sphere takes its \
         momentum: \"stream\" is the box's mean u_x at the end against u0), and **inlet-outlet**, the \
         sphere-drag section's box (velocity inlet at x = 0, pressure outlet at x = L, side faces moving \
         with the stream): the boundaries of a fluidized bed too. Each run lasts {PASSES} passes of the \
         stream through the box and checks the lattice every {} steps: the first cell with |rho - 1| > \
         0.5, |u| > 0.4 or a value not finite ends it (\"blew up\", with that cell, the faces it lies within \
         {NEAR} cells of, and its distance downstream of the sphere's centre). C_d over the last pass (mean and range: a \
         shedding wake swings it) against Schiller & Naumann, valid to Re 800, for reading only: the \
         periodic box is a row of spheres and the open box confines (about +4-6% at this width, \
         sphere-drag section). MRT: d'Humieres' rates for the non-hydrodynamic moments. TRT: tau- = 1/2 + \
         Lambda / (tau - 1/2); \"(tau- <= 1)\": Lambda lowered to (tau - 1/2) / 2 where that would \
         exceed 1 (`lattice.max_tau_minus = 1`, here at every Re). The pressure outlet is the equilibrium outflow (docs/lbm.md); with the \
         anti-bounce-back outlet it replaced (2026-12-03, these runs with the code before) BGK blew up at \
         the outlet from Re 100 (by step 1780), MRT from Re 400 (step 2980; Re 200 held) and TRT 0.01 \
         at Re 200, one cell from the outlet.\n\n\
         | faces | operator | Re | tau | tau- | steps | outcome | stream | C_d mean | C_d range | C_d Schiller-Naumann |\n\
         |---|---|---:|---:|---:|---:|---|---:|---:|---:|---:|\n",
        cases::STREAM_VELOCITY,
        cases::STABILITY_CHECK,
    );
    let mut held = Vec::new();
    for (faces, name) in FACES {
        for operator in OPERATORS {
            for re in REYNOLDS {
                let s =
                    cases::sphere_stability(gpu, &case(re, operator), faces, PASSES, cases::STABILITY_CHECK);
                protocol::say!("lbm-server: stability: {name} {operator} Re {re}: {s:?}");
                let drag = s.cd.map_or(" | ".into(), |[mean, low, high]| {
                    format!("{mean:.3} | {low:.3}-{high:.3}")
                });
                let _ = writeln!(
                    t,
                    "| {name} | {operator} | {re} | {:.4} | {} | {} | {} | {:.3} | {drag} | {:.3} |",
                    s.tau,
                    tau_minus_column(operator, s.tau),
                    s.steps,
                    outcome(&s, faces),
                    s.stream,
                    schiller_naumann(re),
                );
                held.push((name, operator, re, s.unhealthy.is_none()));
            }
        }
    }
    t + &summary(&held)
}

/// The Reynolds numbers each operator held and those it blew up at, by faces.
pub(super) fn summary(runs: &[(&str, &str, f64, bool)]) -> String {
    let list = |faces: &str, op: &str, held: bool| -> String {
        let res: Vec<String> = runs
            .iter()
            .filter(|r| r.0 == faces && r.1 == op && r.3 == held)
            .map(|r| r.2.to_string())
            .collect();
        if res.is_empty() {
            "none".into()
        } else {
            res.join(", ")
        }
    };
    let mut t = String::new();
    for (_, faces) in FACES {
        let lines: Vec<String> = OPERATORS
            .iter()
            .map(|op| {
                format!(
                    "{op} held Re {}, blew up at Re {}",
                    list(faces, op, true),
                    list(faces, op, false)
                )
            })
            .collect();
        t += &format!(
            "\n{faces}, {DIAMETER} cells per diameter: {}.\n",
            lines.join("; ")
        );
    }
    t
}

#[cfg(test)]
mod tests {
    use super::super::report_rows;
    use super::{summary, FACES, OPERATORS, REYNOLDS};

    /// The rows of the report's stability section are the runs of `section`: each set of faces,
    /// each operator, each Reynolds number, in that order.
    #[test]
    fn the_stability_section_holds_the_runs() {
        let rows = report_rows("## Stability near tau = 1/2", &["periodic", "inlet-outlet"], 3);
        let runs: Vec<String> = FACES
            .iter()
            .flat_map(|(_, faces)| {
                OPERATORS
                    .iter()
                    .flat_map(move |op| REYNOLDS.iter().map(move |re| format!("| {faces} | {op} | {re}")))
            })
            .collect();
        assert_eq!(rows, runs);
    }

    /// The summary names, per set of faces and operator, the Reynolds numbers held and blown up.
    #[test]
    fn the_summary_lists_what_held_and_what_blew_up() {
        let runs = [
            ("periodic", "BGK", 100.0, true),
            ("periodic", "BGK", 800.0, true),
            ("periodic", "MRT", 400.0, false),
            ("inlet-outlet", "BGK", 100.0, false),
        ];
        let text = summary(&runs);
        assert!(
            text.contains("periodic, 8 cells per diameter: BGK held Re 100, 800, blew up at Re none;"),
            "{text}"
        );
        assert!(text.contains("MRT held Re none, blew up at Re 400"), "{text}");
        assert!(
            text.contains("inlet-outlet, 8 cells per diameter: BGK held Re none, blew up at Re 100;"),
            "{text}"
        );
    }
}
