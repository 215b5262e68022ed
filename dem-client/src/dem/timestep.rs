//! Time-step rule and sub-cycling.
//!
//! DEM step: dt = t_c / `dem.dt_divisor` (default 50), t_c the shortest contact time of any pair
//! the scene can form (smallest sphere of each material against each material and each wall).
//! A user step above t_c / 10 is refused. Coupled: k = ceil(dt_fluid / dt) DEM steps per fluid
//! step and dt_dem = dt_fluid / k exactly.

use std::f64::consts::PI;

/// Undamped Hertz contact time at impact velocity v:
/// t_c = 2 I d_max / v, d_max = (15 m* v^2 / (16 Y* sqrt(R*)))^(2/5),
/// I = int_0^1 (1 - x^(5/2))^(-1/2) dx = (2/5) B(2/5, 1/2) = 1.471 638.
pub fn hertz_contact_time(m_eff: f64, r_eff: f64, y_star: f64, v: f64) -> f64 {
    2.0 * HERTZ_INTEGRAL * hertz_max_overlap(m_eff, r_eff, y_star, v) / v
}

/// Largest overlap of an undamped Hertz impact [m].
pub fn hertz_max_overlap(m_eff: f64, r_eff: f64, y_star: f64, v: f64) -> f64 {
    (15.0 * m_eff * v * v / (16.0 * y_star * r_eff.sqrt())).powf(0.4)
}

/// (2/5) B(2/5, 1/2).
pub const HERTZ_INTEGRAL: f64 = 1.471_637_592;

/// Contact time of an unclamped linear spring-dashpot, t_c = pi / sqrt(k/m* - (gamma / 2m*)^2)
/// (the undamped one, pi sqrt(m*/k), when overdamped).
pub fn linear_contact_time(k_n: f64, gamma_n: f64, m_eff: f64) -> f64 {
    let w2 = k_n / m_eff - (gamma_n / (2.0 * m_eff)).powi(2);
    if w2 > 0.0 {
        PI / w2.sqrt()
    } else {
        PI * (m_eff / k_n).sqrt()
    }
}

/// Restitution of an unclamped linear spring-dashpot, e = exp(-gamma t_c / (2 m*)).
#[cfg_attr(not(test), allow(dead_code))]
pub fn linear_restitution(k_n: f64, gamma_n: f64, m_eff: f64) -> f64 {
    (-gamma_n * linear_contact_time(k_n, gamma_n, m_eff) / (2.0 * m_eff)).exp()
}

/// Sub-cycling: (k, dt_dem) with k = ceil(dt_fluid / dt_max) and dt_dem = dt_fluid / k.
pub fn substeps(dt_fluid: f64, dt_max: f64) -> (u64, f64) {
    let k = ((dt_fluid / dt_max) * (1.0 - 1e-12)).ceil().max(1.0) as u64;
    (k, dt_fluid / k as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hertz_integral_matches_quadrature() {
        // int_0^1 (1 - x^2.5)^-0.5 dx, substituting x = 1 - s^2 to remove the end singularity.
        let n = 2_000_000;
        let h = 1.0 / n as f64;
        let sum: f64 = (0..n)
            .map(|k| {
                let s = (k as f64 + 0.5) * h;
                let x: f64 = 1.0 - s * s;
                2.0 * s / (1.0 - x.powf(2.5)).sqrt() * h
            })
            .sum();
        assert!((sum - HERTZ_INTEGRAL).abs() < 1e-6, "{sum}");
    }

    #[test]
    fn substeps_divide_the_fluid_step_exactly() {
        assert_eq!(substeps(1e-4, 1e-4).0, 1);
        assert_eq!(substeps(1e-4, 3e-5).0, 4);
        assert_eq!(substeps(1e-4, 2e-3).0, 1);
        let (k, dt) = substeps(1e-4, 1.3e-5);
        assert_eq!(k, 8);
        assert_eq!(dt * k as f64, 1e-4);
    }
}
