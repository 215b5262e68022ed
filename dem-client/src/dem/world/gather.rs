//! The gather pass: per sphere, in parallel over chunks of the bodies, the sum of its pairs'
//! contact and film forces, its wall contacts (the wall pass, `walls.rs`) and its integration
//! (`Body::integrate`), in one pass over the bodies.

use super::bodies::{Body, Finish};
use super::walls::WallPass;
use super::{LawRef, World, CHUNK, V3};
use crate::dem::contact::ContactForce;
use crate::dem::lubrication::SqueezeFilm;
use rayon::prelude::*;

impl World {
    /// The gather pass, in parallel over chunks of the bodies: each sums its pair forces, adds its
    /// wall contacts (the wall pass) and integrates (`finish`); returns the number of wall contacts
    /// and the largest squared displacement since the last build (after a drift). Each body sums
    /// its pairs in slot order (first as j, then as i), then its walls.
    pub(super) fn gather<L: LawRef>(
        &mut self,
        law: L,
        dt: f64,
        finish: Finish,
        pair_contacts: usize,
    ) -> (usize, f64) {
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
            walls: WallPass {
                walls: &self.walls,
                law,
                pm: &self.pair_materials,
                nm: self.n_materials,
                lubrication: self.lubrication,
                dt,
            },
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
    lubrication: Option<SqueezeFilm>,
    first_i: &'a [u32],
    as_j: &'a [u32],
    as_j_start: &'a [u32],
    near: &'a [u32],
    near_start: &'a [u32],
    walls: WallPass<'a, L>,
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

    /// Body k: the sums over its contacts of f_ij (eq. 12) and l_ij x f_ij (eq. 13), pairs then
    /// walls (the wall pass), then `finish` (`Body::integrate`); returns (wall contacts, squared
    /// displacement since the last build after a drift, else 0).
    #[inline(always)]
    fn body(&self, k: usize, b: &mut Body, hist: &mut [V3], x0: &V3) -> (usize, f64) {
        let own = self.first_i[k] as usize..self.first_i[k + 1] as usize;
        let (mut f, mut t) = self.pair_contacts(k, own.clone());
        if self.lubrication.is_some() {
            f += self.pair_films(k, own);
        }
        let touching = self.walls.contacts(b, self.near_walls(k), hist, &mut f, &mut t);
        b.f = f;
        b.t = t;
        (touching, b.integrate(self.dt, self.g, self.finish, x0))
    }
}
