//! `lbm-server validate`: runs the analytic validation cases of the lattice and writes the
//! measured numbers, the references and the errors to REPORT.md. This file holds the command
//! and the registry of its sections; each section lives in the file of its subject, the report's
//! writing in `report`.

use crate::lbm::geometry::Operator;
use crate::lbm::gpu::Gpu;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;

mod array_drag;
mod bed_drag;
mod channels;
mod conservation;
mod moving_boundary;
mod report;
mod sphere_drag;
mod stability;
mod storage;
mod wake_drag;

#[cfg(test)]
pub(crate) use report::{report_rows, report_section};

#[derive(clap::Args)]
pub struct ValidateArgs {
    /// Folder for REPORT.md.
    #[arg(long, default_value = "validation/lbm")]
    out: PathBuf,
    /// Run only these sections (channel, wall, taylor-green, mass, array-drag,
    /// array-drag-solid-collision, unresolved-drag, drag-tau, radius-deficit, sphere-drag, sphere-correction,
    /// moving-boundary, stability, wake-drag, wake-drag-superposition, bed-drag, random-drag,
    /// random-drag-staircase, momentum, storage; wake-drag-fine and random-drag-fine, a GPU's
    /// grids, only when named), print them and replace them in an existing REPORT.md (the other sections are
    /// kept as they are).
    #[arg(long, value_delimiter = ',')]
    only: Vec<String>,
}

type Section = fn(&Arc<Gpu>) -> String;

/// A section that also writes its figures as JSON into the report's folder.
type Recorded = fn(&Arc<Gpu>, &Path) -> String;

const SECTIONS: [(&str, Section); 21] = [
    ("channel", channels::channel_convergence),
    ("wall", channels::wall_location),
    ("taylor-green", channels::taylor_green),
    ("mass", conservation::mass),
    ("array-drag", array_drag::array_drag),
    (
        "array-drag-solid-collision",
        array_drag::array_drag_solid_collision,
    ),
    ("unresolved-drag", array_drag::unresolved_drag),
    ("drag-tau", array_drag::drag_against_tau),
    ("radius-deficit", array_drag::radius_deficit),
    ("sphere-drag", sphere_drag::sphere_drag),
    ("sphere-correction", sphere_drag::sphere_correction),
    ("moving-boundary", moving_boundary::moving_boundary),
    ("stability", stability::section),
    ("wake-drag", wake_drag::section),
    ("wake-drag-fine", wake_drag::fine_section),
    ("wake-drag-superposition", wake_drag::superposition_section),
    ("bed-drag", bed_drag::section),
    ("random-drag", bed_drag::random_section),
    ("random-drag-fine", bed_drag::random_fine_section),
    ("random-drag-staircase", bed_drag::random_staircase_section),
    ("momentum", conservation::momentum),
];

const RECORDED: [(&str, Recorded); 1] = [("storage", storage::section)];

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
    let names: Vec<&str> = SECTIONS
        .iter()
        .map(|(name, _)| *name)
        .chain(RECORDED.iter().map(|(name, _)| *name))
        .collect();
    if let Some(bad) = args.only.iter().find(|o| !names.contains(&o.as_str())) {
        protocol::say!(
            "lbm-server: error: --only {bad}: no such section (one of {})",
            names.join(", ")
        );
        return ExitCode::FAILURE;
    }
    let path = args.out.join("REPORT.md");
    let mut report = report::start(&path, !args.only.is_empty(), &gpu);
    let chosen = |name: &str| {
        args.only.iter().any(|o| o == name) || (args.only.is_empty() && !GPU_ONLY.contains(&name))
    };
    let run = |report: String, text: String| {
        print!("{text}");
        report::replace_section(&report, &text)
    };
    for (name, section) in SECTIONS {
        if chosen(name) {
            report = run(report, section(&gpu));
        }
    }
    for (name, section) in RECORDED {
        if chosen(name) {
            report = run(report, section(&gpu, &args.out));
        }
    }
    if let Err(e) = std::fs::create_dir_all(&args.out).and_then(|()| std::fs::write(&path, &report)) {
        protocol::say!("lbm-server: error: {}: {e}", args.out.display());
        return ExitCode::FAILURE;
    }
    protocol::say!("lbm-server: wrote {}", path.display());
    ExitCode::SUCCESS
}

/// The operator of a [`moving_boundary::HeldAndTowed`] or array row by its name ("BGK", "MRT",
/// "TRT <magic>"): `bench::parse_operator` with TRT's magic parameter from the name.
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
