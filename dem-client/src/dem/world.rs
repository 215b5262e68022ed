//! The particle system and its time integration.
//!
//! Equations of motion (seed paper eqs. 12-13), per sphere i:
//!   m_i dv_i/dt = m_i g + sum_j f_ij + F_ext,i
//!   I_i dw_i/dt = sum_j l_ij x f_ij + T_ext,i,      I_i = 2/5 m_i r_i^2,
//! F_ext, T_ext the fluid's force and torque (held constant over a fluid step when coupled).
//! Integrated by velocity Verlet (LIGGGHTS's scheme): half kick, drift, forces, half kick.

use super::batch::{Batch, LANES};
use super::contact::{contact_force, Contact, ContactForce, ContactLaw, PairMaterial};
use super::lubrication::Lubrication;
use super::neighbor::{periodic_pairs, verlet_pairs, Periodic};
use super::V3;
use rayon::iter::Either;
use rayon::prelude::*;
use std::collections::HashMap;

pub mod everyone;
mod flight;

/// What the force-gathering pass does after the forces.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Finish {
    Nothing,
    /// v += dt/2 a: the end of a step.
    HalfKick,
    /// The end of a step and the start of the next: two half kicks and the drift.
    KickDrift,
}

/// Where the contact loops read the law from: the world's, or a constant whose switches the
/// compiler folds (the loops are compiled once for each).
trait LawRef: Copy + Send + Sync {
    /// Sphere-sphere contacts by `batch::Batch` (only for `ContactLaw::LIGGGHTS_HERTZ`).
    const BATCHED: bool = false;
    fn law(&self) -> &ContactLaw;
}

#[derive(Clone, Copy)]
struct AnyLaw<'a>(&'a ContactLaw);

impl LawRef for AnyLaw<'_> {
    #[inline(always)]
    fn law(&self) -> &ContactLaw {
        self.0
    }
}

#[derive(Clone, Copy)]
struct LiggghtsHertz;

impl LawRef for LiggghtsHertz {
    const BATCHED: bool = true;
    #[inline(always)]
    fn law(&self) -> &ContactLaw {
        &ContactLaw::LIGGGHTS_HERTZ
    }
}

/// Fewest bodies per parallel task (tasks of a few microseconds at least).
pub(crate) const CHUNK: usize = 256;
/// Verlet pairs per parallel task.
const PAIR_CHUNK: usize = 1024;
/// Safety factor on a sphere's travel bound in free flight (`flight`; the bound is exact for the
/// motion it assumes; the margin covers the step's discretisation).
const FREE_FLIGHT_MARGIN: f64 = 1.5;

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

    /// Velocity change over half_dt: a = (f + F_ext - drag v)/m + g, alpha = (t + T_ext -
    /// spin_drag w)/I.
    fn half_kick(&self, half_dt: f64, g: V3) -> (V3, V3) {
        let f = self.f + self.f_ext - self.drag * self.v;
        let t = self.t + self.t_ext - self.spin_drag * self.w;
        (half_dt * (f / self.m + g), half_dt * t / self.inertia)
    }

    /// A bound on |dv/dt| over a held fluid step in which the sphere touches nothing: with the
    /// external force F_ext + t F_ext_rate - drag v, v(t) = v_0 + a_r t + u(t), a_r = F_ext_rate /
    /// drag the reference's acceleration and u' = (a_0 - a_r) exp(-drag t / m), a_0 the
    /// acceleration at t = 0; so |dv/dt| <= |a_r| + |a_0 - a_r| (|a_0| without drag).
    fn acceleration_bound(&self, g: V3) -> f64 {
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
    /// where k sub-steps would have left them.
    fn fly(&mut self, span: f64, g: V3) {
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
    fn kick(&mut self, half_dt: f64, g: V3) {
        let (dv, dw) = self.half_kick(half_dt, g);
        self.v += dv;
        self.w += dw;
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

/// A fixed wall.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    /// Particles on the side the unit `normal` points to.
    Plane { point: V3, normal: V3 },
    /// A solid axis-aligned box; particles outside.
    Solid { min: V3, max: V3 },
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wall {
    pub shape: Shape,
    pub material: usize,
}

impl Wall {
    /// (unit normal from the wall to the sphere, gap between them), where the normal is defined.
    fn separation(&self, x: V3, r: f64) -> Option<(V3, f64)> {
        match self.shape {
            Shape::Plane { point, normal } => Some((normal, (x - point).dot(&normal) - r)),
            Shape::Solid { min, max } => {
                let delta = x - x.sup(&min).inf(&max);
                let dist = delta.norm();
                (dist > 0.0).then(|| (delta / dist, dist - r))
            }
        }
    }

    /// Can a sphere at `x` touch the wall after moving less than `margin`? (Both distances are
    /// 1-Lipschitz in `x`.)
    fn near(&self, x: V3, r: f64, margin: f64) -> bool {
        match self.shape {
            Shape::Plane { point, normal } => (x - point).dot(&normal) < r + margin,
            Shape::Solid { min, max } => (x - x.sup(&min).inf(&max)).norm() < r + margin,
        }
    }
}

/// A pair of the Verlet list: its spheres, their pair material and whether they touch. Not
/// touching implies a zero history in `World::pair_history` and a zero force in `World::out` (so a
/// pair that stays apart costs no writes). 16 bytes, read by every pair pass: the constants that
/// follow from the radii and masses (r_i + r_j, R*, m*) are computed where a pass needs them, and
/// the history (24 bytes) and the periodic shift (24) are kept apart, read only by the pairs that
/// touch and in periodic worlds. A 32^3 bed lists 280,000 pairs, of which 2-14,000 touch; with
/// 104 bytes a pair read every DEM step (history and constants with the pair) its pair pass was
/// 70% of the step, and this layout took 10-12% off the step (docs/dem.md, "Throughput").
#[derive(Debug, Clone, Copy)]
struct Slot {
    i: u32,
    j: u32,
    /// Index into the pair materials.
    material: u32,
    touching: bool,
}

/// The constants of a pair that follow from the spheres' radii and masses, with the same
/// expressions wherever they are needed (so the same bits).
#[inline(always)]
fn r_sum(a: &impl Motion, b: &impl Motion) -> f64 {
    a.r() + b.r()
}

/// R* = r_i r_j / (r_i + r_j).
#[inline(always)]
fn r_eff(a: &impl Motion, b: &impl Motion) -> f64 {
    a.r() * b.r() / (a.r() + b.r())
}

/// m* = m_i m_j / (m_i + m_j).
#[inline(always)]
fn m_eff(a: &impl Motion, b: &impl Motion) -> f64 {
    a.m() * b.m() / (a.m() + b.m())
}

/// Spheres from which a world's contact passes work from compact arrays (`World::compact_from`):
/// the pair pass reads a copy of the spheres' motion (`Kin`) instead of the bodies and records
/// which pairs touch (`World::touch`), and where few do the gather adds only those. 4096 bodies
/// are 1.3 MB, more than a core's L2 cache (1 MB here); below that the bodies stay in the cache
/// and the copy and the record cost more than they save (a 2000-sphere pour, one thread: +5% and
/// +3% wall time). A 32^3 bed (`dem-client bench validation/scenes/bed.toml`, one thread): 1.16 s
/// a fluid step -> 0.96 s with the copy -> 0.60 s with the touching pairs alone gathered.
pub(crate) const COMPACT_FROM: usize = 4096;

/// What the pair pass reads of a sphere, copied from the bodies before each pass in a world of
/// `COMPACT_FROM` spheres or more: 88 bytes a sphere where a `Body` is 320. The pass visits each
/// sphere once per listed pair, and through the bodies it pulled a 32^3 bed's 10.5 MB through the
/// caches every DEM step (the copy reads them once, in order).
#[derive(Debug, Clone, Copy, Default)]
struct Kin {
    x: V3,
    v: V3,
    w: V3,
    r: f64,
    m: f64,
}

/// A sphere's motion as the pair pass reads it: a `Body` or its `Kin`.
trait Motion: Sync {
    /// Whether the pass records which pairs touch (`World::touch`): from the compact copy, in a
    /// world of `COMPACT_FROM` spheres or more.
    const TOUCH: bool;
    fn x(&self) -> V3;
    fn v(&self) -> V3;
    fn w(&self) -> V3;
    fn r(&self) -> f64;
    fn m(&self) -> f64;
}

/// `Motion` from the fields x, v, w, r, m, which `Body` and `Kin` share.
macro_rules! motion_of_fields {
    ($t:ty, touch: $touch:expr) => {
        impl Motion for $t {
            const TOUCH: bool = $touch;
            #[inline(always)]
            fn x(&self) -> V3 {
                self.x
            }
            #[inline(always)]
            fn v(&self) -> V3 {
                self.v
            }
            #[inline(always)]
            fn w(&self) -> V3 {
                self.w
            }
            #[inline(always)]
            fn r(&self) -> f64 {
                self.r
            }
            #[inline(always)]
            fn m(&self) -> f64 {
                self.m
            }
        }
    };
}

motion_of_fields!(Body, touch: false);
motion_of_fields!(Kin, touch: true);

impl Kin {
    #[inline(always)]
    fn of(b: &Body) -> Kin {
        Kin {
            x: b.x,
            v: b.v,
            w: b.w,
            r: b.r,
            m: b.m,
        }
    }
}

/// The particles, the walls and the contact model.
pub struct World {
    /// The spheres. Between steps their state (x, v, w) and external loads may be changed freely;
    /// the pair material is read into the pair list at each neighbour-list build, so a sphere
    /// changes its material (and its radius, which the list's reach assumes) only by `pop` and
    /// `insert`. The walls are fixed: each build lists per sphere those within its reach (a
    /// change in their number forces a build).
    pub bodies: Vec<Body>,
    pub walls: Vec<Wall>,
    pub law: ContactLaw,
    /// Pair materials, `n_materials x n_materials`.
    pair_materials: Vec<PairMaterial>,
    n_materials: usize,
    pub gravity: V3,
    pub dt: f64,
    pub skin: f64,
    pub time: f64,
    /// Squeeze films of a coupled fluid (None: dry, the pure DEM). Set by `set_lubrication`.
    lubrication: Option<Lubrication>,
    /// The axes along which the domain is periodic (none by default). Set by `set_periodic`.
    periodic: Option<Periodic>,
    /// Film force on i of each pair at the last evaluation (empty without lubrication).
    films: Vec<V3>,
    /// The spheres' positions, velocities, spins and radii for the pair pass (`Kin`; empty below
    /// `compact_from` spheres).
    kin: Vec<Kin>,
    /// Spheres from which the contact passes work from compact arrays (`COMPACT_FROM`; the tests
    /// set it to compare both ways).
    pub(crate) compact_from: usize,
    /// The Verlet pairs (i < j), sorted by i then j.
    slots: Vec<Slot>,
    /// Tangential contact history of each pair (zero when not touching).
    pair_history: Vec<V3>,
    /// The periodic image of j that i meets, per pair: x_i - (x_j + shift) (empty in a world
    /// without periodic axes, where it is zero).
    pair_shift: Vec<V3>,
    /// Force on i and torques of each pair at the last evaluation (zero when not touching).
    out: Vec<ContactForce>,
    /// Whether each pair touches, written by the pair pass of a world of `compact_from` spheres or
    /// more for the gather that follows it, which then adds only those pairs' `out` where fewer
    /// than half the listed pairs touch (in a bed most listed pairs are films, not contacts, and
    /// their zero forces were 72 bytes a pair to read twice). Sized with the slots in every world.
    touch: Vec<bool>,
    /// Per body, its first slot as i (CSR: the slots with i = k are `first_i[k]..first_i[k + 1]`).
    first_i: Vec<u32>,
    /// Per body, the slots in which it is j, in slot order (CSR over `as_j`).
    as_j_start: Vec<u32>,
    as_j: Vec<u32>,
    /// Per body and wall: contact history.
    wall_history: Vec<V3>,
    /// Per body, the walls it can touch before the next neighbour-list build (CSR, in wall order).
    near_start: Vec<u32>,
    near: Vec<u32>,
    x_at_build: Vec<V3>,
    /// The spheres' ids at the last build, in order (how the contact histories are carried).
    ids_at_build: Vec<u64>,
    stale: bool,
    /// Number of neighbour-list builds so far, and the wall time they took [s].
    pub builds: u64,
    pub build_seconds: f64,
    /// Fluid steps advanced with an island (`advance_span`: some or all spheres in the DEM steps
    /// among themselves), and islands dropped (a sphere went beyond its reach: every sphere took
    /// the DEM steps with the whole lists).
    pub islands: u64,
    pub dropped_islands: u64,
    contacts: usize,
    /// The largest squared distance a sphere was seen from `x_at_build` (after each drift).
    peak_drift2: f64,
    /// The island's world of the last fluid step that had one, kept for its allocations
    /// (`flight::Spare`).
    spare: Option<Box<flight::Spare>>,
    /// Whether a fluid step whose island is every sphere goes through the island's world or the
    /// whole world's lists: timed on the run's own steps (`everyone`).
    pub everyone: everyone::Everyone,
}

impl World {
    pub fn new(
        bodies: Vec<Body>,
        walls: Vec<Wall>,
        law: ContactLaw,
        materials: &[scene::dem::Material],
        gravity: V3,
        dt: f64,
        skin: f64,
    ) -> World {
        let n = materials.len();
        let pair_materials = (0..n * n)
            .map(|k| PairMaterial::mix(&materials[k / n], &materials[k % n]))
            .collect();
        let mut world = World::bare(bodies, walls, law, pair_materials, n, gravity, dt, skin);
        world.forces(0.0, Finish::Nothing);
        world
    }

    /// A world of these spheres and walls with no lists yet (stale), at time 0; `pair_materials`
    /// mix `n_materials` materials.
    #[allow(clippy::too_many_arguments)]
    fn bare(
        bodies: Vec<Body>,
        walls: Vec<Wall>,
        law: ContactLaw,
        pair_materials: Vec<PairMaterial>,
        n_materials: usize,
        gravity: V3,
        dt: f64,
        skin: f64,
    ) -> World {
        World {
            bodies,
            walls,
            law,
            pair_materials,
            n_materials,
            gravity,
            dt,
            skin,
            time: 0.0,
            lubrication: None,
            periodic: None,
            films: Vec::new(),
            kin: Vec::new(),
            compact_from: COMPACT_FROM,
            touch: Vec::new(),
            slots: Vec::new(),
            pair_history: Vec::new(),
            pair_shift: Vec::new(),
            out: Vec::new(),
            first_i: Vec::new(),
            as_j_start: Vec::new(),
            as_j: Vec::new(),
            wall_history: Vec::new(),
            near_start: Vec::new(),
            near: Vec::new(),
            x_at_build: Vec::new(),
            ids_at_build: Vec::new(),
            stale: true,
            builds: 0,
            build_seconds: 0.0,
            islands: 0,
            dropped_islands: 0,
            contacts: 0,
            peak_drift2: 0.0,
            spare: None,
            everyone: everyone::Everyone::default(),
        }
    }

    fn pair_material(&self, a: usize, b: usize) -> &PairMaterial {
        &self.pair_materials[a * self.n_materials + b]
    }

    /// Adds (or removes) the squeeze-film force of a fluid to every pair and wall gap below its
    /// cut-off; the neighbour lists then reach the cut-off further.
    pub fn set_lubrication(&mut self, lubrication: Option<Lubrication>) {
        self.lubrication = lubrication;
        self.stale = true;
        self.forces(0.0, Finish::Nothing);
    }

    /// Makes the domain periodic along the axes of `box_` with a length (spheres leaving through
    /// one face come back through the other, pairs meet across the faces); refuses a length not
    /// above twice the neighbour-list reach with a lubrication cut-off up to `cutoff` (a pair would
    /// meet two images), naming the axis.
    pub fn set_periodic(&mut self, box_: Option<Periodic>, cutoff: f64) -> Result<(), String> {
        if let Some(p) = &box_ {
            let r_max = self.bodies.iter().map(|b| b.r).fold(0.0, f64::max);
            let reach = 2.0 * r_max + self.skin + self.reach().max(cutoff);
            if let Some(a) = (0..3).find(|&a| p.len[a] > 0.0 && p.len[a] <= 2.0 * reach) {
                return Err(format!(
                    "the periodic {} axis is {} m long, not above twice the pair reach {reach} m \
                     (largest diameter + skin + lubrication cut-off): a sphere would meet two images \
                     of another",
                    ["x", "y", "z"][a],
                    p.len[a]
                ));
            }
        }
        self.periodic = box_.filter(|p| p.any());
        self.stale = true;
        self.forces(0.0, Finish::Nothing);
        Ok(())
    }

    pub fn lubrication(&self) -> Option<&Lubrication> {
        self.lubrication.as_ref()
    }

    /// How much further than contact the neighbour lists must reach: the film cut-off.
    fn reach(&self) -> f64 {
        self.lubrication.map_or(0.0, |l| l.cutoff)
    }

    /// Contacts (sphere-sphere and sphere-wall) at the last force evaluation.
    pub fn contact_count(&self) -> usize {
        self.contacts
    }

    /// Whether the contact passes work from compact arrays (`COMPACT_FROM`).
    fn compact(&self) -> bool {
        self.bodies.len() >= self.compact_from
    }

    /// Pairs in the neighbour list (within contact, the film cut-off and the skin).
    pub fn pair_count(&self) -> usize {
        self.slots.len()
    }

    /// Total kinetic energy, summed the same way every run (per chunk of bodies, then the chunks
    /// in order; rayon's `sum` adds in the order its threads finish).
    pub fn kinetic_energy(&self) -> f64 {
        let chunks: Vec<f64> = self
            .bodies
            .par_chunks(CHUNK)
            .map(|c| c.iter().map(Body::kinetic_energy).sum())
            .collect();
        chunks.iter().sum()
    }

    /// Adds a sphere (its contact forces are evaluated at once).
    pub fn insert(&mut self, body: Body) {
        self.bodies.push(body);
        self.stale = true;
        self.forces(0.0, Finish::Nothing);
    }

    /// Removes the last sphere.
    pub fn pop(&mut self) -> Option<Body> {
        let b = self.bodies.pop();
        self.stale = true;
        self.forces(0.0, Finish::Nothing);
        b
    }

    /// `steps` velocity-Verlet steps, run on a worker of rayon's pool so that the parallel
    /// loops inside need no hand-off from (and wake-up of) the calling thread.
    /// Between two steps of the run the closing half kick of one, the opening half kick and the
    /// drift of the next share one pass over the bodies (the same as separate steps, bit for bit).
    pub fn advance(&mut self, steps: u64) {
        if steps == 0 {
            return;
        }
        rayon::scope(|_| {
            self.open_step();
            for s in 0..steps {
                let last = s + 1 == steps;
                let finish = if last { Finish::HalfKick } else { Finish::KickDrift };
                let moved = self.forces(self.dt, finish);
                self.time += self.dt;
                self.note_drift(moved);
            }
        });
        self.wrap_into_domain();
    }

    /// Along the periodic axes, the spheres that left the domain come back by a period (between
    /// neighbour-list builds they may drift out by up to skin / 2); the pairs' image shifts then
    /// change, so the list is rebuilt before the next forces.
    fn wrap_into_domain(&mut self) {
        let Some(p) = self.periodic else {
            return;
        };
        let mut wrapped = false;
        for b in &mut self.bodies {
            let x = p.wrap(b.x);
            if x != b.x {
                b.x = x;
                wrapped = true;
            }
        }
        if wrapped {
            self.stale = true;
        }
    }

    /// One velocity-Verlet step of `dt`: half kick and drift (one pass, which also finds the
    /// largest displacement since the last neighbour-list build), forces, half kick (fused with
    /// the force gather).
    #[cfg(test)]
    pub fn step(&mut self) {
        self.advance(1);
    }

    /// Half kick and drift; marks the neighbour list stale when some sphere moved more than skin / 2.
    fn open_step(&mut self) {
        let (dt, g) = (self.dt, self.gravity);
        self.move_bodies(|b| {
            b.kick(0.5 * dt, g);
            b.x += dt * b.v;
        });
    }

    /// Applies `motion` to every sphere in one parallel pass that also finds the largest
    /// displacement since the last neighbour-list build, and marks the list stale beyond skin / 2.
    fn move_bodies(&mut self, motion: impl Fn(&mut Body) + Sync + Send) {
        let moved = if self.x_at_build.len() == self.bodies.len() {
            self.bodies
                .par_iter_mut()
                .with_min_len(CHUNK)
                .zip(&self.x_at_build)
                .map(|(b, x0)| {
                    motion(b);
                    (b.x - x0).norm_squared()
                })
                .reduce(|| 0.0, f64::max)
        } else {
            self.bodies.par_iter_mut().with_min_len(CHUNK).for_each(motion);
            f64::INFINITY
        };
        self.note_drift(moved);
    }

    /// Records the largest squared displacement since the last build after a drift, and marks
    /// the neighbour list stale beyond skin / 2.
    fn note_drift(&mut self, moved: f64) {
        self.peak_drift2 = self.peak_drift2.max(moved);
        if moved > 0.25 * self.skin * self.skin {
            self.stale = true;
        }
    }

    /// Has some sphere moved more than skin / 2 since the last build (or the set changed)? Every
    /// drift (`open_step`, the gather's `KickDrift`) measures the largest displacement since the
    /// build and marks the list stale beyond skin / 2, so no scan is needed here.
    fn needs_rebuild(&self) -> bool {
        self.stale
            || self.x_at_build.len() != self.bodies.len()
            || self.wall_history.len() != self.bodies.len() * self.walls.len().max(1)
    }

    /// Rebuilds the Verlet list, carrying the history of the pairs still listed.
    fn rebuild(&mut self) {
        let start = std::time::Instant::now();
        self.wrap_into_domain();
        let x: Vec<V3> = self.bodies.iter().map(|b| b.x).collect();
        let r: Vec<f64> = self.bodies.iter().map(|b| b.r).collect();
        let ids: Vec<u64> = self.bodies.iter().map(|b| b.id).collect();
        let reach = self.reach();
        let pairs: Vec<(u32, u32, V3)> = match &self.periodic {
            Some(p) => periodic_pairs(&x, &r, self.skin + reach, p),
            None => verlet_pairs(&x, &r, self.skin + reach)
                .into_iter()
                .map(|(i, j)| (i, j, V3::zeros()))
                .collect(),
        };
        let history = self.carried_history(&ids);
        let nm = self.n_materials;
        let bodies = &self.bodies;
        let (slots, pair_history): (Vec<Slot>, Vec<V3>) = pairs
            .par_iter()
            .with_min_len(PAIR_CHUNK)
            .map(|&(i, j, _)| {
                let (a, b) = (&bodies[i as usize], &bodies[j as usize]);
                let history = history(i, j);
                let slot = Slot {
                    i,
                    j,
                    material: (a.material * nm + b.material) as u32,
                    touching: history != V3::zeros(),
                };
                (slot, history)
            })
            .unzip();
        drop(history);
        (self.slots, self.pair_history) = (slots, pair_history);
        self.pair_shift.clear();
        if self.periodic.is_some() {
            self.pair_shift
                .par_extend(pairs.par_iter().with_min_len(PAIR_CHUNK).map(|p| p.2));
        }
        self.out.clear();
        self.out.resize(self.slots.len(), ContactForce::default());
        self.films.clear();
        if self.lubrication.is_some() {
            self.films.resize(self.slots.len(), V3::zeros());
        }
        self.build_adjacency();
        self.list_walls(self.skin + reach);
        self.x_at_build = x;
        self.ids_at_build = ids;
        self.peak_drift2 = 0.0;
        self.stale = false;
        self.builds += 1;
        self.build_seconds += start.elapsed().as_secs_f64();
    }

    /// The contact history a new pair (i, j) carries over from the pairs touching at the last
    /// build (zero for the others): looked up by index in the old lists when every sphere kept
    /// its index (`insert` and `pop` add and remove at the end), else by the spheres' ids (the
    /// history's sign turned when their order did).
    fn carried_history(&self, ids: &[u64]) -> impl Fn(u32, u32) -> V3 + Sync + '_ {
        let common = ids.len().min(self.ids_at_build.len());
        let in_place = ids[..common] == self.ids_at_build[..common];
        let by_ids: HashMap<(u64, u64), V3> = if in_place {
            HashMap::new()
        } else {
            self.slots
                .iter()
                .zip(&self.pair_history)
                .filter(|(s, _)| s.touching)
                .filter_map(|(s, h)| {
                    let (a, b) = (
                        self.ids_at_build.get(s.i as usize)?,
                        self.ids_at_build.get(s.j as usize)?,
                    );
                    Some(((*a, *b), *h))
                })
                .collect()
        };
        let ids = ids.to_vec();
        move |i, j| {
            if in_place {
                if j as usize >= common {
                    return V3::zeros();
                }
                let first = self.first_i[i as usize] as usize;
                let own = &self.slots[first..self.first_i[i as usize + 1] as usize];
                return own
                    .binary_search_by_key(&j, |s| s.j)
                    .map_or_else(|_| V3::zeros(), |k| self.pair_history[first + k]);
            }
            let (a, b) = (ids[i as usize], ids[j as usize]);
            by_ids
                .get(&(a, b))
                .copied()
                .or_else(|| by_ids.get(&(b, a)).map(|h| -h))
                .unwrap_or_else(V3::zeros)
        }
    }

    /// Lists per sphere the walls it can reach after moving less than `margin`; the walls out of
    /// reach until the next build are apart now: their history is zero, as the contact loop would
    /// set it.
    fn list_walls(&mut self, margin: f64) {
        let w = self.walls.len();
        self.wall_history
            .resize(self.bodies.len() * w.max(1), V3::zeros());
        let walls = &self.walls;
        let lists: Vec<(Vec<u32>, Vec<u32>)> = self
            .bodies
            .par_chunks(CHUNK)
            .zip(self.wall_history.par_chunks_mut(CHUNK * w.max(1)))
            .map(|(bodies, history)| {
                let (mut near, mut counts) = (Vec::new(), Vec::with_capacity(bodies.len()));
                for (b, h) in bodies.iter().zip(history.chunks_mut(w.max(1))) {
                    let before = near.len();
                    for (l, wall) in walls.iter().enumerate() {
                        if wall.near(b.x, b.r, margin) {
                            near.push(l as u32);
                        } else {
                            h[l] = V3::zeros();
                        }
                    }
                    counts.push((near.len() - before) as u32);
                }
                (near, counts)
            })
            .collect();
        self.near_start.clear();
        self.near_start.push(0);
        self.near.clear();
        for (near, counts) in lists {
            self.near.extend_from_slice(&near);
            for c in counts {
                self.near_start.push(self.near_start.last().unwrap() + c);
            }
        }
    }

    /// The slots of each body: as i a contiguous range (the slots are sorted by i), as j a list.
    fn build_adjacency(&mut self) {
        let n = self.bodies.len();
        let (first_i, start, as_j) = (&mut self.first_i, &mut self.as_j_start, &mut self.as_j);
        for counts in [&mut *first_i, &mut *start] {
            counts.clear();
            counts.resize(n + 1, 0);
        }
        for s in &self.slots {
            first_i[s.i as usize + 1] += 1;
            start[s.j as usize + 1] += 1;
        }
        for k in 0..n {
            first_i[k + 1] += first_i[k];
            start[k + 1] += start[k];
        }
        let mut fill = start.clone();
        as_j.clear();
        as_j.resize(self.slots.len(), 0);
        for (k, s) in self.slots.iter().enumerate() {
            as_j[fill[s.j as usize] as usize] = k as u32;
            fill[s.j as usize] += 1;
        }
    }

    /// Contact forces and torques at the present positions; `dt` advances the contact histories;
    /// `finish` says what the same pass does next. Returns the largest squared displacement since
    /// the last neighbour-list build after a drift (else 0).
    fn forces(&mut self, dt: f64, finish: Finish) -> f64 {
        if self.needs_rebuild() {
            self.rebuild();
        }
        let law = self.law;
        let (pair_contacts, (wall_contacts, moved)) = if law == ContactLaw::LIGGGHTS_HERTZ {
            let pair_contacts = self.pair_forces(LiggghtsHertz, dt);
            (
                pair_contacts,
                self.gather(LiggghtsHertz, dt, finish, pair_contacts),
            )
        } else {
            let pair_contacts = self.pair_forces(AnyLaw(&law), dt);
            (
                pair_contacts,
                self.gather(AnyLaw(&law), dt, finish, pair_contacts),
            )
        };
        self.contacts = pair_contacts + wall_contacts;
        moved
    }

    /// Sphere-sphere contacts and squeeze films, in parallel over chunks of the Verlet pairs (a
    /// plain loop in each chunk; the film of a pair from the same separation and velocities as
    /// its contact, in the same pass); returns how many touch. In a world of `compact_from`
    /// spheres or more, from a compact copy of their motion, recording which pairs touch.
    fn pair_forces<L: LawRef>(&mut self, law: L, dt: f64) -> usize {
        let compact = self.compact();
        self.touch.resize(self.slots.len(), false);
        let lists = PairLists {
            slots: &mut self.slots,
            history: &mut self.pair_history,
            shifts: &self.pair_shift,
            out: &mut self.out,
            films: &mut self.films,
            touch: &mut self.touch,
        };
        let (pm, lubrication) = (&self.pair_materials[..], self.lubrication);
        if !compact {
            self.kin.clear();
            let pass = PairPass {
                motion: &self.bodies[..],
                law,
                pm,
                lubrication,
                dt,
            };
            return pair_pass(&pass, lists);
        }
        self.kin.clear();
        self.kin
            .par_extend(self.bodies.par_iter().with_min_len(CHUNK).map(Kin::of));
        let pass = PairPass {
            motion: &self.kin[..],
            law,
            pm,
            lubrication,
            dt,
        };
        pair_pass(&pass, lists)
    }

    /// Sums the pair forces and adds the wall contacts, in parallel over chunks of the bodies;
    /// returns the number of wall contacts and the largest squared displacement since the last
    /// build (after a drift). Each body sums its pairs in slot order (first as j, then as i), then
    /// its walls.
    fn gather<L: LawRef>(&mut self, law: L, dt: f64, finish: Finish, pair_contacts: usize) -> (usize, f64) {
        let w = self.walls.len().max(1);
        let ctx = Gather {
            dt,
            finish,
            g: self.gravity,
            out: &self.out,
            touch: (self.compact() && 2 * pair_contacts < self.slots.len()).then_some(&self.touch[..]),
            films: &self.films,
            lubrication: self.lubrication,
            first_i: &self.first_i,
            as_j: &self.as_j,
            as_j_start: &self.as_j_start,
            near: &self.near,
            near_start: &self.near_start,
            walls: &self.walls,
            law,
            pm: &self.pair_materials,
            nm: self.n_materials,
        };
        self.bodies
            .par_chunks_mut(CHUNK)
            .zip(self.wall_history.par_chunks_mut(CHUNK * w))
            .zip(self.x_at_build.par_chunks(CHUNK))
            .enumerate()
            .map(|(c, ((bodies, hist), x0))| {
                let mut acc = (0, 0.0f64);
                for (m, ((b, h), x0)) in bodies.iter_mut().zip(hist.chunks_mut(w)).zip(x0).enumerate() {
                    let (touching, moved) = ctx.body(c * CHUNK + m, b, h, x0);
                    acc = (acc.0 + touching, acc.1.max(moved));
                }
                acc
            })
            .reduce(|| (0, 0.0), |a, b| (a.0 + b.0, a.1.max(b.1)))
    }

    /// The pair material of two material indices (for the time-step rule).
    pub fn pair(&self, a: usize, b: usize) -> PairMaterial {
        *self.pair_material(a, b)
    }
}

/// A pair that stopped touching forgets its tangential history and its force.
fn apart(s: &mut Slot, history: &mut V3, out: &mut ContactForce) {
    if s.touching {
        s.touching = false;
        *history = V3::zeros();
        *out = ContactForce::default();
    }
}

/// What the pair pass reads.
struct PairPass<'a, L, K> {
    motion: &'a [K],
    law: L,
    pm: &'a [PairMaterial],
    lubrication: Option<Lubrication>,
    dt: f64,
}

impl<L: LawRef, K: Motion> PairPass<'_, L, K> {
    /// The separation x_i - x_j of a pair (`shifts[m]` its periodic shift, none when empty), and
    /// with lubrication its squeeze film into `films[m]`.
    #[inline(always)]
    fn separation(&self, a: &K, b: &K, shifts: &[V3], films: &mut [V3], m: usize) -> V3 {
        let d = match shifts.get(m) {
            Some(shift) => a.x() - b.x() - shift,
            None => a.x() - b.x(),
        };
        if let Some(lub) = &self.lubrication {
            let r_sum = r_sum(a, b);
            // Beyond the cut-off the film is zero (`pair_force` would say so): R* only within it.
            films[m] = if d.norm() - r_sum >= lub.cutoff {
                V3::zeros()
            } else {
                lub.pair_force(d, a.v() - b.v(), r_sum, r_eff(a, b))
            };
        }
        d
    }

    /// One Verlet pair: its contact force into `out` (zero when apart), its film into `films[m]`;
    /// 1 when touching.
    #[inline(always)]
    fn pair_force(&self, s: &mut Slot, history: &mut V3, out: &mut ContactForce, lists: PairRow) -> usize {
        let PairRow { shifts, films, m } = lists;
        let (a, b) = (&self.motion[s.i as usize], &self.motion[s.j as usize]);
        let d = self.separation(a, b, shifts, films, m);
        let Some((n, overlap)) = contact_geometry(d, r_sum(a, b)) else {
            apart(s, history, out);
            return 0;
        };
        let c = Contact {
            n,
            overlap,
            r_i: a.r(),
            r_j: b.r(),
            r_eff: r_eff(a, b),
            m_eff: m_eff(a, b),
            dv: a.v() - b.v(),
            w_i: a.w(),
            w_j: b.w(),
        };
        s.touching = true;
        let law = self.law.law();
        *out = contact_force(law, &self.pm[s.material as usize], &c, history, self.dt);
        1
    }
}

/// Where a pair's shift and film are in its chunk's lists.
struct PairRow<'a> {
    shifts: &'a [V3],
    films: &'a mut [V3],
    m: usize,
}

/// The pair lists a pair pass writes (and the shifts it reads), or one chunk of them.
struct PairLists<'a> {
    slots: &'a mut [Slot],
    history: &'a mut [V3],
    /// Empty in a world without periodic axes.
    shifts: &'a [V3],
    out: &'a mut [ContactForce],
    /// Empty in a dry world.
    films: &'a mut [V3],
    touch: &'a mut [bool],
}

/// A list's chunks of `PAIR_CHUNK` pairs, as many empty slices where the list is empty.
fn chunks_or_empty<'a>(list: &'a [V3], chunks: usize) -> impl IndexedParallelIterator<Item = &'a [V3]> + 'a {
    match list.is_empty() {
        false => Either::Left(list.par_chunks(PAIR_CHUNK)),
        true => Either::Right((0..chunks).into_par_iter().map(|_| &[][..])),
    }
}

/// The pair pass: contacts and films of every listed pair, in parallel over chunks of them, and
/// whether each touches into `touch`; returns how many touch.
fn pair_pass<L: LawRef, K: Motion>(pass: &PairPass<L, K>, lists: PairLists) -> usize {
    // A dry world has no films, one without periodic axes no shifts: empty slices then.
    let chunks = lists.slots.len().div_ceil(PAIR_CHUNK);
    let films = match pass.lubrication {
        Some(_) => Either::Left(lists.films.par_chunks_mut(PAIR_CHUNK)),
        None => Either::Right((0..chunks).into_par_iter().map(|_| &mut [][..])),
    };
    lists
        .slots
        .par_chunks_mut(PAIR_CHUNK)
        .zip(lists.history.par_chunks_mut(PAIR_CHUNK))
        .zip(chunks_or_empty(lists.shifts, chunks))
        .zip(lists.out.par_chunks_mut(PAIR_CHUNK))
        .zip(films)
        .zip(lists.touch.par_chunks_mut(PAIR_CHUNK))
        // One batch per worker's run of chunks (zeroing one per chunk cost a tenth of the pass).
        .map_init(
            || L::BATCHED.then(Batch::default),
            |batch, (((((slots, history), shifts), out), films), touch)| {
                let chunk = PairLists {
                    slots,
                    history,
                    shifts,
                    out,
                    films,
                    touch,
                };
                match batch {
                    Some(batch) => pair_forces_batched(pass, batch, chunk),
                    None => pair_forces_each(pass, chunk),
                }
            },
        )
        .sum()
}

/// The pairs of a chunk one by one (`PairPass::pair_force`); returns how many touch.
fn pair_forces_each<L: LawRef, K: Motion>(pass: &PairPass<L, K>, chunk: PairLists) -> usize {
    let mut touching = 0;
    for m in 0..chunk.slots.len() {
        let row = PairRow {
            shifts: chunk.shifts,
            films: &mut *chunk.films,
            m,
        };
        let s = &mut chunk.slots[m];
        touching += pass.pair_force(s, &mut chunk.history[m], &mut chunk.out[m], row);
        if K::TOUCH {
            chunk.touch[m] = s.touching;
        }
    }
    touching
}

/// The pairs of a chunk with `ContactLaw::LIGGGHTS_HERTZ`: the geometry per pair, the law in
/// batches of touching pairs (`batch.rs`, the same bits as `pair_force`); returns how many touch.
fn pair_forces_batched<L: LawRef, K: Motion>(
    pass: &PairPass<L, K>,
    batch: &mut Batch,
    chunk: PairLists,
) -> usize {
    let PairLists {
        slots,
        history,
        shifts,
        out: outs,
        films,
        touch,
    } = chunk;
    let (motion, pm, dt) = (pass.motion, pass.pm, pass.dt);
    let damping = ContactLaw::LIGGGHTS_HERTZ.switches.damping as usize;
    batch.len = 0;
    let flush = |batch: &mut Batch, history: &mut [V3], outs: &mut [ContactForce]| {
        batch.run(dt);
        for k in 0..batch.len {
            let m = batch.slot[k] as usize;
            let (force, torque_i, torque_j, h) = batch.result(k);
            outs[m] = ContactForce {
                force,
                torque_i,
                torque_j,
            };
            history[m] = h;
        }
        batch.len = 0;
    };
    let mut touching = 0;
    for m in 0..slots.len() {
        let s = &mut slots[m];
        let (a, b) = (&motion[s.i as usize], &motion[s.j as usize]);
        let d = pass.separation(a, b, shifts, films, m);
        let Some(geometry) = contact_geometry(d, r_sum(a, b)) else {
            apart(s, &mut history[m], &mut outs[m]);
            if K::TOUCH {
                touch[m] = false;
            }
            continue;
        };
        let mat = &pm[s.material as usize];
        queue_contact(batch, m, geometry, [a, b], mat, history[m], damping);
        s.touching = true;
        if K::TOUCH {
            touch[m] = true;
        }
        touching += 1;
        if batch.len == LANES {
            flush(batch, history, outs);
        }
    }
    if batch.len > 0 {
        flush(batch, history, outs);
    }
    touching
}

/// The unit normal (from j to i) and the overlap of two spheres whose centres are `d` = x_i - x_j
/// apart and whose radii sum to `r_sum`; None where they do not touch.
#[inline(always)]
fn contact_geometry(d: V3, r_sum: f64) -> Option<(V3, f64)> {
    let dist2 = d.norm_squared();
    if dist2 >= r_sum * r_sum {
        return None;
    }
    let dist = dist2.sqrt();
    let overlap = r_sum - dist;
    if overlap <= 0.0 {
        return None;
    }
    let n = if dist > 0.0 { d / dist } else { V3::z() };
    Some((n, overlap))
}

/// Puts the contact of pair `m` (its normal and overlap, spheres `a` and `b`, pair material
/// `mat`, tangential history `h`) in the batch's next lane; `damping` the law's damping switch.
#[inline(always)]
fn queue_contact<K: Motion>(
    batch: &mut Batch,
    m: usize,
    (n, overlap): (V3, f64),
    [a, b]: [&K; 2],
    mat: &PairMaterial,
    h: V3,
    damping: usize,
) {
    let k = batch.len;
    batch.slot[k] = m as u32;
    (batch.nx[k], batch.ny[k], batch.nz[k]) = (n.x, n.y, n.z);
    batch.overlap[k] = overlap;
    (batch.r_i[k], batch.r_j[k]) = (a.r(), b.r());
    (batch.r_eff[k], batch.m_eff[k]) = (r_eff(a, b), m_eff(a, b));
    let dv = a.v() - b.v();
    (batch.dvx[k], batch.dvy[k], batch.dvz[k]) = (dv.x, dv.y, dv.z);
    let (wi, wj) = (a.w(), b.w());
    (batch.wix[k], batch.wiy[k], batch.wiz[k]) = (wi.x, wi.y, wi.z);
    (batch.wjx[k], batch.wjy[k], batch.wjz[k]) = (wj.x, wj.y, wj.z);
    (batch.hx[k], batch.hy[k], batch.hz[k]) = (h.x, h.y, h.z);
    batch.y_star[k] = mat.y_star;
    batch.g_star[k] = mat.g_star;
    batch.damping[k] = mat.damping_factor[damping];
    batch.shear_to_normal[k] = mat.shear_to_normal_sqrt;
    batch.friction[k] = mat.friction;
    batch.len += 1;
}

/// What the gather pass reads.
struct Gather<'a, L> {
    dt: f64,
    finish: Finish,
    g: V3,
    out: &'a [ContactForce],
    /// Which pairs touch, where few do (below half the listed pairs): the others are skipped.
    touch: Option<&'a [bool]>,
    films: &'a [V3],
    lubrication: Option<Lubrication>,
    first_i: &'a [u32],
    as_j: &'a [u32],
    as_j_start: &'a [u32],
    near: &'a [u32],
    near_start: &'a [u32],
    walls: &'a [Wall],
    law: L,
    pm: &'a [PairMaterial],
    nm: usize,
}

impl<L: LawRef> Gather<'_, L> {
    /// The walls body k can reach before the next neighbour-list build.
    fn near_walls(&self, k: usize) -> &[u32] {
        &self.near[self.near_start[k] as usize..self.near_start[k + 1] as usize]
    }

    /// The film forces of body k's pairs: as j, then as i (its slots `own`).
    fn pair_films(&self, k: usize, own: std::ops::Range<usize>) -> V3 {
        let as_j = &self.as_j[self.as_j_start[k] as usize..self.as_j_start[k + 1] as usize];
        let pulled: V3 = as_j.iter().map(|&slot| self.films[slot as usize]).sum();
        self.films[own].iter().sum::<V3>() - pulled
    }

    /// The contact force and torque of body k's pairs: as j, then as i (its slots `own`); with
    /// `touch`, only the touching pairs (the others' are zero: adding them changes nothing).
    #[inline(always)]
    fn pair_contacts(&self, k: usize, own: std::ops::Range<usize>) -> (V3, V3) {
        let (out, as_j) = (
            self.out,
            &self.as_j[self.as_j_start[k] as usize..self.as_j_start[k + 1] as usize],
        );
        let (mut f, mut t) = (V3::zeros(), V3::zeros());
        match self.touch {
            Some(touch) => {
                for &slot in as_j.iter().filter(|&&slot| touch[slot as usize]) {
                    let o = &out[slot as usize];
                    f += -o.force;
                    t += o.torque_j;
                }
                for (o, _) in out[own.clone()].iter().zip(&touch[own]).filter(|(_, &on)| on) {
                    f += o.force;
                    t += o.torque_i;
                }
            }
            None => {
                for &slot in as_j {
                    let o = &out[slot as usize];
                    f += -o.force;
                    t += o.torque_j;
                }
                for o in &out[own] {
                    f += o.force;
                    t += o.torque_i;
                }
            }
        }
        (f, t)
    }

    /// Body k: pair forces, wall contacts, then `finish`; returns (wall contacts, squared
    /// displacement since the last build after a drift, else 0).
    #[inline(always)]
    fn body(&self, k: usize, b: &mut Body, hist: &mut [V3], x0: &V3) -> (usize, f64) {
        let (dt, g) = (self.dt, self.g);
        let own = self.first_i[k] as usize..self.first_i[k + 1] as usize;
        let (mut f, mut t) = self.pair_contacts(k, own.clone());
        if self.lubrication.is_some() {
            f += self.pair_films(k, own);
        }
        let mut touching = 0;
        for &l in self.near_walls(k) {
            let (wall, h) = (&self.walls[l as usize], &mut hist[l as usize]);
            let Some((n, gap)) = wall.separation(b.x, b.r) else {
                *h = V3::zeros();
                continue;
            };
            if gap >= 0.0 {
                // Apart: no contact; with lubrication, the squeeze film (R* = r) below its cut-off.
                *h = V3::zeros();
                if let Some(lub) = &self.lubrication {
                    f += n * lub.film_force(b.r, gap, -b.v.dot(&n));
                }
                continue;
            }
            let c = Contact {
                n,
                overlap: -gap,
                r_i: b.r,
                r_j: 0.0,
                r_eff: self.law.law().switches.wall_radius_factor * b.r,
                m_eff: b.m,
                dv: b.v,
                w_i: b.w,
                w_j: V3::zeros(),
            };
            let out = contact_force(
                self.law.law(),
                &self.pm[b.material * self.nm + wall.material],
                &c,
                h,
                dt,
            );
            f += out.force;
            t += out.torque_i;
            touching += 1;
        }
        b.f = f;
        b.t = t;
        b.f_ext += dt * b.f_ext_rate;
        b.t_ext += dt * b.t_ext_rate;
        b.contact_impulse += dt * b.f;
        b.contact_angular_impulse += dt * b.t;
        match self.finish {
            Finish::Nothing => (touching, 0.0),
            Finish::HalfKick => {
                b.kick(0.5 * dt, g);
                (touching, 0.0)
            }
            Finish::KickDrift => {
                // Two half kicks with the same acceleration (computed once: the same bits).
                let (dv, dw) = b.half_kick(0.5 * dt, g);
                b.v += dv;
                b.w += dw;
                b.v += dv;
                b.w += dw;
                b.x += dt * b.v;
                (touching, (b.x - x0).norm_squared())
            }
        }
    }
}
