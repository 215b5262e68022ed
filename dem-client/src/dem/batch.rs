//! The sphere-sphere contacts of LIGGGHTS's Hertz law (`ContactLaw::LIGGGHTS_HERTZ`) in batches:
//! the touching pairs of a chunk are copied into arrays of `LANES` (one array per quantity), the
//! law runs over them in a branch-free loop that the compiler vectorizes (with AVX-512 or AVX2
//! where the processor has them, chosen at run time), and the results go back to the pairs.
//!
//! Every lane calls the scalar law's own `contact::hertz`, `normal_force` and `lever_arms`, and
//! performs the rest with the same IEEE operations, in the same order, as `contact::contact_force`
//! with that law (no fused multiply-adds, no reassociation), so the forces and histories are the
//! same bits as the scalar path's.

use super::contact::{hertz, lever_arms, normal_force, Coefficients, ContactLaw, HertzPair};
use super::V3;

/// Contacts per batch.
pub const LANES: usize = 64;

/// A batch of touching pairs: inputs, then the results (history updated in place).
#[derive(Clone)]
pub struct Batch {
    pub len: usize,
    /// Index of each contact's pair in its chunk.
    pub slot: [u32; LANES],
    pub nx: [f64; LANES],
    pub ny: [f64; LANES],
    pub nz: [f64; LANES],
    pub overlap: [f64; LANES],
    pub r_i: [f64; LANES],
    pub r_j: [f64; LANES],
    pub r_eff: [f64; LANES],
    pub m_eff: [f64; LANES],
    pub dvx: [f64; LANES],
    pub dvy: [f64; LANES],
    pub dvz: [f64; LANES],
    pub wix: [f64; LANES],
    pub wiy: [f64; LANES],
    pub wiz: [f64; LANES],
    pub wjx: [f64; LANES],
    pub wjy: [f64; LANES],
    pub wjz: [f64; LANES],
    pub hx: [f64; LANES],
    pub hy: [f64; LANES],
    pub hz: [f64; LANES],
    /// Pair material: Y*, G*, damping factor, sqrt(4 G* / Y*), friction.
    pub y_star: [f64; LANES],
    pub g_star: [f64; LANES],
    pub damping: [f64; LANES],
    pub shear_to_normal: [f64; LANES],
    pub friction: [f64; LANES],
    pub fx: [f64; LANES],
    pub fy: [f64; LANES],
    pub fz: [f64; LANES],
    pub tix: [f64; LANES],
    pub tiy: [f64; LANES],
    pub tiz: [f64; LANES],
    pub tjx: [f64; LANES],
    pub tjy: [f64; LANES],
    pub tjz: [f64; LANES],
}

impl Default for Batch {
    fn default() -> Batch {
        let z = [0.0; LANES];
        Batch {
            len: 0,
            slot: [0; LANES],
            nx: z,
            ny: z,
            nz: z,
            overlap: z,
            r_i: z,
            r_j: z,
            r_eff: z,
            m_eff: z,
            dvx: z,
            dvy: z,
            dvz: z,
            wix: z,
            wiy: z,
            wiz: z,
            wjx: z,
            wjy: z,
            wjz: z,
            hx: z,
            hy: z,
            hz: z,
            y_star: z,
            g_star: z,
            damping: z,
            shear_to_normal: z,
            friction: z,
            fx: z,
            fy: z,
            fz: z,
            tix: z,
            tiy: z,
            tiz: z,
            tjx: z,
            tjy: z,
            tjz: z,
        }
    }
}

impl Batch {
    /// Force on i, torques on i and j, and the new history of contact `k`.
    pub fn result(&self, k: usize) -> (V3, V3, V3, V3) {
        (
            V3::new(self.fx[k], self.fy[k], self.fz[k]),
            V3::new(self.tix[k], self.tiy[k], self.tiz[k]),
            V3::new(self.tjx[k], self.tjy[k], self.tjz[k]),
            V3::new(self.hx[k], self.hy[k], self.hz[k]),
        )
    }

    /// Runs the law over all lanes (those past `len` hold stale inputs; their results are unused).
    pub fn run(&mut self, dt: f64) {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx512f") {
                // SAFETY: the processor has AVX-512F (checked just above).
                return unsafe { self.run_avx512(dt) };
            }
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the processor has AVX2 (checked just above).
                return unsafe { self.run_avx2(dt) };
            }
        }
        self.run_any(dt)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    unsafe fn run_avx512(&mut self, dt: f64) {
        self.run_any(dt)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn run_avx2(&mut self, dt: f64) {
        self.run_any(dt)
    }

    /// `contact::contact_force` with `ContactLaw::LIGGGHTS_HERTZ` (Hertz, LIGGGHTS damping, no
    /// clamp, total tangential spring, Coulomb limit mu |F_n|, lever arms r - d/2, no rolling) in
    /// every lane: the same `lever_arms`, `hertz` and `normal_force`, the rest written per
    /// component with the same operations in the same order; the Coulomb branch becomes a select.
    #[inline(always)]
    fn run_any(&mut self, dt: f64) {
        for k in 0..LANES {
            self.lane(k, dt);
        }
    }

    /// The contact of lane `k`: its force f_ij (eq. 12) and torques l_ij x f_ij (eq. 13), and its
    /// history.
    #[inline(always)]
    fn lane(&mut self, k: usize, dt: f64) {
        let law = &ContactLaw::LIGGGHTS_HERTZ;
        let n = [self.nx[k], self.ny[k], self.nz[k]];
        let ov = self.overlap[k];
        let (l_i, l_j) = lever_arms(law, self.r_i[k], self.r_j[k], ov);
        let v_rel = self.contact_velocity(k, n, l_i, l_j);
        let v_n = v_rel[0] * n[0] + v_rel[1] * n[1] + v_rel[2] * n[2];
        let pair = HertzPair {
            y_star: self.y_star[k],
            g_star: self.g_star[k],
            damping_factor: self.damping[k],
            shear_to_normal_sqrt: self.shear_to_normal[k],
        };
        let c = hertz(&pair, self.r_eff[k], self.m_eff[k], ov);
        let (f_n, limit) = normal_force(law, &c, v_n);
        let f_t = self.tangential_force(k, &c, self.friction[k] * limit, n, v_rel, v_n, dt);
        // contact_force: F = F_n n + F_t, torques -l n x F_t (eq. 13).
        self.fx[k] = f_n * n[0] + f_t[0];
        self.fy[k] = f_n * n[1] + f_t[1];
        self.fz[k] = f_n * n[2] + f_t[2];
        let arm_x = n[1] * f_t[2] - n[2] * f_t[1];
        let arm_y = n[2] * f_t[0] - n[0] * f_t[2];
        let arm_z = n[0] * f_t[1] - n[1] * f_t[0];
        self.tix[k] = -l_i * arm_x;
        self.tiy[k] = -l_i * arm_y;
        self.tiz[k] = -l_i * arm_z;
        self.tjx[k] = -l_j * arm_x;
        self.tjy[k] = -l_j * arm_y;
        self.tjz[k] = -l_j * arm_z;
    }

    /// The relative velocity at the contact point of lane `k`, v_rel = dv - (l_i w_i + l_j w_j) x n.
    #[inline(always)]
    fn contact_velocity(&self, k: usize, [nx, ny, nz]: [f64; 3], l_i: f64, l_j: f64) -> [f64; 3] {
        let sx = l_i * self.wix[k] + l_j * self.wjx[k];
        let sy = l_i * self.wiy[k] + l_j * self.wjy[k];
        let sz = l_i * self.wiz[k] + l_j * self.wjz[k];
        [
            self.dvx[k] - (sy * nz - sz * ny),
            self.dvy[k] - (sz * nx - sx * nz),
            self.dvz[k] - (sx * ny - sy * nx),
        ]
    }

    /// `contact::tangential_force` with the total spring, in lane `k` (`mu_fn` the Coulomb
    /// limit): the tangential spring-dashpot with the Coulomb slider as a select; its history
    /// updated in place.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn tangential_force(
        &mut self,
        k: usize,
        c: &Coefficients,
        mu_fn: f64,
        [nx, ny, nz]: [f64; 3],
        [vrx, vry, vrz]: [f64; 3],
        v_n: f64,
        dt: f64,
    ) -> [f64; 3] {
        let k_t = c.k_t;
        let vtx = vrx - v_n * nx;
        let vty = vry - v_n * ny;
        let vtz = vrz - v_n * nz;
        let mut hx = self.hx[k] + vtx * dt;
        let mut hy = self.hy[k] + vty * dt;
        let mut hz = self.hz[k] + vtz * dt;
        let hn = hx * nx + hy * ny + hz * nz;
        hx -= nx * hn;
        hy -= ny * hn;
        hz -= nz * hn;
        let ex = -k_t * hx;
        let ey = -k_t * hy;
        let ez = -k_t * hz;
        let magnitude2 = ex * ex + ey * ey + ez * ez;
        let slip = magnitude2 > mu_fn * mu_fn;
        let magnitude = magnitude2.sqrt();
        let scale = mu_fn / magnitude;
        let positive = magnitude > 0.0;
        let scx = if positive { ex * scale } else { 0.0 };
        let scy = if positive { ey * scale } else { 0.0 };
        let scz = if positive { ez * scale } else { 0.0 };
        let stiff = k_t > 0.0;
        // The spring's history: at the Coulomb limit the stretch that gives it (none without a
        // spring), else the stretched spring.
        let history = |limit: f64, stretched: f64| match (slip, stiff) {
            (true, true) => -limit / k_t,
            (true, false) => 0.0,
            (false, _) => stretched,
        };
        self.hx[k] = history(scx, hx);
        self.hy[k] = history(scy, hy);
        self.hz[k] = history(scz, hz);
        let gamma_t = c.gamma_t;
        [
            if slip { scx } else { ex - gamma_t * vtx },
            if slip { scy } else { ey - gamma_t * vty },
            if slip { scz } else { ez - gamma_t * vtz },
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dem::contact::{contact_force, Contact, PairMaterial};
    use scene::dem::Material;

    /// The `k`th of the random contacts of the test (drawn by `unit`): its pair material, its
    /// geometry and kinematics (every third fast), its history (every fourth fresh).
    fn random_contact(unit: &mut dyn FnMut() -> f64, k: usize) -> (PairMaterial, Contact, V3) {
        let material = |e: f64, mu: f64| Material {
            name: "m".into(),
            young_modulus: 5e7,
            poisson_ratio: 0.3,
            restitution: e,
            friction: mu,
            ..Default::default()
        };
        let pm = PairMaterial::mix(&material(0.3 + 0.6 * unit(), unit()), &material(0.5, 0.4));
        let n = V3::new(unit() - 0.5, unit() - 0.5, unit() - 0.5).normalize();
        let v = |s: f64, unit: &mut dyn FnMut() -> f64| V3::new(unit() - 0.5, unit() - 0.5, unit() - 0.5) * s;
        let (r_i, r_j) = (0.0018 + 0.0004 * unit(), 0.0018 + 0.0004 * unit());
        let c = Contact {
            n,
            overlap: 1e-5 * unit(),
            r_i,
            r_j,
            r_eff: r_i * r_j / (r_i + r_j),
            m_eff: 4e-5 * (0.5 + unit()),
            dv: v(if k.is_multiple_of(3) { 2.0 } else { 0.05 }, unit),
            w_i: v(50.0, unit),
            w_j: v(50.0, unit),
        };
        let history = if k.is_multiple_of(4) {
            V3::zeros()
        } else {
            v(2e-5, unit)
        };
        (pm, c, history)
    }

    /// Contact `c` (pair material `pm`, history `history`, law `law`) into lane `k` of `batch`.
    fn load_lane(batch: &mut Batch, k: usize, pm: &PairMaterial, c: &Contact, history: V3, law: &ContactLaw) {
        let n = c.n;
        batch.slot[k] = k as u32;
        (batch.nx[k], batch.ny[k], batch.nz[k]) = (n.x, n.y, n.z);
        batch.overlap[k] = c.overlap;
        (batch.r_i[k], batch.r_j[k], batch.r_eff[k], batch.m_eff[k]) = (c.r_i, c.r_j, c.r_eff, c.m_eff);
        (batch.dvx[k], batch.dvy[k], batch.dvz[k]) = (c.dv.x, c.dv.y, c.dv.z);
        (batch.wix[k], batch.wiy[k], batch.wiz[k]) = (c.w_i.x, c.w_i.y, c.w_i.z);
        (batch.wjx[k], batch.wjy[k], batch.wjz[k]) = (c.w_j.x, c.w_j.y, c.w_j.z);
        (batch.hx[k], batch.hy[k], batch.hz[k]) = (history.x, history.y, history.z);
        batch.y_star[k] = pm.y_star;
        batch.g_star[k] = pm.g_star;
        batch.damping[k] = pm.damping_factor[law.switches.damping as usize];
        batch.shear_to_normal[k] = pm.shear_to_normal_sqrt;
        batch.friction[k] = pm.friction;
    }

    /// Every lane, on every instruction set, gives the bits of `contact_force` (sticking and
    /// sliding contacts, fresh and loaded histories, both spheres spinning).
    #[test]
    fn batches_equal_the_scalar_law_bit_for_bit() {
        let mut seed = 12345u64;
        let mut unit = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let law = ContactLaw::LIGGGHTS_HERTZ;
        let dt = 5e-6;
        let mut batch = Batch::default();
        let mut expected = Vec::new();
        let mut slips = 0;
        for k in 0..LANES {
            let (pm, c, history) = random_contact(&mut unit, k);
            let mut h = history;
            let out = contact_force(&law, &pm, &c, &mut h, dt);
            expected.push((out.force, out.torque_i, out.torque_j, h));
            // Sliding: the tangential force sits on the Coulomb limit mu |F_n|.
            let f_n = out.force.dot(&c.n);
            let f_t = (out.force - f_n * c.n).norm();
            slips += usize::from((f_t - pm.friction * f_n.abs()).abs() <= 1e-9 * f_t);
            load_lane(&mut batch, k, &pm, &c, history, &law);
        }
        batch.len = LANES;
        assert!(slips > 0 && slips < LANES, "{slips} of {LANES} sliding");
        let inputs = batch.clone();
        let check = |b: &Batch, what: &str| {
            for (k, e) in expected.iter().enumerate() {
                let r = b.result(k);
                let same = |a: V3, b: V3| (0..3).all(|i| a[i].to_bits() == b[i].to_bits());
                assert!(
                    same(r.0, e.0) && same(r.1, e.1) && same(r.2, e.2) && same(r.3, e.3),
                    "{what} lane {k}: {r:?} vs {e:?}"
                );
            }
        };
        let mut b = inputs.clone();
        b.run(dt);
        check(&b, "dispatched");
        let mut b = inputs.clone();
        b.run_any(dt);
        check(&b, "portable");
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2") {
                let mut b = inputs.clone();
                // SAFETY: AVX2 present (checked above).
                unsafe { b.run_avx2(dt) };
                check(&b, "avx2");
            }
            if std::arch::is_x86_feature_detected!("avx512f") {
                let mut b = inputs.clone();
                // SAFETY: AVX-512F present (checked above).
                unsafe { b.run_avx512(dt) };
                check(&b, "avx512");
            }
        }
    }
}
