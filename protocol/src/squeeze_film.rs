//! The squeeze-film law of PROTOCOL.md 4.5: the normal lubrication force the lattice misses across
//! a gap below one cell, F = c v_n with c = 6 pi mu R*^2 (1/h - 1/h_c). One definition for the
//! fluid's held correction (lbm-server) and the film dem-client integrates in its sub-steps.

/// Roughness floor of the gap, as a fraction of the reduced radius.
pub const MIN_GAP_FRACTION: f64 = 0.01;

/// Film damping c = 6 pi mu R*^2 (1/h - 1/h_c) [N s/m] of a gap 0 < gap < cutoff, h =
/// max(gap, MIN_GAP_FRACTION R*); 0 in contact and beyond the cut-off. SI units.
pub fn film_damping(viscosity: f64, r_eff: f64, gap: f64, cutoff: f64) -> f64 {
    if gap <= 0.0 || gap >= cutoff {
        return 0.0;
    }
    let h = gap.max(MIN_GAP_FRACTION * r_eff);
    6.0 * std::f64::consts::PI * viscosity * r_eff * r_eff * (1.0 / h - 1.0 / cutoff)
}
