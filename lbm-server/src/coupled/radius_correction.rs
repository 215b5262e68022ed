//! `coupling.radius_correction = "calibrated"`: each sphere drawn larger by the hydrodynamic
//! radius deficit measured at the lattice's tau ([`RADIUS_DEFICIT`]), scaled as 1 / radius.

use super::accuracy::{deficit_radius, measured_at, operator_index, RADIUS_DEFICIT};

/// The smallest radius (cells) whose deficit the correction scales to (1 / radius).
const MIN_DEFICIT_RADIUS: f64 = 2.0;

/// Largest tau of the calibration per operator (BGK, TRT, MRT): BGK's deficit grows too fast
/// beyond tau 1 for the calibration's one secant step (drawn with it, the array's drag is 5.3%
/// high at tau 1.5 and 14.3% at 2; TRT and MRT within 1.8%).
const CALIBRATED_TAU: [f64; 3] = [1.0, 2.0, 2.0];

/// `coupling.radius_correction` as the product deficit x radius (cells^2): a sphere of r cells is
/// drawn r + product / max(r, 2). 0 for "none"; for "calibrated" the measured deficit at the lattice's
/// tau times its radius (refused beyond the operator's calibrated taus).
pub(super) fn radius_deficit_product(correction: &str, operator: &str, tau: f64) -> Result<f64, String> {
    if correction != "calibrated" {
        return Ok(0.0);
    }
    let k = operator_index(operator);
    let limit = k.map_or(0.0, |k| CALIBRATED_TAU[k]);
    match measured_at(&RADIUS_DEFICIT, operator, tau) {
        Some(deficit) if tau <= limit => Ok(deficit * deficit_radius()),
        _ => Err(format!(
            "coupling.radius_correction = \"calibrated\": lattice tau = {tau:.3} is beyond the \
             calibrated taus of {operator} (up to {limit}; validation/lbm/REPORT.md, \"hydrodynamic \
             radius deficit against tau\"): lower lattice.mach (or raise lattice.velocity_scale) or set \
             lattice.tau"
        )),
    }
}

/// How much larger (cells) a sphere of `radius` cells is drawn for the deficit product
/// `product` (cells^2, [`radius_deficit_product`]); below [`MIN_DEFICIT_RADIUS`], where nothing
/// was measured, the deficit of that radius.
pub(super) fn drawn_larger_by(product: f64, radius: f64) -> f64 {
    if product == 0.0 {
        return 0.0;
    }
    product / radius.max(MIN_DEFICIT_RADIUS)
}

/// How much larger (cells) `coupling.radius_correction = "calibrated"` draws a sphere of
/// `radius` cells on a lattice of `operator` at `tau`.
pub(crate) fn calibrated_drawn_larger(operator: &str, tau: f64, radius: f64) -> Result<f64, String> {
    Ok(drawn_larger_by(
        radius_deficit_product("calibrated", operator, tau)?,
        radius,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_calibrated_correction_draws_the_measured_deficit() {
        let product = |op, tau| radius_deficit_product("calibrated", op, tau);
        assert_eq!(radius_deficit_product("none", "trt", 1.7), Ok(0.0));
        let trt = product("trt", 1.0).unwrap();
        assert!((trt / deficit_radius() - 0.192).abs() < 1e-12, "{trt}");
        let below = product("mrt", 0.52).unwrap();
        assert!(
            (below / deficit_radius() + 0.036).abs() < 1e-12,
            "below the table: its first row"
        );
        let err = product("mrt", 2.4).unwrap_err();
        assert!(
            err.contains("coupling.radius_correction") && err.contains("tau = 2.400"),
            "{err}"
        );
        assert!(product("bgk", 1.2).unwrap_err().contains("of bgk (up to 1;"));
        let held = calibrated_drawn_larger("trt", 1.0, 4.0).unwrap();
        assert!(
            (held - trt / 4.0).abs() < 1e-12,
            "a held sphere of 4 cells: {held}"
        );
    }
}
