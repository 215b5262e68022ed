//! The lattice against analytic flows: Poiseuille plates and duct, Taylor-Green decay, mass
//! conservation.

use super::super::cases::*;
use super::*;

const MAGIC: f64 = 3.0 / 16.0;

#[test]
fn poiseuille_plates_converge_at_second_order_with_bgk() {
    let g = gpu();
    let runs: Vec<Channel> = [8, 16, 32]
        .iter()
        .map(|&n| poiseuille_plates(&g, n, 0.6, Operator::Bgk, 0.02))
        .collect();
    for pair in runs.windows(2) {
        let p = order(&pair[0], &pair[1]);
        assert!(
            (1.8..2.3).contains(&p),
            "order {p:.2} between {:?} and {:?}",
            pair[0],
            pair[1]
        );
    }
}

#[test]
fn trt_wall_location_is_viscosity_independent_bgk_is_not() {
    let g = gpu();
    let trt = Operator::Trt { magic: MAGIC };
    let taus = [0.6, 1.0, 2.0];
    let trt_err: Vec<f64> = taus
        .iter()
        .map(|&t| poiseuille_plates(&g, 16, t, trt, 0.02).l2_error)
        .collect();
    let bgk_err: Vec<f64> = taus
        .iter()
        .map(|&t| poiseuille_plates(&g, 16, t, Operator::Bgk, 0.02).l2_error)
        .collect();
    // TRT with Lambda = 3/16 keeps the wall half-way at every tau: what remains is far below BGK.
    assert!(trt_err.iter().all(|e| *e < 2e-4), "TRT errors {trt_err:?}");
    // BGK's wall moves with tau: its error grows by far more than 10x from tau 0.6 to 2.
    assert!(bgk_err[2] > 10.0 * bgk_err[0], "BGK errors {bgk_err:?}");
    assert!(
        bgk_err[2] > 100.0 * trt_err[2],
        "BGK {bgk_err:?} vs TRT {trt_err:?}"
    );
}

#[test]
fn square_duct_converges_at_second_order() {
    let g = gpu();
    let runs: Vec<Channel> = [8, 16, 24]
        .iter()
        .map(|&n| poiseuille_duct(&g, n, 0.8, Operator::Bgk, 0.02))
        .collect();
    for pair in runs.windows(2) {
        let p = order(&pair[0], &pair[1]);
        assert!(
            (1.7..2.4).contains(&p),
            "order {p:.2} between {:?} and {:?}",
            pair[0],
            pair[1]
        );
    }
}

#[test]
fn taylor_green_decay_gives_the_viscosity_within_one_percent() {
    let g = gpu();
    for op in [
        Operator::Bgk,
        Operator::Trt { magic: MAGIC },
        Operator::Mrt {
            rates: Rates::dhumieres(1.0 / 0.8),
        },
    ] {
        let d = taylor_green(&g, 32, 0.8, op, 0.02, 1000);
        assert!(d.relative_error < 0.01, "{}: {d:?}", op.name());
    }
}

#[test]
fn mass_is_conserved_to_round_off_over_10000_steps() {
    let m = closed_box_mass(&gpu(), 12, 10_000, Operator::Trt { magic: MAGIC });
    assert!(m.relative_drift < 1e-6, "{m:?}");
}
