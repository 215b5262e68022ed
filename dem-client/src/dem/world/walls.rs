//! The walls: their shapes, the walls each sphere can reach (listed at each neighbour-list build),
//! and the wall pass (each sphere's contacts with them, within the gather).

use super::bodies::Body;
use super::{LawRef, World, CHUNK, V3};
use crate::dem::contact::{contact_force, Contact, ContactForce, PairMaterial};
use crate::dem::lubrication::SqueezeFilm;
use rayon::prelude::*;

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
    pub(super) fn separation(&self, x: V3, r: f64) -> Option<(V3, f64)> {
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

impl World {
    /// Lists per sphere the walls it can reach after moving less than `margin`; the walls out of
    /// reach until the next build are apart now: their history is zero, as the contact loop would
    /// set it.
    pub(super) fn list_walls(&mut self, margin: f64) {
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
}

/// What the wall pass reads.
pub(super) struct WallPass<'a, L> {
    pub walls: &'a [Wall],
    pub law: L,
    /// Pair materials, `nm x nm`.
    pub pm: &'a [PairMaterial],
    pub nm: usize,
    pub lubrication: Option<SqueezeFilm>,
    pub dt: f64,
}

impl<L: LawRef> WallPass<'_, L> {
    /// The wall pass of sphere `b`: its contact with each wall `near` it (its wall histories
    /// `hist`, a squeeze film where apart with lubrication), added to its force `f` and torque `t`
    /// in wall order; returns how many walls it touches.
    #[inline(always)]
    pub fn contacts(&self, b: &Body, near: &[u32], hist: &mut [V3], f: &mut V3, t: &mut V3) -> usize {
        let mut touching = 0;
        for &l in near {
            let (wall, h) = (&self.walls[l as usize], &mut hist[l as usize]);
            let Some((n, gap)) = wall.separation(b.x, b.r) else {
                *h = V3::zeros();
                continue;
            };
            if gap >= 0.0 {
                // Apart: no contact; with lubrication, the squeeze film (R* = r) below its cut-off.
                *h = V3::zeros();
                if let Some(lub) = &self.lubrication {
                    *f += n * lub.film_force(b.r, gap, -b.v.dot(&n));
                }
                continue;
            }
            let out = self.contact(b, wall, n, -gap, h);
            *f += out.force;
            *t += out.torque_i;
            touching += 1;
        }
        touching
    }

    /// The contact law between sphere `b` and `wall` (unit normal `n` from the wall, `overlap`,
    /// history `h`): a sphere against a body of R* = factor r and m* = m at rest.
    #[inline(always)]
    fn contact(&self, b: &Body, wall: &Wall, n: V3, overlap: f64, h: &mut V3) -> ContactForce {
        let c = Contact {
            n,
            overlap,
            r_i: b.r,
            r_j: 0.0,
            r_eff: self.law.law().switches.wall_radius_factor * b.r,
            m_eff: b.m,
            dv: b.v,
            w_i: b.w,
            w_j: V3::zeros(),
        };
        let pm = &self.pm[b.material * self.nm + wall.material];
        contact_force(self.law.law(), pm, &c, h, self.dt)
    }
}
