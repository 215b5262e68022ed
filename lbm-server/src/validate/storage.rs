//! `lbm-server validate --only storage`: the lattice's validation cases with each storage of the
//! populations (`lattice.storage`), each against the same case in FP32: Poiseuille flow between
//! plates and in a duct, the Taylor-Green decay, the Zick-Homsy array's drag, at their usual speeds
//! and down to where 16 bits lose the flow (low Mach), and a closed box's mass over a long run.
//! Writes the section and its figures as JSON (`storage_lattice.json` beside REPORT.md).

use super::TRT;
use crate::lbm::cases;
use crate::lbm::geometry::Operator;
use crate::lbm::gpu::Gpu;
use crate::lbm::storage::Storage;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;
use std::sync::Arc;

/// One case measured in each storage (in the order of [`Storage::ALL`]).
#[derive(Serialize)]
struct Measured {
    case: String,
    quantity: &'static str,
    /// The flow's lattice speed (centre line, or the mean through the array), FP32's.
    lattice_speed: f64,
    fp32: f64,
    fp16s: f64,
    fp16c: f64,
}

impl Measured {
    fn new(case: String, quantity: &'static str, run: impl Fn(Storage) -> (f64, f64)) -> Measured {
        let [(fp32, lattice_speed), (fp16s, _), (fp16c, _)] = Storage::ALL.map(&run);
        Measured {
            case,
            quantity,
            lattice_speed,
            fp32,
            fp16s,
            fp16c,
        }
    }

    /// The row: case, quantity, speed, the three values, each 16-bit one against FP32.
    fn row(&self) -> String {
        let against = |x: f64| format!("{:+.3}%", 100.0 * (x / self.fp32 - 1.0));
        format!(
            "| {} | {} | {:.2e} | {:.6} | {:.6} | {:.6} | {} | {} |\n",
            self.case,
            self.quantity,
            self.lattice_speed,
            self.fp32,
            self.fp16s,
            self.fp16c,
            against(self.fp16s),
            against(self.fp16c)
        )
    }
}

/// The mass of the closed box after some steps, in each storage.
#[derive(Serialize)]
struct Drift {
    steps: u64,
    fp32: f64,
    fp16s: f64,
    fp16c: f64,
}

#[derive(Serialize)]
struct Record<'a> {
    about: &'static str,
    cases: &'a [Measured],
    low_mach: &'a [Measured],
    mass: &'a [Drift],
}

const HEADER: &str = "| case | quantity | lattice speed | FP32 | FP16S | FP16C | FP16S against FP32 | \
                      FP16C against FP32 |\n|---|---|---:|---:|---:|---:|---:|---:|\n";

/// Centre-line speeds of the low-Mach series between plates.
const PLATE_SPEEDS: [f64; 7] = [0.1, 0.03, 0.01, 0.003, 0.001, 3e-4, 1e-4];
/// Body forces of the low-Mach series through the array (1e-6 is the array-drag sections').
const ARRAY_FORCES: [f64; 5] = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7];
/// The steps after which the closed box's mass is read.
const MASS_STEPS: [u64; 3] = [1_000, 10_000, 30_000];

pub(super) fn section(gpu: &Arc<Gpu>, out: &Path) -> String {
    let cases = usual_speeds(gpu);
    let low_mach = low_mach(gpu);
    let mass = mass(gpu);
    let record = Record {
        about: "lbm-server validate --only storage: each case in each storage of the populations \
                (validation/lbm/REPORT.md, \"Storage of the populations\"); lattice units",
        cases: &cases,
        low_mach: &low_mach,
        mass: &mass,
    };
    let json = serde_json::to_string(&record).expect("JSON") + "\n";
    if let Err(e) =
        std::fs::create_dir_all(out).and_then(|()| std::fs::write(out.join("storage_lattice.json"), json))
    {
        protocol::say!("lbm-server: error: {}: {e}", out.display());
    }
    let table = |rows: &[Measured]| HEADER.to_string() + &rows.iter().map(Measured::row).collect::<String>();
    let mut t = format!(
        "\n## Storage of the populations: FP16S and FP16C against FP32\n\nEach case in each \
         `lattice.storage` (docs/lbm.md, \"Storage\"), the arithmetic f32 in all three; the 16-bit \
         runs against the FP32 run of the same case. The lattice speed is FP32's centre-line speed \
         (the channels, the vortex's u0) or mean speed through the array. The figures are also in \
         validation/lbm/storage_lattice.json.\n\nAt the cases' usual speeds:\n\n{}\n\
         The vortex is a low-Mach case too: over the 1000 steps fitted its speed decays from 9.2e-3 \
         to 4.9e-6 (exp(-2 nu k^2 t)), and the 16-bit runs decay too slowly once it is slow.\n\n\
         Down to low Mach: Poiseuille flow between plates (16 cells, TRT, tau 0.6) by centre-line \
         speed, and the Zick-Homsy array (solid fraction 0.125, box 16, TRT, tau 1) by driving \
         force. A flow's populations differ from rest by about w_i 3 c_i.u; below 2^-14 (6.1e-5) both \
         formats keep them in fixed steps, 2^-24 (FP16S) or 2^-25 (FP16C), and a flow a few such steps from rest is lost: FP16S from a lattice speed of \
         about 1e-4, FP16C about ten times slower.\n\n{}\n\
         Mass of the closed 16^3 box with a moving lid (lattice speed 0.05, TRT, tau 0.6, random \
         initial populations) over a long run: rounding to 16 bits does not conserve mass exactly; the \
         16-bit drift grows while the lid's flow develops and stays once it is steady, FP32's grows \
         with the steps (1.5e-8 per 1000).\n\n\
         | steps | FP32 relative drift | FP16S relative drift | FP16C relative drift |\n|---:|---:|---:|---:|\n",
        table(&cases),
        table(&low_mach)
    );
    for d in &mass {
        let _ = writeln!(
            t,
            "| {} | {:.3e} | {:.3e} | {:.3e} |",
            d.steps, d.fp32, d.fp16s, d.fp16c
        );
    }
    t
}

/// The channels, the vortex and the array at the speeds of their own sections.
fn usual_speeds(gpu: &Arc<Gpu>) -> Vec<Measured> {
    let plates = |s| {
        let c = cases::poiseuille_plates_stored(gpu, flow(0.6, Operator::Bgk, 0.02, s));
        (c.mean_speed, 0.02)
    };
    let duct = |s| {
        let c = cases::poiseuille_duct_stored(gpu, flow(0.8, Operator::Bgk, 0.02, s));
        (c.mean_speed, 0.02)
    };
    let vortex = |op| {
        move |s| {
            (
                cases::taylor_green_stored(gpu, 32, 0.8, op, 0.02, 1000, s).nu_measured,
                0.02,
            )
        }
    };
    let (phi, _) = cases::ZICK_HOMSY[1];
    let array = |s| {
        let d = cases::zick_homsy_stored(
            gpu,
            16,
            cases::radius_for(phi, 16),
            1.0,
            TRT,
            cases::STOKES_FORCE,
            s,
        );
        (d.k, d.speed)
    };
    vec![
        Measured::new(
            "Poiseuille between plates, 16 cells, BGK, tau 0.6".into(),
            "mean speed",
            plates,
        ),
        Measured::new(
            "Poiseuille in a square duct, 16 cells, BGK, tau 0.8".into(),
            "mean speed",
            duct,
        ),
        Measured::new(
            "Taylor-Green, 32 x 32, BGK, tau 0.8".into(),
            "nu",
            vortex(Operator::Bgk),
        ),
        Measured::new("Taylor-Green, 32 x 32, TRT, tau 0.8".into(), "nu", vortex(TRT)),
        Measured::new(
            "Zick-Homsy array 0.125, box 16, TRT, tau 1, force 1e-6".into(),
            "K",
            array,
        ),
    ]
}

/// The plates by centre-line speed and the array by force, in each storage.
fn low_mach(gpu: &Arc<Gpu>) -> Vec<Measured> {
    let mut rows = Vec::new();
    for u in PLATE_SPEEDS {
        let plates = |s| {
            (
                cases::poiseuille_plates_stored(gpu, flow(0.6, TRT, u, s)).mean_speed,
                u,
            )
        };
        rows.push(Measured::new(
            format!("Poiseuille between plates, centre speed {u}"),
            "mean speed",
            plates,
        ));
    }
    let (phi, _) = cases::ZICK_HOMSY[1];
    for f in ARRAY_FORCES {
        let array = |s| {
            let d = cases::zick_homsy_stored(gpu, 16, cases::radius_for(phi, 16), 1.0, TRT, f, s);
            (d.k, d.speed)
        };
        rows.push(Measured::new(
            format!("Zick-Homsy array, force {f:e}"),
            "K",
            array,
        ));
    }
    rows
}

/// A channel of 16 cells across.
fn flow(tau: f64, operator: Operator, u_max: f64, storage: Storage) -> cases::Flow {
    cases::Flow {
        n: 16,
        tau,
        operator,
        u_max,
        storage,
    }
}

/// The closed box's relative mass drift after each of [`MASS_STEPS`], in each storage.
fn mass(gpu: &Arc<Gpu>) -> Vec<Drift> {
    let [fp32, fp16s, fp16c] =
        Storage::ALL.map(|s| cases::closed_box_mass_stored(gpu, 16, &MASS_STEPS, TRT, s));
    (0..MASS_STEPS.len())
        .map(|k| Drift {
            steps: MASS_STEPS[k],
            fp32: fp32[k].relative_drift,
            fp16s: fp16s[k].relative_drift,
            fp16c: fp16c[k].relative_drift,
        })
        .collect()
}
