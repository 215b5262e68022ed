//! The neighbour lists: the Verlet pairs (slots, with the contact histories they carry over a
//! rebuild), each sphere's slots as i and as j, and when they are rebuilt. The walls each sphere
//! can reach are listed with them (`walls.rs`).

use super::pairs::Slot;
use super::{World, PAIR_CHUNK, V3};
use crate::dem::contact::ContactForce;
use crate::dem::neighbor::{periodic_pairs, verlet_pairs};
use rayon::prelude::*;
use std::collections::HashMap;

impl World {
    /// Has some sphere moved more than skin / 2 since the last build (or the set changed)? Every
    /// drift (`open_step`, the gather's `KickDrift`) measures the largest displacement since the
    /// build and marks the list stale beyond skin / 2, so no scan is needed here.
    pub(super) fn needs_rebuild(&self) -> bool {
        self.stale
            || self.x_at_build.len() != self.bodies.len()
            || self.wall_history.len() != self.bodies.len() * self.walls.len().max(1)
    }

    /// Rebuilds the Verlet list, carrying the history of the pairs still listed, and the walls
    /// each sphere can reach.
    pub(super) fn rebuild(&mut self) {
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
        self.list_pairs(&pairs, &ids);
        self.build_adjacency();
        self.list_walls(self.skin + reach);
        self.x_at_build = x;
        self.ids_at_build = ids;
        self.peak_drift2 = 0.0;
        self.stale = false;
        self.builds += 1;
        self.build_seconds += start.elapsed().as_secs_f64();
    }

    /// The pair lists of the Verlet pairs `pairs` (i, j, periodic shift), the spheres' ids now
    /// `ids`: slots, carried histories, shifts, and zero forces and films.
    fn list_pairs(&mut self, pairs: &[(u32, u32, V3)], ids: &[u64]) {
        let history = self.carried_history(ids);
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

    /// The slots of each body: as i a contiguous range (the slots are sorted by i), as j a list.
    pub(super) fn build_adjacency(&mut self) {
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
}
