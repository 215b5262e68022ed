//! Free flight (docs/dem.md "Free flight"): in a fluid step a sphere that can touch nothing (no
//! sphere, no wall, no squeeze film within reach) moves in one exact step of its free motion
//! (`Body::fly`); the spheres that can touch something, the island, take the DEM's sub-steps among
//! themselves.
//!
//! Each sphere's travel over the step is bounded by `FREE_FLIGHT_MARGIN` span (|v| + span a_max)
//! (a_max: `Body::acceleration_bound`, valid while it touches nothing). A sphere of the island can
//! be thrown by its contacts, so it is given a reach, `ISLAND_REACH` skin, and a sphere flies only
//! when its gap to every island sphere exceeds the films' cut-off by its travel plus that reach;
//! the island's own world leaves out its pairs farther apart than the cut-off plus two reaches
//! (they cannot meet); after the island's sub-steps, if one of its spheres went further than its
//! reach, the step is taken again with every sphere sub-stepped (the island is a copy: nothing to
//! undo).

use super::everyone::Way;
use super::{Body, World, CHUNK, PAIR_CHUNK, V3};
use rayon::prelude::*;
use std::time::Instant;

/// Safety factor on a sphere's travel bound in free flight (the bound is exact for the motion it
/// assumes; the margin covers the step's discretisation).
const FREE_FLIGHT_MARGIN: f64 = 1.5;
/// How far a sphere of the island may move within a fluid step, as a fraction of the skin (below
/// half the skin, where the neighbour lists end).
const ISLAND_REACH: f64 = 0.25;
/// A sphere outside the island.
const FLYING: u32 = u32::MAX;

/// An island's world, the slots of its pairs in the whole world and each sphere's index in the
/// island, kept by the world between fluid steps so that their vectors are refilled, not made
/// anew (`World::split_off`).
pub(super) struct Spare {
    part: World,
    slots: Vec<u32>,
    local: Vec<u32>,
}

impl Spare {
    /// Empty, with the pair materials of `world`'s islands (`split_off` sets the rest).
    fn for_islands_of(world: &World) -> Spare {
        let part = World::bare(
            Vec::new(),
            world.walls.clone(),
            world.law,
            world.pair_materials.clone(),
            world.n_materials,
            world.gravity,
            world.dt,
            world.skin,
        );
        Spare {
            part,
            slots: Vec::new(),
            local: Vec::new(),
        }
    }
}

/// a > b, false when a is NaN (a NaN gap is never clear).
fn exceeds(a: f64, b: f64) -> bool {
    a > b
}

/// How a fluid step is advanced.
enum Plan {
    /// Every sphere in one exact step.
    Fly,
    /// These spheres (ascending) in sub-steps among themselves, the others in one exact step.
    Island(Vec<u32>),
    /// Every sphere in sub-steps.
    Substep,
}

impl World {
    /// Advances a fluid step of `span` seconds: the spheres that can touch nothing within it in
    /// one exact step of their free motion, the others (the island) in `steps` DEM steps among
    /// themselves (possibly every sphere), or every sphere in DEM steps with the whole lists when
    /// one of the island's spheres went, or would by its speed alone go, further than its reach.
    /// Returns how many spheres flew.
    pub fn advance_span(&mut self, span: f64, steps: u64) -> usize {
        match self.flight_plan(span) {
            Plan::Fly => {
                self.fly(span);
                self.bodies.len()
            }
            Plan::Island(island) if island.len() == self.bodies.len() => {
                // The same bits either way (`everyone`): the quicker on this machine.
                let (way, start) = (self.everyone.next(), Instant::now());
                if way == Way::Whole {
                    self.advance(steps);
                } else if self.advance_island(&island, span, steps) {
                    self.islands += 1;
                } else {
                    self.dropped_islands += 1;
                    self.advance(steps);
                }
                self.everyone.record(way, start.elapsed().as_secs_f64());
                0
            }
            Plan::Island(island) => {
                if self.advance_island(&island, span, steps) {
                    self.islands += 1;
                    return self.bodies.len() - island.len();
                }
                self.dropped_islands += 1;
                self.advance(steps);
                0
            }
            Plan::Substep => {
                self.advance(steps);
                0
            }
        }
    }

    /// Who flies over the next `span` seconds. The neighbour lists must hold every pair and wall
    /// a sphere can reach: they are rebuilt first when a sphere's drift since the last build plus
    /// its travel could exceed skin / 2, and again when an island sphere's drift plus the
    /// island's reach could; nobody flies when the travel over the span alone could.
    fn flight_plan(&mut self, span: f64) -> Plan {
        let g = self.gravity;
        let travel: Vec<f64> = self
            .bodies
            .par_iter()
            .with_min_len(CHUNK)
            .map(|b| FREE_FLIGHT_MARGIN * span * (b.v.norm() + span * b.acceleration_bound(g)))
            .collect();
        let longest = travel.iter().copied().fold(0.0, f64::max);
        let half_skin = 0.5 * self.skin;
        if !(longest.is_finite() && longest < half_skin) {
            return Plan::Substep;
        }
        if self.needs_rebuild()
            || self.farthest((0..self.bodies.len()).into_par_iter(), |k| travel[k]) >= half_skin
        {
            self.rebuild();
        }
        let reach = ISLAND_REACH * self.skin;
        let mut rebuilt = false;
        loop {
            let seeds = self.seeds(&travel);
            if seeds.is_empty() {
                return Plan::Fly;
            }
            let island = self.island(seeds, &travel, reach);
            // An island sphere that its speed alone takes beyond its reach would have the island
            // dropped after all its sub-steps: sub-step everything at once.
            if island
                .iter()
                .any(|&k| span * self.bodies[k as usize].v.norm() > reach)
            {
                return Plan::Substep;
            }
            let members = island.par_iter().map(|&k| k as usize);
            if rebuilt || self.farthest(members, |_| reach) < half_skin {
                return Plan::Island(island);
            }
            self.rebuild();
            rebuilt = true;
        }
    }

    /// The largest distance one of `spheres` can be from where it was at the last
    /// neighbour-list build: its drift since then plus `ahead(k)`. The lists hold every pair and
    /// wall that can come within reach while it stays below skin / 2 for every sphere.
    fn farthest(
        &self,
        spheres: impl IndexedParallelIterator<Item = usize>,
        ahead: impl Fn(usize) -> f64 + Sync + Send,
    ) -> f64 {
        spheres
            .with_min_len(CHUNK)
            .map(|k| (self.bodies[k].x - self.x_at_build[k]).norm() + ahead(k))
            .reduce(|| 0.0, f64::max)
    }

    /// The gap between the spheres of slot `s` (negative: overlap).
    fn slot_gap(&self, s: usize) -> f64 {
        let slot = &self.slots[s];
        let (a, b) = (&self.bodies[slot.i as usize], &self.bodies[slot.j as usize]);
        let shift = self.pair_shift.get(s).copied().unwrap_or_else(V3::zeros);
        (a.x - b.x - shift).norm() - super::pairs::r_sum(a, b)
    }

    /// The spheres that could touch something, or come within the films' cut-off, if every sphere
    /// flew: both spheres of each listed pair whose gap does not exceed the cut-off by their two
    /// travels, and each sphere whose gap to a listed wall does not by its travel (with repeats).
    fn seeds(&self, travel: &[f64]) -> Vec<u32> {
        let reach = self.reach();
        let mut seeds: Vec<u32> = (0..self.slots.len())
            .into_par_iter()
            .with_min_len(PAIR_CHUNK)
            .filter(|&s| {
                let (i, j) = (self.slots[s].i as usize, self.slots[s].j as usize);
                !exceeds(self.slot_gap(s) - travel[i] - travel[j], reach)
            })
            .flat_map_iter(|s| [self.slots[s].i, self.slots[s].j])
            .collect();
        let by_walls: Vec<u32> = self
            .bodies
            .par_iter()
            .with_min_len(CHUNK)
            .enumerate()
            .filter(|&(k, b)| !self.walls_clear(k, b, travel[k] + reach))
            .map(|(k, _)| k as u32)
            .collect();
        seeds.extend(by_walls);
        seeds
    }

    /// Is sphere k's gap to every wall it lists above `margin`?
    fn walls_clear(&self, k: usize, b: &Body, margin: f64) -> bool {
        let listed = &self.near[self.near_start[k] as usize..self.near_start[k + 1] as usize];
        listed.iter().all(|&l| {
            self.walls[l as usize]
                .separation(b.x, b.r)
                .is_some_and(|(_, gap)| gap > margin)
        })
    }

    /// The island grown from `seeds`: a listed neighbour of an island sphere joins it unless their
    /// gap exceeds the films' cut-off by its travel plus the island's `reach`. Ascending.
    fn island(&self, seeds: Vec<u32>, travel: &[f64], reach: f64) -> Vec<u32> {
        let cutoff = self.reach();
        let mut inside = vec![false; self.bodies.len()];
        let mut island = Vec::new();
        for k in seeds {
            if !std::mem::replace(&mut inside[k as usize], true) {
                island.push(k);
            }
        }
        if island.len() == self.bodies.len() {
            // Every sphere is a seed (a bed): none is left to join.
            return (0..island.len() as u32).collect();
        }
        let mut next = 0;
        while next < island.len() {
            let a = island[next] as usize;
            next += 1;
            let as_i = self.first_i[a]..self.first_i[a + 1];
            let as_j = &self.as_j[self.as_j_start[a] as usize..self.as_j_start[a + 1] as usize];
            for s in as_i.chain(as_j.iter().copied()).map(|s| s as usize) {
                let (i, j) = (self.slots[s].i, self.slots[s].j);
                let other = if i as usize == a { j } else { i };
                let o = other as usize;
                if !inside[o] && !exceeds(self.slot_gap(s) - travel[o] - reach, cutoff) {
                    inside[o] = true;
                    island.push(other);
                }
            }
        }
        island.sort_unstable();
        island
    }

    /// The island's `steps` DEM steps in a world of its own (its spheres, their pairs with each
    /// other that can meet, their walls), then its spheres back and the others flown over `span`;
    /// false, with nothing changed, when an island sphere went further than `ISLAND_REACH` skin
    /// from where it started (or the island's lists ran out).
    fn advance_island(&mut self, island: &[u32], span: f64, steps: u64) -> bool {
        let mut spare = self
            .spare
            .take()
            .unwrap_or_else(|| Box::new(Spare::for_islands_of(self)));
        spare.local.clear();
        spare.local.resize(self.bodies.len(), FLYING);
        for (l, &k) in island.iter().enumerate() {
            spare.local[k as usize] = l as u32;
        }
        self.split_off(island, &mut spare);
        let part = &mut spare.part;
        let builds = part.builds;
        part.advance(steps);
        let reach = ISLAND_REACH * self.skin;
        let kept = part.builds == builds && part.peak_drift2 <= reach * reach;
        if kept {
            self.merge(&spare.part, island, &spare.local, &spare.slots, span);
        }
        self.spare = Some(spare);
        kept
    }

    /// Fills `spare` with the island's world: its spheres (`spare.local`: each sphere's index in
    /// it, or `FLYING`) with their pairs among themselves that can come within the films' cut-off
    /// while each sphere stays within its reach (state and history), their walls, and lists
    /// measured from where they are now; and `spare.slots`, the slots of those pairs here. A pair
    /// left out is apart and stays so, as `advance_island` checks: its force is an exact zero
    /// either way. The vectors are refilled, not made anew (a 32^3 bed's island world is some 20
    /// MB, which fresh allocations fault in and then unmap every fluid step), in parallel chunks.
    fn split_off(&self, island: &[u32], spare: &mut Spare) {
        let Spare { part, slots, local } = spare;
        self.island_pairs(island, local, slots);
        self.copy_spheres(island, part);
        self.copy_settings(part);
        self.copy_pairs(slots, local, part);
        part.build_adjacency();
    }

    /// Into `slots`, the pairs of the island's spheres (`local`: their index in the island, or
    /// FLYING) with both spheres in the island and within reach of each other.
    fn island_pairs(&self, island: &[u32], local: &[u32], slots: &mut Vec<u32>) {
        let apart = self.reach() + 2.0 * ISLAND_REACH * self.skin;
        slots.clear();
        slots.par_extend(
            island
                .par_iter()
                .with_min_len(CHUNK)
                .flat_map_iter(|&k| self.first_i[k as usize]..self.first_i[k as usize + 1])
                .filter(|&s| {
                    local[self.slots[s as usize].j as usize] != FLYING
                        && !exceeds(self.slot_gap(s as usize), apart)
                }),
        );
    }

    /// The island's spheres into `part`: their bodies, where they were at the last build, the
    /// walls near each and their wall histories.
    fn copy_spheres(&self, island: &[u32], part: &mut World) {
        part.near_start.clear();
        part.near_start.push(0);
        part.near.clear();
        for k in island.iter().map(|&k| k as usize) {
            part.near
                .extend_from_slice(&self.near[self.near_start[k] as usize..self.near_start[k + 1] as usize]);
            part.near_start.push(part.near.len() as u32);
        }
        part.bodies.clear();
        part.bodies.par_extend(
            island
                .par_iter()
                .with_min_len(CHUNK)
                .map(|&k| self.bodies[k as usize]),
        );
        part.x_at_build.clear();
        part.x_at_build.extend(part.bodies.iter().map(|b| b.x));
        part.ids_at_build.clear();
        part.ids_at_build.extend(part.bodies.iter().map(|b| b.id));
        let w = self.walls.len().max(1);
        part.wall_history.clear();
        part.wall_history
            .par_extend(island.par_iter().with_min_len(CHUNK).flat_map_iter(|&k| {
                self.wall_history[k as usize * w..(k as usize + 1) * w]
                    .iter()
                    .copied()
            }));
    }

    /// The world's walls, law and settings into `part`, its neighbour lists fresh.
    fn copy_settings(&self, part: &mut World) {
        part.walls.clone_from(&self.walls);
        part.law = self.law;
        part.compact_from = self.compact_from;
        part.gravity = self.gravity;
        part.dt = self.dt;
        part.skin = self.skin;
        part.time = self.time;
        part.lubrication = self.lubrication;
        part.periodic = self.periodic;
        part.stale = false;
        part.builds = self.builds;
        part.build_seconds = 0.0;
        part.contacts = self.contacts;
        part.peak_drift2 = 0.0;
    }

    /// The island's pairs `slots` into `part`, their spheres renumbered by `local`, with their
    /// films, histories, periodic shifts and last forces.
    fn copy_pairs(&self, slots: &[u32], local: &[u32], part: &mut World) {
        let pairs = || slots.par_iter().with_min_len(PAIR_CHUNK).map(|&s| s as usize);
        part.films.clear();
        if !self.films.is_empty() {
            part.films.par_extend(pairs().map(|s| self.films[s]));
        }
        part.slots.clear();
        part.slots.par_extend(pairs().map(|s| {
            let slot = self.slots[s];
            super::Slot {
                i: local[slot.i as usize],
                j: local[slot.j as usize],
                ..slot
            }
        }));
        part.pair_history.clear();
        part.pair_history
            .par_extend(pairs().map(|s| self.pair_history[s]));
        part.pair_shift.clear();
        if !self.pair_shift.is_empty() {
            part.pair_shift.par_extend(pairs().map(|s| self.pair_shift[s]));
        }
        part.out.clear();
        part.out.par_extend(pairs().map(|s| self.out[s]));
    }

    /// Takes the island's spheres, pair and wall histories back, and flies every other sphere
    /// over `span`.
    fn merge(&mut self, part: &World, island: &[u32], local: &[u32], slots: &[u32], span: f64) {
        let g = self.gravity;
        let moved = self
            .bodies
            .par_iter_mut()
            .with_min_len(CHUNK)
            .zip(&self.x_at_build)
            .zip(local)
            .map(|((b, x0), &l)| {
                if l == FLYING {
                    b.fly(span, g);
                } else {
                    *b = part.bodies[l as usize];
                }
                (b.x - x0).norm_squared()
            })
            .reduce(|| 0.0, f64::max);
        for (l, &s) in slots.iter().enumerate() {
            let s = s as usize;
            self.slots[s].touching = part.slots[l].touching;
            self.pair_history[s] = part.pair_history[l];
            self.out[s] = part.out[l];
            if !self.films.is_empty() {
                self.films[s] = part.films[l];
            }
        }
        let w = self.walls.len().max(1);
        for (l, &k) in island.iter().enumerate() {
            let k = k as usize;
            self.wall_history[k * w..(k + 1) * w].copy_from_slice(&part.wall_history[l * w..(l + 1) * w]);
        }
        self.contacts = part.contacts;
        self.time += span;
        self.note_drift(moved);
        self.wrap_into_domain();
    }

    /// Advances `span` seconds in one exact step of every sphere's free motion (gravity and its
    /// external load with their drag: `Body::fly`). Only when nothing touches nor comes within
    /// the films' reach over the span (`flight_plan`): the contact and film forces stay zero.
    fn fly(&mut self, span: f64) {
        let g = self.gravity;
        self.move_bodies(|b| b.fly(span, g));
        self.time += span;
        self.wrap_into_domain();
    }
}
