//! A sphere: its state, its loads, and its time integration (velocity Verlet, and the exact free
//! flight of a sphere that touches nothing).

use super::V3;

/// One sphere.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Body {
    pub id: u64,
    pub x: V3,
    pub v: V3,
    pub w: V3,
    pub r: f64,
    pub m: f64,
    /// Moment of inertia 2/5 m r^2 [kg m^2].
    pub inertia: f64,
    /// Index into the world's materials.
    pub material: usize,
    /// Contact (and lubrication) force and torque of the last force evaluation.
    pub f: V3,
    pub t: V3,
    /// External (fluid) force and torque.
    pub f_ext: V3,
    pub t_ext: V3,
    /// Linear drag coefficients [N s/m] and [N m s]: the external force and torque follow the
    /// velocity within a held fluid step as F_ext - drag v and T_ext - spin_drag w (0 without a
    /// fluid).
    pub drag: f64,
    pub spin_drag: f64,
    /// Rates of change of f_ext and t_ext over a held fluid step [N/s], [N m/s] (0 without a
    /// fluid): the drag's reference velocity moves with the acceleration the held forces give.
    pub f_ext_rate: V3,
    pub t_ext_rate: V3,
    /// Contact impulse and angular impulse summed over the DEM steps since they were last reset
    /// [N s], [N m s].
    pub contact_impulse: V3,
    pub contact_angular_impulse: V3,
}

impl Body {
    pub fn sphere(id: u64, x: V3, v: V3, w: V3, r: f64, density: f64, material: usize) -> Body {
        let m = density * 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
        Body {
            id,
            x,
            v,
            w,
            r,
            m,
            inertia: 0.4 * m * r * r,
            material,
            f: V3::zeros(),
            t: V3::zeros(),
            f_ext: V3::zeros(),
            t_ext: V3::zeros(),
            drag: 0.0,
            spin_drag: 0.0,
            f_ext_rate: V3::zeros(),
            t_ext_rate: V3::zeros(),
            contact_impulse: V3::zeros(),
            contact_angular_impulse: V3::zeros(),
        }
    }

    /// Velocity change over half_dt by the equations of motion: eq. 12,
    /// a = (f + F_ext - drag v)/m + g, and eq. 13, alpha = (t + T_ext - spin_drag w)/I (f and t
    /// the sums over its contacts of f_ij and l_ij x f_ij, F_ext and T_ext the fluid's F_fluid and
    /// T_fluid).
    fn half_kick(&self, half_dt: f64, g: V3) -> (V3, V3) {
        let f = self.f + self.f_ext - self.drag * self.v;
        let t = self.t + self.t_ext - self.spin_drag * self.w;
        // eq. 12: dv/dt = f / m + g; eq. 13: dw/dt = t / I.
        (half_dt * (f / self.m + g), half_dt * t / self.inertia)
    }

    /// A bound on |dv/dt| over a held fluid step in which the sphere touches nothing: with the
    /// external force F_ext + t F_ext_rate - drag v, v(t) = v_0 + a_r t + u(t), a_r = F_ext_rate /
    /// drag the reference's acceleration and u' = (a_0 - a_r) exp(-drag t / m), a_0 the
    /// acceleration at t = 0; so |dv/dt| <= |a_r| + |a_0 - a_r| (|a_0| without drag).
    pub(super) fn acceleration_bound(&self, g: V3) -> f64 {
        let reference = if self.drag > 0.0 {
            self.f_ext_rate / self.drag
        } else {
            V3::zeros()
        };
        let start = (self.f_ext - self.drag * self.v) / self.m + g;
        reference.norm() + (start - reference).norm()
    }

    /// Moves the sphere over `span` touching nothing, exactly: with a = (F_ext + s F_ext_rate -
    /// drag v) / m + g, v(s) = v_0 + a_r s + (a_0 - a_r) (1 - exp(-lambda s)) / lambda and x(s) =
    /// x_0 + v_0 s + a_r s^2 / 2 + (a_0 - a_r) (s / lambda - (1 - exp(-lambda s)) / lambda^2),
    /// lambda = drag / m, a_r = F_ext_rate / drag (see `acceleration_bound`); the same for the spin
    /// with spin_drag / I (a sphere's orientation is not tracked). Then the external loads are
    /// where k sub-steps would have left them. Eqs. 12-13 with no contact (f_ij = 0), integrated
    /// exactly.
    pub(super) fn fly(&mut self, span: f64, g: V3) {
        let (v0, w0) = (self.v, self.w);
        let (a_r, a_0) = (
            rate_over(self.f_ext_rate, self.drag),
            (self.f_ext - self.drag * v0) / self.m + g,
        );
        let (phi1, phi2) = relaxation_integrals(self.drag / self.m, span);
        self.v = v0 + a_r * span + (a_0 - a_r) * phi1;
        self.x += v0 * span + a_r * (0.5 * span * span) + (a_0 - a_r) * phi2;
        let alpha_r = rate_over(self.t_ext_rate, self.spin_drag);
        let alpha_0 = (self.t_ext - self.spin_drag * w0) / self.inertia;
        let (psi1, _) = relaxation_integrals(self.spin_drag / self.inertia, span);
        self.w = w0 + alpha_r * span + (alpha_0 - alpha_r) * psi1;
        self.f_ext += span * self.f_ext_rate;
        self.t_ext += span * self.t_ext_rate;
    }

    /// v += dt/2 a, w += dt/2 alpha.
    pub(super) fn kick(&mut self, half_dt: f64, g: V3) {
        let (dv, dw) = self.half_kick(half_dt, g);
        self.v += dv;
        self.w += dw;
    }

    /// The end of a force evaluation for this sphere (its contact force and torque `f`, `t` just
    /// summed): the held external loads advance by their rates and the contact impulses add up,
    /// then `finish` integrates eqs. 12-13. Returns the squared displacement since the last
    /// neighbour-list build (at `x0`) after a drift, else 0.
    #[inline(always)]
    pub(super) fn integrate(&mut self, dt: f64, g: V3, finish: Finish, x0: &V3) -> f64 {
        self.f_ext += dt * self.f_ext_rate;
        self.t_ext += dt * self.t_ext_rate;
        self.contact_impulse += dt * self.f;
        self.contact_angular_impulse += dt * self.t;
        match finish {
            Finish::Nothing => 0.0,
            Finish::HalfKick => {
                self.kick(0.5 * dt, g);
                0.0
            }
            Finish::KickDrift => {
                // Two half kicks with the same acceleration (computed once: the same bits).
                let (dv, dw) = self.half_kick(0.5 * dt, g);
                self.v += dv;
                self.w += dw;
                self.v += dv;
                self.w += dw;
                self.x += dt * self.v;
                (self.x - x0).norm_squared()
            }
        }
    }

    pub fn kinetic_energy(&self) -> f64 {
        0.5 * self.m * self.v.norm_squared() + 0.5 * self.inertia * self.w.norm_squared()
    }
}

/// The reference's acceleration rate / drag (0 without drag).
fn rate_over(rate: V3, drag: f64) -> V3 {
    if drag > 0.0 {
        rate / drag
    } else {
        V3::zeros()
    }
}

/// (int_0^s exp(-lambda t) dt, int_0^s int_0^t exp(-lambda u) du dt) = ((1 - e) / lambda, (lambda s -
/// (1 - e)) / lambda^2), e = exp(-lambda s); their series where lambda s is small (s and s^2 / 2
/// without drag).
fn relaxation_integrals(lambda: f64, s: f64) -> (f64, f64) {
    let x = lambda * s;
    if x < 1e-4 {
        return (
            s * (1.0 - 0.5 * x + x * x / 6.0),
            s * s * (0.5 - x / 6.0 + x * x / 24.0),
        );
    }
    let one_minus_e = -(-x).exp_m1();
    (one_minus_e / lambda, (x - one_minus_e) / (lambda * lambda))
}

/// What the integration does after a force evaluation (`Body::integrate`, in the gather pass).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Finish {
    Nothing,
    /// v += dt/2 a: the end of a step.
    HalfKick,
    /// The end of a step and the start of the next: two half kicks and the drift.
    KickDrift,
}
