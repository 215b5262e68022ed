//! `lbm-server validate`: runs the analytic validation cases of the lattice and writes the
//! measured numbers, the references and the errors to REPORT.md.

use crate::lbm::geometry::Operator;
use crate::lbm::gpu::Gpu;
use crate::lbm::imb::solid_reach;
use crate::lbm::mrt::Rates;
use crate::lbm::validation::{self, Channel};
use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;

mod bed_drag;
mod stability;
mod wake_drag;

#[derive(clap::Args)]
pub struct ValidateArgs {
    /// Folder for REPORT.md.
    #[arg(long, default_value = "validation/lbm")]
    out: PathBuf,
    /// Run only these sections (channel, wall, taylor-green, mass, array-drag,
    /// array-drag-solid-collision, unresolved-drag, drag-tau, radius-deficit, sphere-drag, sphere-correction,
    /// moving-boundary, stability, wake-drag, wake-drag-superposition, bed-drag, random-drag,
    /// random-drag-staircase, momentum; wake-drag-fine and random-drag-fine, a GPU's grids, only
    /// when named), print them and replace them in an existing REPORT.md (the other sections are
    /// kept as they are).
    #[arg(long, value_delimiter = ',')]
    only: Vec<String>,
}

type Section = fn(&Arc<Gpu>) -> String;

const SECTIONS: [(&str, Section); 21] = [
    ("channel", channel_convergence),
    ("wall", wall_location),
    ("taylor-green", taylor_green),
    ("mass", mass),
    ("array-drag", array_drag),
    ("array-drag-solid-collision", array_drag_solid_collision),
    ("unresolved-drag", unresolved_drag),
    ("drag-tau", drag_against_tau),
    ("radius-deficit", radius_deficit),
    ("sphere-drag", sphere_drag),
    ("sphere-correction", sphere_correction),
    ("moving-boundary", moving_boundary),
    ("stability", stability::section),
    ("wake-drag", wake_drag::section),
    ("wake-drag-fine", wake_drag::fine_section),
    ("wake-drag-superposition", wake_drag::superposition_section),
    ("bed-drag", bed_drag::section),
    ("random-drag", bed_drag::random_section),
    ("random-drag-fine", bed_drag::random_fine_section),
    ("random-drag-staircase", bed_drag::random_staircase_section),
    ("momentum", momentum),
];

/// Sections run only when named with --only: grids for a GPU (hours on lavapipe).
const GPU_ONLY: [&str; 2] = ["wake-drag-fine", "random-drag-fine"];

const TRT: Operator = Operator::Trt { magic: 3.0 / 16.0 };

pub fn main(args: ValidateArgs) -> ExitCode {
    let gpu = match Gpu::new() {
        Ok(g) => Arc::new(g),
        Err(e) => {
            protocol::say!("lbm-server: error: {e}");
            return ExitCode::FAILURE;
        }
    };
    let mut report = format!(
        "# Lattice-Boltzmann core: validation report\n\nWritten by `lbm-server validate` on {} ({:?}).\n\
         All quantities in lattice units. Errors are relative L2 norms against the analytic solution.\n",
        gpu.adapter.name, gpu.adapter.backend
    );
    if let Some(bad) = args
        .only
        .iter()
        .find(|o| !SECTIONS.iter().any(|(name, _)| name == *o))
    {
        let names: Vec<&str> = SECTIONS.iter().map(|(name, _)| *name).collect();
        protocol::say!(
            "lbm-server: error: --only {bad}: no such section (one of {})",
            names.join(", ")
        );
        return ExitCode::FAILURE;
    }
    let path = args.out.join("REPORT.md");
    if !args.only.is_empty() {
        match std::fs::read_to_string(&path) {
            Ok(existing) => report = existing,
            Err(e) => protocol::say!(
                "lbm-server: {}: {e}; writing the chosen sections only",
                path.display()
            ),
        }
    }
    for (name, section) in SECTIONS {
        let chosen = args.only.iter().any(|o| o == name);
        if chosen || (args.only.is_empty() && !GPU_ONLY.contains(&name)) {
            let text = section(&gpu);
            print!("{text}");
            report = replace_section(&report, &text);
        }
    }
    if let Err(e) = std::fs::create_dir_all(&args.out).and_then(|()| std::fs::write(&path, &report)) {
        protocol::say!("lbm-server: error: {}: {e}", args.out.display());
        return ExitCode::FAILURE;
    }
    protocol::say!("lbm-server: wrote {}", path.display());
    ExitCode::SUCCESS
}

/// `report` with the section of the same `## ` heading as `section` replaced by it (appended when
/// the report has no such section). A section runs from its heading to the next `## ` heading.
fn replace_section(report: &str, section: &str) -> String {
    let heading = section.lines().find(|l| l.starts_with("## ")).unwrap_or_default();
    let marker = format!("\n{heading}\n");
    match report.find(&marker) {
        Some(start) if !heading.is_empty() => {
            let end = report[start + 1..]
                .find("\n## ")
                .map_or(report.len(), |k| start + 1 + k);
            format!("{}{section}{}", &report[..start], &report[end..])
        }
        _ => format!("{report}{section}"),
    }
}

fn table_of(runs: &[Channel]) -> String {
    let mut t = String::from(
        "| cells across | tau | steps | L2 error | observed order |\n|---:|---:|---:|---:|---:|\n",
    );
    for (k, r) in runs.iter().enumerate() {
        let order = if k == 0 {
            "".to_string()
        } else {
            format!("{:.2}", validation::order(&runs[k - 1], r))
        };
        let _ = writeln!(
            t,
            "| {} | {} | {} | {:.3e} | {order} |",
            r.cells, r.tau, r.steps, r.l2_error
        );
    }
    t
}

fn channel_convergence(gpu: &Arc<Gpu>) -> String {
    let plates: Vec<Channel> = [8, 16, 32, 64]
        .iter()
        .map(|&n| validation::poiseuille_plates(gpu, n, 0.6, Operator::Bgk, 0.02))
        .collect();
    let duct: Vec<Channel> = [8, 16, 24, 32]
        .iter()
        .map(|&n| validation::poiseuille_duct(gpu, n, 0.8, Operator::Bgk, 0.02))
        .collect();
    format!(
        "\n## Poiseuille flow, BGK, half-way bounce-back\n\nBetween plates (body force, centre speed 0.02), \
         against u(y) = 4 u_max y (H - y) / H^2 with the walls half-way between cells:\n\n{}\n\
         At 64 cells the body force per step (8 nu u_max / H^2 = 1.3e-6) is only ~350 f32 ulps of a \
         population (3.7e-9 near 0.05): single-precision round-off sets the floor there, not the scheme.\n\n\
         In a square duct, against the Fourier series solution:\n\n{}\nBoth converge at second order \
         down to that floor.\n",
        table_of(&plates),
        table_of(&duct)
    )
}

fn wall_location(gpu: &Arc<Gpu>) -> String {
    let mut t = String::from(
        "\n## Wall location: TRT (Lambda = 3/16) against BGK\n\nPoiseuille between plates, 16 cells, \
         centre speed 0.02, at several tau. With TRT the error stays 2-5 orders of magnitude below \
         BGK's at every tau (the half-way wall does not move; what remains comes from the second-order \
         forcing terms, O(u F)); BGK's wall moves with tau (exact only near tau = 0.933).\n\n| tau | BGK L2 error | TRT L2 error |\n|---:|---:|---:|\n",
    );
    for tau in [0.55, 0.6, 0.8, 1.0, 1.5, 2.0] {
        let bgk = validation::poiseuille_plates(gpu, 16, tau, Operator::Bgk, 0.02).l2_error;
        let trt = validation::poiseuille_plates(gpu, 16, tau, TRT, 0.02).l2_error;
        let _ = writeln!(t, "| {tau} | {bgk:.3e} | {trt:.3e} |");
    }
    t
}

fn taylor_green(gpu: &Arc<Gpu>) -> String {
    let mut t = String::from(
        "\n## Taylor-Green vortex decay\n\n2D vortex in a periodic 32 x 32 box, u0 = 0.02, tau = 0.8: the kinetic \
         energy decays as exp(-4 nu k^2 t); the viscosity fitted over 1000 steps against (tau - 1/2) / 3.\n\n\
         | operator | nu expected | nu measured | relative error |\n|---|---:|---:|---:|\n",
    );
    let ops = [
        Operator::Bgk,
        TRT,
        Operator::Mrt {
            rates: Rates::dhumieres(1.0 / 0.8),
        },
    ];
    for op in ops {
        let d = validation::taylor_green(gpu, 32, 0.8, op, 0.02, 1000);
        let _ = writeln!(
            t,
            "| {} | {:.6} | {:.6} | {:.3e} |",
            op.name(),
            d.nu_expected,
            d.nu_measured,
            d.relative_error
        );
    }
    t
}

fn mass(gpu: &Arc<Gpu>) -> String {
    let m = validation::closed_box_mass(gpu, 16, 10_000, TRT);
    format!(
        "\n## Mass conservation\n\nClosed 16^3 box with a moving lid (lattice speed 0.05), TRT, tau 0.6, random \
         initial populations, 10,000 steps (FP32 populations stored as f - w_i):\n\n\
         | mass before | mass after | relative drift |\n|---:|---:|---:|\n| {:.9} | {:.9} | {:.3e} |\n",
        m.before, m.after, m.relative_drift
    )
}

fn array_drag(gpu: &Arc<Gpu>) -> String {
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
    for &(phi, k_ref) in &validation::ZICK_HOMSY {
        for n in [12, 16, 24, 32] {
            let d = validation::zick_homsy(gpu, n, validation::radius_for(phi, n), 1.0, TRT);
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
    t += "\nThe same at solid fraction 0.125, box 16 (radius 4.96), by operator, tau and weighting: the \
          immersed boundary's drag depends on tau (a known property of partially saturated cells).\n\n\
          | operator | tau | weighting | K | error |\n|---|---:|---|---:|---:|\n";
    let (phi, k_ref) = validation::ZICK_HOMSY[1];
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
        let d = validation::zick_homsy_with(gpu, 16, validation::radius_for(phi, 16), tau, op, options);
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
fn unresolved_drag(gpu: &Arc<Gpu>) -> String {
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
        let k_ref = validation::sangani_acrivos(c);
        let err = |k: f64| format!("{:+.1}%", 100.0 * (k - k_ref) / k_ref);
        let rest = |op: Operator, tau: f64| err(validation::zick_homsy(gpu, n, radius, tau, op).k);
        let moving = |tau: f64| {
            let options = crate::lbm::imb::ImbOptions::default();
            err(validation::moving_array_drag(gpu, n, [radius; 2], tau, TRT, options, 0.01).k)
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
        let k_ref = validation::sangani_acrivos(c);
        let larger =
            |tau: f64| crate::coupled::calibrated_drawn_larger("trt", tau, radius).expect("calibrated");
        let moving = |tau: f64| {
            let options = crate::lbm::imb::ImbOptions::default();
            let drawn = [radius + larger(tau), radius];
            let k = validation::moving_array_drag(gpu, n, drawn, tau, TRT, options, 0.01).k;
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
fn array_drag_solid_collision(gpu: &Arc<Gpu>) -> String {
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
    for &(phi, k_ref) in &validation::ZICK_HOMSY[1..] {
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
                    let d = validation::zick_homsy_with(
                        gpu,
                        16,
                        validation::radius_for(phi, 16),
                        tau,
                        op,
                        options,
                    );
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
fn drag_against_tau(gpu: &Arc<Gpu>) -> String {
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
    let (phi, k_ref) = validation::ZICK_HOMSY[1];
    for (n, tau, op) in runs_over_tau() {
        let options = crate::lbm::imb::ImbOptions {
            slots: 2,
            ..Default::default()
        };
        let d = validation::zick_homsy_with(gpu, n, validation::radius_for(phi, n), tau, op, options);
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
fn radius_deficit(gpu: &Arc<Gpu>) -> String {
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
    let (phi, k_ref) = validation::ZICK_HOMSY[1];
    for (n, tau, op) in runs_over_tau() {
        let radius = validation::radius_for(phi, n);
        let d = validation::radius_deficit(gpu, n, radius, k_ref, tau, op);
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

fn sphere_drag(gpu: &Arc<Gpu>) -> String {
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
            match validation::fixed_sphere(gpu, re, d, w, l) {
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
        if let Some((cd, p)) = validation::unconfined_drag(&confined) {
            let reference = validation::schiller_naumann(re);
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
const E4_REYNOLDS: f64 = 32.2;
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
fn sphere_correction(gpu: &Arc<Gpu>) -> String {
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
                let drag = match case.and_then(|c| validation::held_sphere(gpu, &c)) {
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
/// ([`validation::towed_sphere`]), against their held C_d.
fn towed_spheres(gpu: &Arc<Gpu>, held: &[validation::SphereDrag]) -> String {
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
            let towed = correction_case(d, tau, (6.0, 10.0), corrected)
                .and_then(|c| validation::towed_sphere(gpu, &c));
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

/// The operator of a [`HeldAndTowed`] or array row by its name ("BGK", "MRT", "TRT <magic>"):
/// `bench::parse_operator` with TRT's magic parameter from the name.
fn operator_named(name: &str, tau: f64) -> Operator {
    let (kind, magic) = name.split_once(' ').unwrap_or((name, "3/16"));
    let operator = crate::bench::parse_operator(&kind.to_lowercase(), tau).expect("operator name");
    match (operator, magic) {
        (Operator::Trt { .. }, "3/16") | (Operator::Bgk | Operator::Mrt { .. }, _) => operator,
        (Operator::Trt { .. }, "1/4") => Operator::Trt { magic: 0.25 },
        (Operator::Trt { .. }, "1/12") => Operator::Trt { magic: 1.0 / 12.0 },
        (Operator::Trt { .. }, bounded) if bounded.contains(" (tau- <= ") => {
            let (magic, max) = bounded
                .trim_end_matches(')')
                .split_once(" (tau- <= ")
                .expect("checked");
            let Operator::Trt { magic } = operator_named(&format!("TRT {magic}"), tau) else {
                unreachable!("a TRT name")
            };
            Operator::Trt {
                magic: scene::lattice::bounded_magic(magic, tau, max.parse().expect("TRT tau- bound")),
            }
        }
        (Operator::Trt { .. }, other) => Operator::Trt {
            magic: other.parse().expect("TRT magic"),
        },
    }
}

/// One measured row of [`moving_boundary`]: towed C_d against held C_d.
struct TowedRow {
    operator: &'static str,
    reynolds: f64,
    seed_weighting: bool,
    gap: f64,
}

/// Whether an immersed boundary acts the same moving as at rest: the sphere held in a stream
/// and towed through fluid at rest ([`validation::held_sphere`], [`validation::towed_sphere`])
/// at 6 cells per diameter, one thing changed at a time; then the Zick-Homsy array moving
/// through the lattice in Stokes flow ([`validation::moving_array_drag`]).
fn moving_boundary(gpu: &Arc<Gpu>) -> String {
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
    let d = 6.0;
    let mut rows = Vec::new();
    for c in &HELD_AND_TOWED {
        let imb = crate::lbm::imb::ImbOptions {
            seed_weighting: c.seed_weighting,
            ..Default::default()
        };
        let case = |shift: f64| validation::HeldSphere {
            reynolds: c.reynolds,
            diameter: d,
            width: 36,
            length: 60,
            tau: Some(c.tau),
            drawn_larger: 0.0,
            operator: operator_named(c.operator, c.tau),
            imb,
            shift,
        };
        let weighting = if c.seed_weighting {
            "seed"
        } else {
            "Noble-Torczynski"
        };
        let layer = d / c.reynolds.sqrt();
        let towed = validation::towed_sphere(gpu, &case(0.0));
        protocol::say!("lbm-server: moving-boundary: {} {towed:?}", c.operator);
        for &shift in c.shifts {
            let held = validation::held_sphere(gpu, &case(shift));
            protocol::say!("lbm-server: moving-boundary: {} {held:?}", c.operator);
            let (held, towed) = match (&held, &towed) {
                (Ok(h), Ok(t)) => (h, t),
                _ => {
                    let _ = writeln!(
                        t,
                        "| {} | {weighting} | {} | {layer:.2} | {} | | {shift} | {held:?} | {towed:?} | | |",
                        c.operator, c.reynolds, c.tau
                    );
                    continue;
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
            rows.push(TowedRow {
                operator: c.operator,
                reynolds: c.reynolds,
                seed_weighting: c.seed_weighting,
                gap,
            });
        }
    }
    t + &towed_summary(&rows) + &moving_arrays(gpu)
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
    let (phi, k_ref) = validation::ZICK_HOMSY[1];
    let n = 16;
    let radius = validation::radius_for(phi, n);
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
            let drag = validation::moving_array_drag(
                gpu,
                n,
                [radius, radius],
                tau,
                op,
                Default::default(),
                velocity,
            );
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

/// The held sphere of [`sphere_correction`]: `d` cells, a box (W, L) in diameters.
fn correction_case(
    d: f64,
    tau: f64,
    (w, l): (f64, f64),
    corrected: bool,
) -> Result<validation::HeldSphere, String> {
    let drawn_larger = if corrected {
        crate::coupled::calibrated_drawn_larger("trt", tau, d / 2.0)?
    } else {
        0.0
    };
    Ok(validation::HeldSphere {
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
fn drag_in_box(rows: &[validation::SphereDrag], (w, l): (f64, f64), corrected: bool) -> Vec<(f64, f64)> {
    rows.iter()
        .filter(|r| (r.width as f64 - w * r.diameter).abs() < 0.5)
        .filter(|r| (r.length as f64 - l * r.diameter).abs() < 0.5)
        .filter(|r| (r.drawn_larger > 0.0) == corrected)
        .map(|r| (r.diameter, r.cd))
        .collect()
}

/// C_d of the row at `d` cells in a box of (W, L) diameters, drawn larger or not.
fn held_drag(rows: &[validation::SphereDrag], b: (f64, f64), corrected: bool, d: f64) -> Option<f64> {
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
fn correction_summary(rows: &[validation::SphereDrag], experiment: f64) -> String {
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
fn box_share(rows: &[validation::SphereDrag]) -> String {
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

fn momentum(gpu: &Arc<Gpu>) -> String {
    let m = validation::momentum_exchange(gpu, 16, 300);
    format!(
        "\n## Immersed moving boundary: momentum conservation\n\nPeriodic 16^3 box, fluid moving at 0.02 \
         along x around a free sphere (radius 16/6, density ratio 2) at rest, 300 steps, the sphere moved \
         with the returned force. Fluid + particle momentum:\n\n| initial | after 300 steps | relative \
         change | particle velocity |\n|---|---|---:|---|\n| {:.6?} | {:.6?} | {:.2e} | {:.5?} |\n",
        m.initial, m.last, m.relative_change, m.particle_velocity
    )
}

/// The section of validation/lbm/REPORT.md under `heading` ("## ..."), up to the next heading.
#[cfg(test)]
pub(crate) fn report_section(heading: &str) -> &'static str {
    include_str!("../../validation/lbm/REPORT.md")
        .split(heading)
        .nth(1)
        .and_then(|rest| rest.split("\n## ").next())
        .unwrap_or_else(|| panic!("the report has no section {heading:?}"))
}

/// The first `columns` cells ("| a | b") of the rows of the report's section `heading` whose
/// first cell starts with one of `starts`: the runs a section test holds against its constants.
#[cfg(test)]
pub(crate) fn report_rows(heading: &str, starts: &[&str], columns: usize) -> Vec<String> {
    report_section(heading)
        .lines()
        .filter(|l| starts.iter().any(|s| l.starts_with(&format!("| {s}"))))
        .map(|l| l.split(" | ").take(columns).collect::<Vec<_>>().join(" | "))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::{
        correction_boxes, correction_summary, replace_section, report_section, runs_over_tau,
        second_order_limit, towed_summary, TowedRow, E4_REYNOLDS, E4_TAUS, HELD_AND_TOWED,
    };

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

    /// The summary reads each box's row: C_d chosen so that every figure is known.
    #[test]
    fn the_correction_summary_reads_the_rows_of_each_box() {
        let row =
            |d: f64, (w, l): (f64, f64), drawn_larger: f64, cd: f64| crate::lbm::validation::SphereDrag {
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

    #[test]
    fn a_section_is_replaced_in_place_and_a_new_one_appended() {
        let report = "# R\n\n## A\n\nold a\n\n## B\n\nb\n";
        let replaced = replace_section(report, "\n## A\n\nnew a\n");
        assert_eq!(replaced, "# R\n\n## A\n\nnew a\n\n## B\n\nb\n");
        let last = replace_section(report, "\n## B\n\nnew b\n");
        assert_eq!(last, "# R\n\n## A\n\nold a\n\n## B\n\nnew b\n");
        let added = replace_section(report, "\n## C\n\nc\n");
        assert_eq!(added, format!("{report}\n## C\n\nc\n"));
    }
}
