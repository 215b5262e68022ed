//! Contact laws, composed of a normal, a tangential and an optional rolling part, with the
//! switches that reproduce LIGGGHTS (`pair_style gran model hertz tangential history`) or YADE
//! (`Law2_ScGeom_MindlinPhys_Mindlin`) exactly.
//!
//! Conventions: `n` is the unit normal from body j to body i, `overlap` d > 0 the interpenetration
//! [m], the force returned acts on i (j gets its opposite). SI units throughout.

use super::V3;
use scene::dem::{
    CoulombNormal, DampingLaw, LeverArm, Material, NormalLaw, Preset, RollingLaw, TangentialLaw,
    TangentialSpring,
};
use std::f64::consts::PI;

/// The switches that tell reference codes apart (see docs/dem.md).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Switches {
    pub damping: DampingLaw,
    /// Normal force clamped to >= 0.
    pub clamp_normal: bool,
    pub spring: TangentialSpring,
    /// Sphere-wall contact radius R* = factor * r.
    pub wall_radius_factor: f64,
    pub coulomb: CoulombNormal,
    pub lever: LeverArm,
}

impl Switches {
    /// LIGGGHTS 3.8: LIGGGHTS damping, no clamp, total spring, R* = r on walls, mu |F_n|, r - d/2.
    pub const LIGGGHTS: Switches = Switches {
        damping: DampingLaw::Liggghts,
        clamp_normal: false,
        spring: TangentialSpring::Total,
        wall_radius_factor: 1.0,
        coulomb: CoulombNormal::Absolute,
        lever: LeverArm::ContactPoint,
    };
    /// YADE 2023.02a Mindlin: Thornton damping, clamp, incremental spring, R* = r/2 on walls,
    /// mu max(F_n, 0), lever arm r - d/2 (the reference oblique impacts agree within 0.5% with
    /// r - d/2 and miss by 0.7% in spin with r; `lever_arm = "radius"` remains available).
    pub const YADE: Switches = Switches {
        damping: DampingLaw::Thornton,
        clamp_normal: true,
        spring: TangentialSpring::Incremental,
        wall_radius_factor: 0.5,
        coulomb: CoulombNormal::Clamped,
        lever: LeverArm::ContactPoint,
    };

    pub fn preset(p: Preset) -> Switches {
        match p {
            Preset::Liggghts => Self::LIGGGHTS,
            Preset::Yade => Self::YADE,
        }
    }
}

/// Linear spring-dashpot parameters as given in the scene.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Linear {
    pub normal_stiffness: Option<f64>,
    pub normal_damping: Option<f64>,
    pub tangential_stiffness: Option<f64>,
    pub tangential_damping: Option<f64>,
    pub contact_time: Option<f64>,
}

/// A complete contact law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactLaw {
    pub normal: NormalLaw,
    pub tangential: TangentialLaw,
    pub rolling: RollingLaw,
    pub linear: Linear,
    pub switches: Switches,
}

impl ContactLaw {
    /// LIGGGHTS's `pair_style gran model hertz tangential history` (the `liggghts` preset's
    /// default): a constant, so that the contact loops specialised to it fold every switch.
    pub const LIGGGHTS_HERTZ: ContactLaw = ContactLaw {
        normal: NormalLaw::Hertz,
        tangential: TangentialLaw::History,
        rolling: RollingLaw::None,
        linear: Linear {
            normal_stiffness: None,
            normal_damping: None,
            tangential_stiffness: None,
            tangential_damping: None,
            contact_time: None,
        },
        switches: Switches::LIGGGHTS,
    };

    pub fn from_scene(c: &scene::dem::Contact) -> ContactLaw {
        let p = Switches::preset(c.preset);
        ContactLaw {
            normal: c.normal,
            tangential: c.tangential,
            rolling: c.rolling,
            linear: Linear {
                normal_stiffness: c.normal_stiffness,
                normal_damping: c.normal_damping,
                tangential_stiffness: c.tangential_stiffness,
                tangential_damping: c.tangential_damping,
                contact_time: c.contact_time,
            },
            switches: Switches {
                damping: c.damping_law.unwrap_or(p.damping),
                clamp_normal: c.clamp_normal_force.unwrap_or(p.clamp_normal),
                spring: c.tangential_spring.unwrap_or(p.spring),
                wall_radius_factor: c.wall_radius_factor.unwrap_or(p.wall_radius_factor),
                coulomb: c.coulomb_normal.unwrap_or(p.coulomb),
                lever: c.lever_arm.unwrap_or(p.lever),
            },
        }
    }
}

/// Properties of a pair of materials.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairMaterial {
    /// Y* = 1 / sum (1 - nu^2) / E [Pa].
    pub y_star: f64,
    /// G* = 1 / sum 2 (2 - nu)(1 + nu) / E [Pa].
    pub g_star: f64,
    /// Restitution e = min(e_i, e_j).
    pub restitution: f64,
    /// Friction mu = min(mu_i, mu_j) (YADE: the smaller friction angle).
    pub friction: f64,
    /// Rolling friction mu_r = min.
    pub rolling_friction: f64,
    /// Damping factor f of gamma = f sqrt(S m*) under each law (index: `DampingLaw as usize`):
    /// LIGGGHTS 2 sqrt(5/6) |beta|, Thornton 2 beta_T. Precomputed: ln, exp and the polynomial
    /// stay out of the contact loop.
    pub damping_factor: [f64; 2],
    /// sqrt(4 G* / Y*) = sqrt(k_t / S_n) of the Hertz-Mindlin law.
    pub shear_to_normal_sqrt: f64,
}

impl PairMaterial {
    pub fn mix(a: &Material, b: &Material) -> PairMaterial {
        let y = |m: &Material| (1.0 - m.poisson_ratio.powi(2)) / m.young_modulus;
        let g = |m: &Material| 2.0 * (2.0 - m.poisson_ratio) * (1.0 + m.poisson_ratio) / m.young_modulus;
        let (y_star, g_star) = (1.0 / (y(a) + y(b)), 1.0 / (g(a) + g(b)));
        PairMaterial {
            y_star,
            g_star,
            shear_to_normal_sqrt: (4.0 * g_star / y_star).sqrt(),
            restitution: a.restitution.min(b.restitution),
            friction: a.friction.min(b.friction),
            rolling_friction: a.rolling_friction.min(b.rolling_friction),
            damping_factor: [
                damping_factor(DampingLaw::Liggghts, a.restitution.min(b.restitution)),
                damping_factor(DampingLaw::Thornton, a.restitution.min(b.restitution)),
            ],
        }
    }
}

/// LIGGGHTS damping ratio beta = ln e / sqrt(ln^2 e + pi^2) (<= 0).
pub fn beta_liggghts(e: f64) -> f64 {
    let l = e.ln();
    l / (l * l + PI * PI).sqrt()
}

/// Thornton et al. 2013 (eqs. B6, B7): damping ratio of a Hertz contact without attraction.
pub fn beta_thornton(e: f64) -> f64 {
    let e = e.max(0.001);
    if e > 0.999 {
        return 0.0;
    }
    let h = [
        -6.918798, -16.41105, 146.8049, -796.4559, 2928.711, -7206.864, 11494.29, -11342.18, 6276.757,
        -1489.915,
    ];
    let alpha = e * h.iter().rev().fold(0.0, |acc, hk| hk + e * acc);
    (1.0 / (1.0 - (1.0 + e).powi(2) * alpha.exp()) - 1.0).sqrt()
}

/// Factor f of the damping coefficient gamma = f sqrt(S m*) of a spring of tangent stiffness S:
/// LIGGGHTS f = 2 sqrt(5/6) |beta|, Thornton f = 2 beta_T.
pub fn damping_factor(law: DampingLaw, e: f64) -> f64 {
    match law {
        DampingLaw::Liggghts => 2.0 * (5.0f64 / 6.0).sqrt() * beta_liggghts(e).abs(),
        DampingLaw::Thornton => 2.0 * beta_thornton(e),
    }
}

/// Linear law: k_n and gamma_n from contact time t_c and restitution e (unclamped closed form):
/// k_n = m* (pi^2 + ln^2 e) / t_c^2, gamma_n = -2 m* ln e / t_c.
pub fn linear_from_contact_time(t_c: f64, e: f64, m_eff: f64) -> (f64, f64) {
    let l = e.ln();
    (m_eff * (PI * PI + l * l) / (t_c * t_c), -2.0 * m_eff * l / t_c)
}

/// Linear law: gamma_n from k_n and e, gamma_n = sqrt(4 m* k_n ln^2 e / (ln^2 e + pi^2)).
pub fn linear_damping_from_restitution(k_n: f64, e: f64, m_eff: f64) -> f64 {
    let l2 = e.ln().powi(2);
    (4.0 * m_eff * k_n * l2 / (l2 + PI * PI)).sqrt()
}

/// Geometry and kinematics of one contact.
#[derive(Debug, Clone, Copy)]
pub struct Contact {
    /// Unit normal from j to i.
    pub n: V3,
    /// Overlap d > 0 [m].
    pub overlap: f64,
    /// Radii of i and j (j = 0 for a wall) [m].
    pub r_i: f64,
    pub r_j: f64,
    /// Effective radius R* and mass m*.
    pub r_eff: f64,
    pub m_eff: f64,
    /// v_i - v_j [m/s].
    pub dv: V3,
    pub w_i: V3,
    pub w_j: V3,
}

/// Stiffness and damping of a contact at its present overlap.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Coefficients {
    /// Normal elastic force magnitude [N].
    pub f_elastic: f64,
    pub gamma_n: f64,
    pub k_t: f64,
    pub gamma_t: f64,
}

/// The constants of a pair's Hertz-Mindlin law, from its `PairMaterial` and the law's damping.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HertzPair {
    /// Y* [Pa].
    pub y_star: f64,
    /// G* [Pa].
    pub g_star: f64,
    /// Damping factor f of gamma = f sqrt(S m*) (`PairMaterial::damping_factor`).
    pub damping_factor: f64,
    /// sqrt(4 G* / Y*).
    pub shear_to_normal_sqrt: f64,
}

impl HertzPair {
    #[inline(always)]
    pub fn of(m: &PairMaterial, damping: DampingLaw) -> HertzPair {
        HertzPair {
            y_star: m.y_star,
            g_star: m.g_star,
            damping_factor: m.damping_factor[damping as usize],
            shear_to_normal_sqrt: m.shear_to_normal_sqrt,
        }
    }
}

/// The Hertz-Mindlin law: the springs and dashpots of the seed paper's contact model (section
/// 2.3, the normal and tangential spring-dashpots of f_ij in eqs. 12-13) with the stiffness of two
/// elastic spheres. With the contact radius a = sqrt(R* d): normal tangent stiffness S_n = 2 Y* a,
/// elastic force F_el = 4/3 Y* a d, tangential stiffness k_t = 8 G* a, dampings gamma_n = f
/// sqrt(S_n m*) and gamma_t = f sqrt(k_t m*) = gamma_n sqrt(4 G* / Y*). Called per pair by the
/// scalar pair pass (`coefficients`) and per lane by the batched one (`batch.rs`).
#[inline(always)]
pub fn hertz(p: &HertzPair, r_eff: f64, m_eff: f64, overlap: f64) -> Coefficients {
    let a = (r_eff * overlap).sqrt();
    let s_n = 2.0 * p.y_star * a;
    let k_t = 8.0 * p.g_star * a;
    let gamma_n = p.damping_factor * (s_n * m_eff).sqrt();
    Coefficients {
        f_elastic: 4.0 / 3.0 * p.y_star * a * overlap,
        gamma_n,
        k_t,
        // f sqrt(k_t m*) = gamma_n sqrt(k_t / S_n) = gamma_n sqrt(4 G* / Y*).
        gamma_t: gamma_n * p.shear_to_normal_sqrt,
    }
}

/// The linear spring-dashpot law (the seed paper's contact model, section 2.3, with constant
/// springs): F_el = k_n d; k_n and gamma_n from the contact time and the restitution `e`, or k_n
/// given and gamma_n given or from `e`; k_t and gamma_t given, else k_n and gamma_n.
#[inline(always)]
pub fn linear_spring_dashpot(l: &Linear, e: f64, m_eff: f64, overlap: f64) -> Coefficients {
    let (k_n, gamma_n) = match (l.contact_time, l.normal_stiffness) {
        (Some(t_c), _) => linear_from_contact_time(t_c, e, m_eff),
        (None, Some(k)) => (
            k,
            l.normal_damping
                .unwrap_or_else(|| linear_damping_from_restitution(k, e, m_eff)),
        ),
        (None, None) => (0.0, 0.0),
    };
    Coefficients {
        f_elastic: k_n * overlap,
        gamma_n,
        k_t: l.tangential_stiffness.unwrap_or(k_n),
        gamma_t: l.tangential_damping.unwrap_or(gamma_n),
    }
}

/// Normal elastic force, tangential stiffness and both dampings of the law's normal model.
#[inline(always)]
pub fn coefficients(law: &ContactLaw, m: &PairMaterial, c: &Contact) -> Coefficients {
    match law.normal {
        NormalLaw::Hertz => hertz(
            &HertzPair::of(m, law.switches.damping),
            c.r_eff,
            c.m_eff,
            c.overlap,
        ),
        NormalLaw::Linear => linear_spring_dashpot(&law.linear, m.restitution, c.m_eff, c.overlap),
    }
}

/// Force on i and torques on i and j of one contact.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ContactForce {
    pub force: V3,
    pub torque_i: V3,
    pub torque_j: V3,
}

/// The normal spring-dashpot (the seed paper's contact model, section 2.3; its force is part of
/// f_ij in eqs. 12-13): normal force magnitude F_n = F_el - gamma_n v_n (v_n = dv . n < 0
/// approaching), clamped to >= 0 when the switch says so. Returns (F_n, F_n for the Coulomb
/// limit).
#[inline(always)]
pub fn normal_force(law: &ContactLaw, k: &Coefficients, v_n: f64) -> (f64, f64) {
    let f = k.f_elastic - k.gamma_n * v_n;
    let f = if law.switches.clamp_normal { f.max(0.0) } else { f };
    let limit = match law.switches.coulomb {
        CoulombNormal::Absolute => f.abs(),
        CoulombNormal::Clamped => f.max(0.0),
    };
    (f, limit)
}

/// Tangential spring-dashpot with Coulomb slider (the seed paper's contact model, section 2.3: the
/// friction slider caps the tangential force by Coulomb's law; part of f_ij in eqs. 12-13);
/// `history` is the total shear displacement xi [m]
/// (total spring) or the elastic shear force [N] (incremental spring), updated in place.
/// Total: xi += v_t dt, projected on the tangent plane, F_t = -k_t xi - gamma_t v_t.
/// Incremental: F_s rotated into the tangent plane, F_s -= k_t v_t dt, F_t = F_s - gamma_t v_t.
/// Slip when |elastic part| > mu F_n: the elastic part is scaled to mu F_n, no damping.
#[inline(always)]
pub fn tangential_force(
    law: &ContactLaw,
    k: &Coefficients,
    mu_fn: f64,
    n: V3,
    v_t: V3,
    history: &mut V3,
    dt: f64,
) -> V3 {
    let elastic = match law.switches.spring {
        TangentialSpring::Total => {
            *history += v_t * dt;
            *history -= n * history.dot(&n);
            -k.k_t * *history
        }
        TangentialSpring::Incremental => {
            let before = history.norm();
            *history -= n * history.dot(&n);
            let after = history.norm();
            if after > 0.0 {
                *history *= before / after;
            }
            *history -= k.k_t * v_t * dt;
            *history
        }
    };
    let magnitude2 = elastic.norm_squared();
    if magnitude2 > mu_fn * mu_fn {
        let magnitude = magnitude2.sqrt();
        let scaled = if magnitude > 0.0 {
            elastic * (mu_fn / magnitude)
        } else {
            V3::zeros()
        };
        *history = match law.switches.spring {
            TangentialSpring::Total if k.k_t > 0.0 => -scaled / k.k_t,
            TangentialSpring::Total => V3::zeros(),
            TangentialSpring::Incremental => scaled,
        };
        scaled
    } else {
        elastic - k.gamma_t * v_t
    }
}

/// Constant directional rolling torque on i: M_r = -mu_r R* |F_n| w_rel / |w_rel|, w_rel = w_i - w_j.
#[inline(always)]
pub fn rolling_torque(mu_r: f64, r_eff: f64, f_n: f64, w_rel: V3) -> V3 {
    let w = w_rel.norm();
    if w > 0.0 {
        -mu_r * r_eff * f_n.abs() * w_rel / w
    } else {
        V3::zeros()
    }
}

/// Lever arms (l_i, l_j) of spheres of radii `r_i`, `r_j` overlapping by `overlap`: r - d/2 or r
/// (|l_ij| of eq. 13).
#[inline(always)]
pub fn lever_arms(law: &ContactLaw, r_i: f64, r_j: f64, overlap: f64) -> (f64, f64) {
    match law.switches.lever {
        LeverArm::ContactPoint => (r_i - 0.5 * overlap, (r_j - 0.5 * overlap).max(0.0)),
        LeverArm::Radius => (r_i, r_j),
    }
}

/// Full contact: the force f_ij of eq. 12, F_i = F_n n + F_t, and the torques l_ij x f_ij of eq.
/// 13, -l_i n x F_t on i and -l_j n x F_t on j (l_ij = -l_i n: n x n = 0 leaves F_t alone), plus
/// rolling. The relative velocity at the contact point is v_rel = dv - (l_i w_i + l_j w_j) x n.
#[inline(always)]
pub fn contact_force(
    law: &ContactLaw,
    m: &PairMaterial,
    c: &Contact,
    history: &mut V3,
    dt: f64,
) -> ContactForce {
    let (l_i, l_j) = lever_arms(law, c.r_i, c.r_j, c.overlap);
    let v_rel = c.dv - (l_i * c.w_i + l_j * c.w_j).cross(&c.n);
    let v_n = v_rel.dot(&c.n);
    let k = coefficients(law, m, c);
    let (f_n, limit) = normal_force(law, &k, v_n);
    let mut out = ContactForce {
        force: f_n * c.n,
        ..Default::default()
    };
    if law.tangential == TangentialLaw::History {
        let v_t = v_rel - v_n * c.n;
        let f_t = tangential_force(law, &k, m.friction * limit, c.n, v_t, history, dt);
        out.force += f_t;
        // eq. 13: l_ij x f_ij.
        let arm = c.n.cross(&f_t);
        out.torque_i = -l_i * arm;
        out.torque_j = -l_j * arm;
    }
    if law.rolling == RollingLaw::ConstantTorque && m.rolling_friction > 0.0 {
        let m_r = rolling_torque(m.rolling_friction, c.r_eff, f_n, c.w_i - c.w_j);
        out.torque_i += m_r;
        out.torque_j -= m_r;
    }
    out
}
