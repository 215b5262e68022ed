//! The GPU kernels with 16-bit storage (`lattice.storage`) against the f64 reference step, on
//! random populations: each step is compared with the reference step taken from the populations
//! the GPU holds before it (as stored, so rounded), and may differ by the FP32 kernels' tolerance
//! plus the format's rounding of the value stored (`Storage::rounding_bound`: half a step, 2^-11
//! relative for FP16S, 2^-12 for FP16C, half the subnormal step near zero). And tiny flows in each
//! 16-bit storage against the same flow in FP32.

use super::cases;
use super::geometry::{Cell, Operator, Setup};
use super::gpu::{GpuLattice, Health};
use super::imb::{CoveredCells, ImbOptions};
use super::random::random_populations;
use super::reference;
use super::storage::{Storage, StorageOnDevice};
use super::tests::immersed_boundary::{trt_under_a_moving_lid, two_particles};
use super::tests::{bgk_periodic_with_force, gpu, mrt_inlet_outlet_and_solids, trt_walls_and_solids};

/// FP32 kernels' bound for one step (lbm/tests/mod.rs's TOLERANCE).
const TOLERANCE: f64 = 64.0 * f32::EPSILON as f64 * 0.35;

/// Largest |got - want| beyond what storing `want` in `storage` may round.
fn excess(got: &[Cell], want: &[Cell], storage: Storage) -> f64 {
    got.iter()
        .zip(want)
        .flat_map(|(x, y)| x.iter().zip(y))
        .map(|(g, w)| (g - w).abs() - storage.rounding_bound(w.abs() + TOLERANCE))
        .fold(0.0, f64::max)
}

/// The 16-bit storages.
const SIXTEEN: [Storage; 2] = [Storage::Fp16s, Storage::Fp16c];

/// Two steps (odd and even AA phases) of `setup` in each 16-bit storage, each against the
/// reference step from what the GPU holds; the upload stores each population rounded once.
fn check(setup: Setup, seed: u64) {
    for storage in SIXTEEN {
        let setup = Setup {
            storage,
            ..setup.clone()
        };
        let f0 = random_populations(&setup, seed);
        let mut lattice = GpuLattice::new(gpu(), setup.clone(), Health::default(), None).unwrap();
        lattice.set_populations(&f0);
        let mut f = lattice.populations();
        let upload = excess(&f, &f0, storage);
        assert!(
            upload <= 0.0,
            "{storage:?}: the upload rounds beyond the format by {upload:e}"
        );
        for step in 1..=2 {
            let want = reference::step(&setup, &f);
            lattice.step(1);
            f = lattice.populations();
            let err = excess(&f, &want, storage);
            assert!(
                err < TOLERANCE,
                "{storage:?} {}: step {step} differs by {err:e} beyond the format's rounding",
                setup.operator.name()
            );
        }
    }
}

#[test]
fn sixteen_bit_bgk_periodic_with_body_force_matches_reference() {
    // An odd number of cells: the last word holds one cell.
    check(bgk_periodic_with_force([7, 5, 5]), 1);
}

#[test]
fn sixteen_bit_trt_walls_moving_wall_and_solids_match_reference() {
    check(trt_walls_and_solids([8, 7, 6]), 3);
}

#[test]
fn sixteen_bit_mrt_inlet_outlet_and_solids_match_reference() {
    check(mrt_inlet_outlet_and_solids(), 5);
}

/// The coupling's passes (the covered cells' own kernels, each way) read and write the
/// populations through the same pair: two overlapping moving spheres, each way and 16-bit storage,
/// populations and loads against the reference step from what the GPU holds.
#[test]
fn sixteen_bit_coupled_steps_match_reference() {
    let base = trt_under_a_moving_lid();
    let particles = two_particles;
    for storage in SIXTEEN {
        for covered_cells in CoveredCells::DEFINITE {
            let setup = Setup {
                storage,
                ..base.clone()
            };
            let options = ImbOptions {
                covered_cells,
                ..ImbOptions::default()
            };
            let mut lattice =
                GpuLattice::new(gpu(), setup.clone(), Health::default(), Some(options)).unwrap();
            lattice.set_populations(&random_populations(&setup, 11));
            for (step, shift) in [0.0, 0.37, 0.81].into_iter().enumerate() {
                let f = lattice.populations();
                let (next, want) = reference::step_with_particles(&setup, &f, &particles(shift), options);
                let got = lattice.step_coupled(&particles(shift)).unwrap();
                let scale = want
                    .iter()
                    .flat_map(|l| l.force)
                    .fold(0.0, |m: f64, v| m.max(v.abs()));
                let err = got
                    .iter()
                    .zip(&want)
                    .flat_map(|(g, w)| {
                        (0..3).flat_map(move |k| [g.force[k] - w.force[k], g.torque[k] - w.torque[k]])
                    })
                    .fold(0.0, |m: f64, d| m.max(d.abs()));
                assert!(
                    scale > 1e-3 && err < 1e-4 * scale.max(1.0),
                    "{storage:?} {covered_cells:?} step {step}: loads differ by {err:e}"
                );
                let pop = excess(&lattice.populations(), &next, storage);
                assert!(
                    pop < TOLERANCE,
                    "{storage:?} {covered_cells:?} step {step}: populations differ by {pop:e}"
                );
            }
        }
    }
}

/// Tiny flows in each 16-bit storage against the same flow in FP32: Poiseuille flow between plates
/// (16 cells, BGK, tau 0.6, centre speed 0.02) keeps its mean speed within PLATES_BOUND (the
/// 16-bit storages' target, 0.5%) of FP32's, and the Taylor-Green vortex (16 x 16, TRT, tau 0.6, u0
/// 0.02 decaying to 0.002 over the 200 steps fitted) its viscosity within VORTEX_BOUND.
/// Measured on lavapipe: plates +0.24% FP16S, +0.22% FP16C; vortex -0.014%, +0.018%. Slower flows
/// lose more (validation/lbm/REPORT.md, "Storage of the populations").
#[test]
fn sixteen_bit_tiny_flows_match_fp32() {
    const PLATES_BOUND: f64 = 5e-3;
    const VORTEX_BOUND: f64 = 1e-3;
    let g = gpu();
    let plates = |storage| {
        let flow = cases::Flow {
            n: 16,
            tau: 0.6,
            operator: Operator::Bgk,
            u_max: 0.02,
            storage,
        };
        cases::poiseuille_plates_stored(&g, flow).mean_speed
    };
    let trt = Operator::Trt { magic: 3.0 / 16.0 };
    let vortex = |s| cases::taylor_green_stored(&g, 16, 0.6, trt, 0.02, 200, s).nu_measured;
    let (plates32, vortex32) = (plates(Storage::Fp32), vortex(Storage::Fp32));
    for storage in SIXTEEN {
        let plates = plates(storage) / plates32 - 1.0;
        let vortex = vortex(storage) / vortex32 - 1.0;
        assert!(
            plates.abs() < PLATES_BOUND && vortex.abs() < VORTEX_BOUND,
            "{storage:?}: plates {plates:+e}, vortex {vortex:+e}"
        );
    }
}
