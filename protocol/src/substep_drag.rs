//! The sub-step drag of PROTOCOL.md 3.2: how fast the immersed boundary's force answers a sphere's
//! velocity within a fluid step, the fluid state held. One definition for dem-client's sub-steps
//! and the external DEMs' native helper (clients/native).

/// The drag coefficients (c, c_r) of a sphere of radius `r` [m]: its solid term drives the fluid
/// of the covered cells to the sphere's velocity every step, so dF/dv = -sum_cells B rho dx^3 / dt,
/// about the fluid mass the sphere covers per fluid step, c = rho_f V / dt [N s/m]; for the torque
/// c_r = rho_f (2/5) V r^2 / dt [N m s]. `covered_mass_rate` is rho_f / dt_fluid [kg/m^3/s] (0: the
/// force is held constant over the fluid step). The DEM applies F_n - c (v(t) - v_n - a t), a the
/// acceleration of the held force, gravity and the previous step's mean contact force: the fluid's
/// answer to what the contacts change.
pub fn substep_drag(covered_mass_rate: f64, r: f64) -> (f64, f64) {
    let drag = covered_mass_rate * 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
    (drag, 0.4 * drag * r * r)
}
