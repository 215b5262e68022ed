//! The pair pass: the contact and squeeze film of every Verlet pair, in parallel over chunks of
//! the pairs, from the spheres' bodies or a compact copy of their motion (`Kin`); with
//! `ContactLaw::LIGGGHTS_HERTZ` the contacts in batches (`batch.rs`).

use super::bodies::Body;
use super::{LawRef, World, CHUNK, PAIR_CHUNK, V3};
use crate::dem::batch::{Batch, LANES};
use crate::dem::contact::{contact_force, Contact, ContactForce, ContactLaw, PairMaterial};
use crate::dem::lubrication::SqueezeFilm;
use rayon::iter::Either;
use rayon::prelude::*;

/// A pair of the Verlet list: its spheres, their pair material and whether they touch. Not
/// touching implies a zero history in `World::pair_history` and a zero force in `World::out` (so a
/// pair that stays apart costs no writes). 16 bytes, read by every pair pass: the constants that
/// follow from the radii and masses (r_i + r_j, R*, m*) are computed where a pass needs them, and
/// the history (24 bytes) and the periodic shift (24) are kept apart, read only by the pairs that
/// touch and in periodic worlds. A 32^3 bed lists 280,000 pairs, of which 2-14,000 touch; with
/// 104 bytes a pair read every DEM step (history and constants with the pair) its pair pass was
/// 70% of the step, and this layout took 10-12% off the step (docs/dem.md, "Throughput").
#[derive(Debug, Clone, Copy)]
pub(super) struct Slot {
    pub i: u32,
    pub j: u32,
    /// Index into the pair materials.
    pub material: u32,
    pub touching: bool,
}

/// The constants of a pair that follow from the spheres' radii and masses, with the same
/// expressions wherever they are needed (so the same bits).
#[inline(always)]
pub(super) fn r_sum(a: &impl Motion, b: &impl Motion) -> f64 {
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

/// What the pair pass reads of a sphere, copied from the bodies before each pass in a world of
/// `COMPACT_FROM` spheres or more: 88 bytes a sphere where a `Body` is 320. The pass visits each
/// sphere once per listed pair, and through the bodies it pulled a 32^3 bed's 10.5 MB through the
/// caches every DEM step (the copy reads them once, in order).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Kin {
    x: V3,
    v: V3,
    w: V3,
    r: f64,
    m: f64,
}

/// A sphere's motion as the pair pass reads it: a `Body` or its `Kin`.
pub(super) trait Motion: Sync {
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

impl World {
    /// Sphere-sphere contacts and squeeze films, in parallel over chunks of the Verlet pairs (a
    /// plain loop in each chunk; the film of a pair from the same separation and velocities as
    /// its contact, in the same pass); returns how many touch. In a world of `compact_from`
    /// spheres or more, from a compact copy of their motion, recording which pairs touch.
    pub(super) fn pair_forces<L: LawRef>(&mut self, law: L, dt: f64) -> usize {
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
    lubrication: Option<SqueezeFilm>,
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

    /// One Verlet pair: its contact force f_ij (eq. 12) and torques l_ij x f_ij (eq. 13) into
    /// `out` (zero when apart), its film into `films[m]`; 1 when touching.
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
            flush(batch, dt, history, outs);
        }
    }
    if batch.len > 0 {
        flush(batch, dt, history, outs);
    }
    touching
}

/// Runs the law over the batch's contacts and writes their forces and histories back to their
/// pairs; empties the batch.
#[inline(always)]
fn flush(batch: &mut Batch, dt: f64, history: &mut [V3], outs: &mut [ContactForce]) {
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
