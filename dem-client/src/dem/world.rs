//! The particle system and its time integration: a `World` of spheres (`bodies.rs`) and fixed
//! walls (`walls.rs`) under one contact law (`contact.rs`).
//!
//! Equations of motion (seed paper eqs. 12-13), per sphere i:
//!   m_i dv_i/dt = m_i g + sum_j f_ij + F_ext,i                           (eq. 12)
//!   I_i dw_i/dt = sum_j l_ij x f_ij + T_ext,i,    I_i = 2/5 m_i r_i^2    (eq. 13)
//! F_ext, T_ext the fluid's force and torque (held constant over a fluid step when coupled).
//! Integrated by velocity Verlet (LIGGGHTS's scheme): half kick, drift, forces, half kick.
//!
//! A run of DEM steps (`World::advance`), its passes in order:
//!   1. open: half kick and drift of every sphere (`World::open_step`; after the first step the
//!      gather of the step before does it);
//!   2. neighbour lists: rebuilt when a sphere moved more than skin / 2 (`lists.rs`);
//!   3. pair pass: the contact and squeeze film of every listed pair (`pairs.rs`; LIGGGHTS's Hertz
//!      law in batches, `batch.rs`);
//!   4. gather, one pass over the spheres (`gather.rs`): each sums its pairs' forces, adds its
//!      wall contacts (the wall pass, `walls.rs`) and integrates (`Body::integrate`: the closing
//!      half kick, and until the last step the next step's opening kick and drift);
//!   5. wrap: along periodic axes, the spheres that left the domain back into it.
//!
//! A fluid step (`World::advance_span`, `flight.rs`): the spheres that can touch nothing in free
//! flight (`Body::fly`), the others (the island) in DEM steps among themselves, or every sphere
//! in DEM steps; a fluid step whose island is every sphere goes the way timed quicker
//! (`everyone.rs`).

use super::contact::{ContactForce, ContactLaw, PairMaterial};
use super::lubrication::SqueezeFilm;
use super::neighbor::Periodic;
use super::V3;
use rayon::prelude::*;

mod bodies;
pub mod everyone;
mod flight;
mod gather;
mod lists;
mod pairs;
mod saved;
mod walls;

pub use bodies::Body;
use bodies::Finish;
use pairs::{Kin, Slot};
pub use walls::{Shape, Wall};

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

/// Spheres from which a world's contact passes work from compact arrays (`World::compact_from`):
/// the pair pass reads a copy of the spheres' motion (`Kin`) instead of the bodies and records
/// which pairs touch (`World::touch`), and where few do the gather adds only those. 4096 bodies
/// are 1.3 MB, more than a core's L2 cache (1 MB here); below that the bodies stay in the cache
/// and the copy and the record cost more than they save (a 2000-sphere pour, one thread: +5% and
/// +3% wall time). A 32^3 bed (`dem-client bench validation/scenes/bed.toml`, one thread): 1.16 s
/// a fluid step -> 0.96 s with the copy -> 0.60 s with the touching pairs alone gathered.
pub(crate) const COMPACT_FROM: usize = 4096;

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
    lubrication: Option<SqueezeFilm>,
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
    pub fn set_lubrication(&mut self, lubrication: Option<SqueezeFilm>) {
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

    pub fn lubrication(&self) -> Option<&SqueezeFilm> {
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

    /// The pair material of two material indices (for the time-step rule).
    pub fn pair(&self, a: usize, b: usize) -> PairMaterial {
        *self.pair_material(a, b)
    }

    /// `steps` velocity-Verlet steps, run on a worker of rayon's pool so that the parallel
    /// loops inside need no hand-off from (and wake-up of) the calling thread: the opening half
    /// kick and drift, then per step the forces (neighbour lists, pair pass, gather) with the
    /// closing half kick; between two steps the closing half kick of one, the opening half kick
    /// and the drift of the next share the gather's pass over the bodies (the same as separate
    /// steps, bit for bit); then the spheres wrapped into a periodic domain.
    pub fn advance(&mut self, steps: u64) {
        if steps == 0 {
            return;
        }
        rayon::scope(|_| {
            // 1. open: half kick and drift.
            self.open_step();
            for s in 0..steps {
                let last = s + 1 == steps;
                let finish = if last { Finish::HalfKick } else { Finish::KickDrift };
                // 2-4. neighbour lists, pair pass, gather (walls, integration).
                let moved = self.forces(self.dt, finish);
                self.time += self.dt;
                self.note_drift(moved);
            }
        });
        // 5. wrap.
        self.wrap_into_domain();
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

    /// Contact forces and torques at the present positions, and the integration that follows in
    /// the same pass over the bodies (`finish`); `dt` advances the contact histories. The passes,
    /// in order: the neighbour lists (rebuilt when stale, `lists.rs`), the pair pass (`pairs.rs`),
    /// the gather with the wall pass and `finish` (`gather.rs`). Returns the largest squared
    /// displacement since the last neighbour-list build after a drift (else 0).
    fn forces(&mut self, dt: f64, finish: Finish) -> f64 {
        // 2. neighbour lists.
        if self.needs_rebuild() {
            self.rebuild();
        }
        let law = self.law;
        let (pair_contacts, (wall_contacts, moved)) = if law == ContactLaw::LIGGGHTS_HERTZ {
            self.contact_passes(LiggghtsHertz, dt, finish)
        } else {
            self.contact_passes(AnyLaw(&law), dt, finish)
        };
        self.contacts = pair_contacts + wall_contacts;
        moved
    }

    /// The pair pass, then the gather (with the wall pass and `finish`), compiled for `law`;
    /// returns (pair contacts, (wall contacts, largest squared displacement)).
    fn contact_passes<L: LawRef>(&mut self, law: L, dt: f64, finish: Finish) -> (usize, (usize, f64)) {
        // 3. pair pass.
        let pair_contacts = self.pair_forces(law, dt);
        // 4. gather: pair sums, wall pass, integration.
        (pair_contacts, self.gather(law, dt, finish, pair_contacts))
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
}
