//! Lubrication integrated in the DEM's sub-steps: the normal squeeze-film force of a sphere pair
//! or a sphere and a wall across a gap the fluid lattice cannot resolve (below one cell),
//!
//!   F = 6 pi mu R*^2 (1/h - 1/h_c) v_n,   R* = r_i r_j / (r_i + r_j) (sphere-wall: R* = r),
//!
//! along the line of centres (the wall's normal), v_n the approach speed (negative when the gap
//! opens: the film pulls as it pushes, Reynolds' lubrication being linear in v_n), for
//! 0 < gap < h_c, h = max(gap, h_min) with a roughness floor h_min = 1% of R*, h_c the cut-off (one
//! lattice cell: larger gaps the lattice resolves itself). In contact (gap <= 0) the contact law
//! alone acts: its damping stands for the wet restitution.
//!
//! Evaluated at every DEM step with the present gap and velocities (the fluid's held force answers
//! the gap and the velocity of the start of the fluid step), explicitly, like the contact
//! damping: exact while a film carries a steady load, which is what a film mostly does. An
//! explicit damping c is stable for lambda = c dt / m* < 2; the DEM step keeps each sphere's wall
//! film at the roughness floor at lambda <= 1/6 (`step_limit`), which keeps a sphere with twelve
//! pair films at their floor stable too (Gershgorin: 2 x 12 x 1/12 = 2; a pair film of equal
//! spheres is half as stiff per unit mass). A form that decays each film exactly over the step,
//! m* v_n (1 - exp(-lambda)) / dt, was tried first: stable at any step, but its force falls short
//! of the steady load by lambda / (1 - exp(-lambda)): closing times 3-8% short at lambda 0.1-0.4.

use super::V3;
pub use protocol::squeeze_film::MIN_GAP_FRACTION;

/// Largest lambda = c dt / m of a sphere's wall film at the roughness floor that `step_limit`
/// allows.
pub const MAX_FILM_LAMBDA: f64 = 1.0 / 6.0;

/// The squeeze-film law of a fluid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SqueezeFilm {
    /// Dynamic viscosity [Pa s].
    pub viscosity: f64,
    /// Cut-off gap h_c [m]: one lattice cell.
    pub cutoff: f64,
}

impl SqueezeFilm {
    /// Film damping 6 pi mu R*^2 (1/h - 1/h_c) [N s/m] of a gap below the cut-off (0 beyond it
    /// and in contact).
    pub fn damping(&self, r_eff: f64, gap: f64) -> f64 {
        protocol::squeeze_film::film_damping(self.viscosity, r_eff, gap, self.cutoff)
    }

    /// Film force along the separation direction (positive pushes apart) for an approach speed
    /// `approach` (negative: the gap opens).
    pub fn film_force(&self, r_eff: f64, gap: f64, approach: f64) -> f64 {
        self.damping(r_eff, gap) * approach
    }

    /// Force on sphere i of a pair: `d` = x_i - x_j, `dv` = v_i - v_j.
    pub fn pair_force(&self, d: V3, dv: V3, r_sum: f64, r_eff: f64) -> V3 {
        let dist = d.norm();
        if dist == 0.0 || dist - r_sum >= self.cutoff {
            return V3::zeros();
        }
        let n = d / dist;
        n * self.film_force(r_eff, dist - r_sum, -dv.dot(&n))
    }

    /// Longest DEM step that keeps lambda <= `MAX_FILM_LAMBDA` for the wall film of a sphere of
    /// radius r and mass m at the roughness floor (the stiffest film per unit mass the sphere can
    /// have: m*/R* of a pair is never below its smaller sphere's m/r).
    pub fn step_limit(&self, r: f64, m: f64) -> f64 {
        let stiffest = self.damping(r, MIN_GAP_FRACTION * r);
        if stiffest > 0.0 {
            MAX_FILM_LAMBDA * m / stiffest
        } else {
            f64::INFINITY
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    const LUB: SqueezeFilm = SqueezeFilm {
        viscosity: 0.1,
        cutoff: 0.002,
    };

    #[test]
    fn the_film_force_is_reynolds_law() {
        // R* = 5 mm, v_n = 0.02 m/s, h = 0.5 mm: F = 6 pi mu R*^2 (1/h - 1/h_c) v_n.
        let exact = 6.0 * PI * 0.1 * 0.005f64.powi(2) * (1.0 / 0.0005 - 1.0 / 0.002) * 0.02;
        let f = LUB.film_force(0.005, 0.0005, 0.02);
        assert!((f - exact).abs() < 1e-12 * exact, "{f} vs {exact}");
        assert_eq!(LUB.film_force(0.005, 0.0005, -0.02), -f, "pulls as the gap opens");
        assert_eq!(LUB.film_force(0.005, 0.0025, 0.02), 0.0, "beyond the cut-off");
        assert_eq!(LUB.film_force(0.005, -1e-6, 0.02), 0.0, "in contact");
        let floor = LUB.film_force(0.005, 1e-6, 0.02);
        assert_eq!(floor, LUB.film_force(0.005, 0.00005, 0.02), "roughness floor");
    }

    #[test]
    fn the_step_limit_bounds_the_stiffest_film() {
        let (r, m) = (0.005, 1e-3);
        let limit = LUB.step_limit(r, m);
        let lambda = LUB.damping(r, MIN_GAP_FRACTION * r) * limit / m;
        assert!((lambda - MAX_FILM_LAMBDA).abs() < 1e-12, "lambda {lambda}");
        let wider = LUB.damping(r, 0.001) * limit / m;
        assert!(wider < lambda, "a wider gap is softer: {wider}");
    }

    #[test]
    fn a_pair_is_pushed_apart_along_the_line_of_centres() {
        let d = V3::new(0.0101, 0.0, 0.0);
        let f = LUB.pair_force(d, V3::new(-0.02, 0.0, 0.0), 0.01, 0.0025);
        assert!(f.x > 0.0 && f.y == 0.0 && f.z == 0.0, "{f:?}");
        let sliding = LUB.pair_force(d, V3::new(0.0, 0.02, 0.0), 0.01, 0.0025);
        assert_eq!(sliding, V3::zeros(), "no normal approach, no normal film force");
    }
}
