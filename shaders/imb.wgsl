// Immersed moving boundary (partially saturated cells; Noble & Torczynski 1998, Owen et al. 2011;
// seed eq. 7-11). Appended to lbm.wgsl when a scene couples particles.
//
// Per step: `cover` computes the solid fraction of every cell in each particle's bounding box
// (work = particles x cells covered, never cells x particles) and registers up to SLOTS particles
// per cell; the fluid kernels of lbm.wgsl stream and collide; `reduce` sums each particle's force
// and torque over slices of its box and `sum_loads` adds the slices, each in a fixed order (no
// floating-point atomics: the result is the same every run), and `reduce` clears the slots of its
// cells for the next step. The covered cells get their solid term in one of two ways (the
// same result):
// - FUSED: `cover` sets the cell's bit in a cover mask, and the fluid kernels, which test the bit
//   of every cell, apply the solid term where it is set (`solid_term`);
// - otherwise (the redo): `cover` lists the covered cells, `collide_covered` gives each its
//   collision with the solid term from its pre-collision populations and keeps the result, the
//   loads are reduced and go back to the host, and meanwhile the fluid kernels update every cell as
//   without particles and `store_covered` writes the kept populations over the covered cells'
//   (the AA pattern: a cell reads and writes the same 19 slots, which no other cell touches in
//   that step, so the second write simply replaces the first);
// - SKIP: as the redo, but `collide_covered` stores the covered cells in place, `cover` sets their
//   bits of the cover mask, the fluid kernels leave those cells alone, and the mask is cleared
//   after them (a buffer clear: every bit of it is a covered cell's of this step).
//
// The seed's equations: the solid fraction that B weighs in `solid_fraction`, B in `weighting`,
// the covered cell's collision (eq. 7) in `immersed_boundary`, the solid term Omega (eq. 8) at the
// solid's velocity (eq. 9) in `solid_collision`, the force (eq. 10) and torque (eq. 11) summed over
// the covered cells in `reduce` and `sum_loads`.
//
// Four files, appended in this order (lbm-server/src/lbm/gpu/way.rs, IMB_SHADER): this one (the
// bindings, the constants, the geometry of a particle's box, the slots and `cover`, the list of
// covered cells and `covered_groups`), imb_covered.wgsl (`collide_covered`, `store_covered`, the
// cover mask), imb_solid_term.wgsl (`solid_term`, `immersed_boundary`, `solid_collision`) and
// imb_loads.wgsl (`reduce`, `sum_loads`).

// Particles a cell can hold (1-4).
override SLOTS: u32 = 2u;
// The solid term in the fluid kernels (true) or in `collide_covered` before them (false).
override FUSED: bool = false;
// With FUSED false: `collide_covered` stores the covered cells in place and the fluid kernels skip
// them (true), or it keeps them for `store_covered` after the fluid kernels (false: the redo).
override SKIP: bool = false;
// Solid weighting: false = Noble & Torczynski B(eps, tau), true = the seed's B = eps.
override SEED_WEIGHTING: bool = false;
// Solid collision: false = Noble & Torczynski's, true = superposition (`immersed_boundary`).
override SUPERPOSITION: bool = false;
// The list of covered cells (`saved`) as structure of arrays (true, on a GPU: the cells, then
// each population in a run of its own, so that neighbouring invocations touch neighbouring words)
// or one 20-word record per cell (false, on a CPU driver, where each invocation's loads go one by
// one and a record's words are best together).
override BY_POPULATION: bool = true;

struct Particle {
    // centre in lattice units (cell i spans [i, i + 1]) and radius
    pos_r: vec4<f32>,
    vel: vec3<f32>,
    // the particle's first pair (its bounding box's first cell in `pairs`)
    first: u32,
    omega: vec3<f32>,
    // edge of the bounding box (cells)
    edge: u32,
}

@group(0) @binding(24) var<storage, read_write> particles: array<Particle>;
// Hydrodynamic force and torque about the centre of each particle (lattice units), six numbers
// per particle: the coupling's output, kept apart from the states so that only these 24 bytes per
// particle are read back by the host.
@group(0) @binding(30) var<storage, read_write> loads: array<f32>;
// Per cell of each particle's bounding box (the particle's pair range, in the box order of
// `box_cell`): xyz the momentum the fluid gave the particle in that cell during the step (0 where
// it holds no slot), w 1 where the particle covers the cell, 0 elsewhere.
@group(0) @binding(25) var<storage, read_write> pairs: array<vec4<f32>>;
// (FUSED, SKIP) The cover mask: bit k % 32 of word k / 32 set when cell k is covered.
@group(0) @binding(26) var<storage, read_write> covered: array<atomic<u32>>;
// Per cell: the particles covering it (SLOTS entries), as keys (`slot_key`, 0: empty), largest
// first: the SLOTS largest solid fractions, whatever the order in which `cover`'s invocations
// arrive (see `hold_slot`).
@group(0) @binding(27) var<storage, read_write> slots: array<atomic<u32>>;
// particles, pairs, -, capacity of `saved`
@group(0) @binding(28) var<storage, read> imb_info: vec4<u32>;
// The covered cells of this step, each once, in the order `cover` found them, over the `fields`
// buffer (binding 3), which only `macroscopic` uses and which it rewrites: from the front those
// none of whose links leaves the fluid or wraps (status[4] of them: their neighbours are at fixed
// index offsets), from the back the others (status[8]). Entry e holds the cell and the 19
// populations it sends out this step (`collide_covered`), laid out by BY_POPULATION.
// Seen four words at a time (an entry point binds a buffer once): with one record per cell
// (BY_POPULATION false) entry e's 20 words, the cell and its 19 populations, are the five vectors
// from 5 e, each moved by one vector load or store, where llvmpipe loops over the SIMD lanes per
// access; single words through `saved_word` and `set_saved_word`.
@group(0) @binding(3) var<storage, read_write> saved: array<vec4<u32>>;

// Word w of the list of covered cells, and its store.
fn saved_word(w: u32) -> u32 {
    return saved[w >> 2u][w & 3u];
}

fn set_saved_word(w: u32, value: u32) {
    saved[w >> 2u][w & 3u] = value;
}

const NO_CELL: u32 = 0xffffffffu;

// Fraction of the cell centred at `x` inside the sphere (the solid fraction that eq. 7's B
// weighs): the fraction of a unit cell below a plane at the cell centre's distance from the
// surface (exact for a face-aligned plane), 0 or 1 beyond half a cell, on a radius shortened by
// 1/(12 r) that cancels the volume the curvature adds (docs/imb.md). Branch-free: one square root
// per cell.
fn solid_fraction(x: vec3<f32>, centre: vec3<f32>, r: f32) -> f32 {
    return clamp(r - 1.0 / (12.0 * r) + 0.5 - length(x - centre), 0.0, 1.0);
}

// The first cell (lowest corner) of a particle's bounding box: the cell holding x - r. Its lower
// neighbour's centre is at least r + 1/2 away along an axis, where `solid_fraction` is 0 with a
// margin of 1/(12 r) (far above the rounding of x - r).
fn box_origin(p: Particle) -> vec3<i32> {
    return vec3<i32>(floor(p.pos_r.xyz - p.pos_r.w));
}

// t / m for t < 2^24: by the float quotient, corrected by one either way (llvmpipe has no vector
// integer division and divides lane by lane).
fn divide(t: u32, m: u32) -> u32 {
    let q = u32(max(f32(t) / f32(m), 0.0));
    return select(select(q, q + 1u, (q + 1u) * m <= t), q - 1u, q * m > t);
}

// Cell t of a particle's bounding box of edge m, x fastest.
fn box_cell(origin: vec3<i32>, m: u32, t: u32) -> vec3<i32> {
    let row = divide(t, m);
    let layer = divide(row, m);
    return origin + vec3<i32>(i32(t - row * m), i32(row - layer * m), i32(layer));
}

// A block of a lattice decomposed over ranks (lbm-server/src/parallel/; BLOCK true): the
// particles and their boxes stay in the whole lattice's coordinates (WHOLE_* cells, periodic
// along the axes of the bits of WHOLE_PERIODIC), and the block covers only its own cells, OWN_LO_*
// to OWN_HI_* (excluded); its lattice's cell (0, 0, 0) is the whole lattice's BASE_* (ghost
// layers included). Without BLOCK the lattice is the whole.
override BLOCK: bool = false;
override WHOLE_X: i32 = 1;
override WHOLE_Y: i32 = 1;
override WHOLE_Z: i32 = 1;
override WHOLE_PERIODIC: u32 = 0u;
override OWN_LO_X: i32 = 0;
override OWN_LO_Y: i32 = 0;
override OWN_LO_Z: i32 = 0;
override OWN_HI_X: i32 = 1;
override OWN_HI_Y: i32 = 1;
override OWN_HI_Z: i32 = 1;
override BASE_X: i32 = 0;
override BASE_Y: i32 = 0;
override BASE_Z: i32 = 0;
// The block lattice's cells outside its shell (lbm-server/src/parallel/halo.rs
// `Halo::interior`), INTERIOR_LO_* to INTERIOR_HI_* (excluded), in its own coordinates.
override INTERIOR_LO_X: i32 = 0;
override INTERIOR_LO_Y: i32 = 0;
override INTERIOR_LO_Z: i32 = 0;
override INTERIOR_HI_X: i32 = 1;
override INTERIOR_HI_Y: i32 = 1;
override INTERIOR_HI_Z: i32 = 1;

// The whole lattice's cells along each axis, and its periodic axes.
fn whole_n() -> vec3<i32> {
    if BLOCK { return vec3<i32>(WHOLE_X, WHOLE_Y, WHOLE_Z); }
    return vec3<i32>(params.n.xyz);
}

fn whole_periodic() -> vec3<bool> {
    if BLOCK { return (vec3<u32>(WHOLE_PERIODIC) & vec3<u32>(1u, 2u, 4u)) != vec3<u32>(0u); }
    return vec3<bool>(face_type(0u) == PERIODIC, face_type(2u) == PERIODIC, face_type(4u) == PERIODIC);
}

// The whole lattice's coordinates of this lattice's cell k (one of the block's own cells).
fn whole_coords(k: u32) -> vec3<i32> {
    if BLOCK { return coords(k) + vec3<i32>(BASE_X, BASE_Y, BASE_Z); }
    return coords(k);
}

// The lattice cell of box cell q: wrapped along the periodic axes (a box spans at most the axis and
// the host wraps the centres into the lattice, so q is less than one period outside), NO_CELL
// outside the domain along the others, and (BLOCK) outside the block's own cells.
fn lattice_cell(q: vec3<i32>) -> u32 {
    let n = whole_n();
    let periodic = whole_periodic();
    let inside = (q >= vec3<i32>(0)) & (q < n);
    if !all(inside | periodic) { return NO_CELL; }
    let wrapped = vec3<i32>(vec3<u32>(wrap(q.x, n.x), wrap(q.y, n.y), wrap(q.z, n.z)));
    let g = select(q, wrapped, periodic);
    if BLOCK {
        let own = (g >= vec3<i32>(OWN_LO_X, OWN_LO_Y, OWN_LO_Z)) & (g < vec3<i32>(OWN_HI_X, OWN_HI_Y, OWN_HI_Z));
        if !all(own) { return NO_CELL; }
        return cell_at(g - vec3<i32>(BASE_X, BASE_Y, BASE_Z));
    }
    return cell_at(g);
}

// The box cell (offset from the box origin) that lattice cell k is in particle p's box: k's
// coordinates, moved by one period where the box wraps.
fn box_offset(k: u32, p: Particle) -> vec3<i32> {
    let n = whole_n();
    let t = whole_coords(k) - box_origin(p);
    let up = select(t, t + n, t < vec3<i32>(0));
    return select(up, up - n, up >= vec3<i32>(i32(p.edge)));
}

fn cell_at(q: vec3<i32>) -> u32 {
    return u32(q.x) + params.n.x * (u32(q.y) + params.n.y * u32(q.z));
}

// Weight B of the solid collision for solid fraction eps (seed eq. 7's beta_n): the seed's B = eps,
// or Noble & Torczynski's B = eps (tau - 1/2) / ((1 - eps) + (tau - 1/2)).
fn weighting(eps: f32) -> f32 {
    if SEED_WEIGHTING { return eps; }
    let t = 1.0 / params.relax.x - 0.5;
    return eps * t / ((1.0 - eps) + t);
}

// The rank of particle j, covering a cell with solid fraction eps, among the cell's particles: eps
// in 1/255ths (rounded up, so 1-255) above the complement of j (24 bits), so that a larger key is a
// larger solid fraction, or the lower index of two equal ones. `coupled_step` refuses more than
// 2^24 particles.
fn slot_key(eps: f32, j: u32) -> u32 {
    return (min(u32(ceil(eps * 255.0)), 255u) << 24u) | (PARTICLE_MASK - j);
}

const PARTICLE_MASK: u32 = 0xffffffu;

// The particle of a key.
fn slot_particle(key: u32) -> u32 {
    return PARTICLE_MASK - (key & PARTICLE_MASK);
}

// A particle's arrival at a cell's slots (`hold_slot`): whether it found them empty, the first of
// the step to cover the cell, and whether a key fell off the last slot (the cell has more than
// SLOTS particles: one of them is dropped).
struct Arrival {
    first: bool,
    dropped: bool,
}

// Particle j joins cell k's slots if its key is among the SLOTS largest of the cell: the key goes
// down the slots by atomicMax, each slot keeping the larger key and passing the smaller on. Every
// key but the largest reaches slot 1, every key but the two largest slot 2, ..., so the slots end
// with the SLOTS largest keys in order whatever the order of arrival: a crowded cell keeps its
// largest solid fractions, and the same particles every run (the f64 reference keeps the same ones).
// Keys are never 0 and the slots start at 0, so exactly one arrival finds slot 0 empty, and each
// key the cell does not keep is carried past the last slot by exactly one arrival: the slots filled
// are the cell's count of particles up to SLOTS (`slot_count`), with no counter of their own.
fn hold_slot(k: u32, rank: u32) -> Arrival {
    let old = atomicMax(&slots[k * SLOTS], rank);
    var key = min(rank, old);
    for (var s = 1u; s < SLOTS && key != 0u; s++) {
        key = min(key, atomicMax(&slots[k * SLOTS + s], key));
    }
    return Arrival(old == 0u, key != 0u);
}

// One workgroup per particle, its threads over the particle's bounding box. The pairs are zero
// here (the step clears them before the pass): a covered cell's pair gets w = 1.
@compute @workgroup_size(64)
fn cover(at: Invocation) {
    let j = workgroup_index(at);
    if j >= imb_info.x { return; }
    let p = particles[j];
    let m = p.edge;
    let origin = box_origin(p);
    let cells = m * m * m;
    // Every invocation of the workgroup takes the same turns (`list_position` may gather a subgroup).
    for (var start = 0u; start < cells; start += 64u) {
        let t = start + at.local;
        var k = NO_CELL;
        // The list the cell joins (the redo): FRONT, BACK or NO_LIST.
        var list = NO_LIST;
        if t < cells {
            let q = box_cell(origin, m, t);
            k = lattice_cell(q);
            if k != NO_CELL {
                let eps = solid_fraction(vec3<f32>(q) + 0.5, p.pos_r.xyz, p.pos_r.w);
                let flag = flags[k];
                if eps > 0.0 && (flag & SOLID) == 0u {
                    let arrival = hold_slot(k, slot_key(eps, j));
                    if arrival.first {
                        // First to cover the cell: it sets the cell's bit of the cover mask
                        // (FUSED), or the cell joins a list of covered cells.
                        if FUSED {
                            atomicOr(&covered[mask_word(k)], mask_bit(k));
                        } else {
                            list = select(BACK, FRONT, (flag & (0x7ffffu | WRAPS)) == 0u);
                        }
                    }
                    if arrival.dropped {
                        atomicAdd(&status[1], 1u);
                    }
                    pairs[p.first + t].w = 1.0;
                }
            }
        }
        if !FUSED {
            join_list(k, list);
        }
    }
}

const FRONT: u32 = 0u;
const BACK: u32 = 1u;
const NO_LIST: u32 = 2u;

// Cell k joins the front of the covered cells' list (status[4] of them) or its back (status[8]); a
// cell that would not fit is counted by `covered_groups`. Called by every invocation of `cover`
// at each turn, `list` NO_LIST for those whose cell joins none (`list_position` may gather a
// subgroup).
fn join_list(k: u32, list: u32) {
    let position = list_position(list);
    let e = select(imb_info.w - 1u - position, position, list == FRONT);
    if list != NO_LIST && position < imb_info.w {
        set_saved_word(list_cell(e), k);
        // SKIP: the fluid kernels leave the listed cells alone (a cell beyond the list's room is
        // updated without its solid term, as with the redo, and the run stops).
        if SKIP {
            atomicOr(&covered[mask_word(k)], mask_bit(k));
        }
    }
}

// The covered cells' workgroups for the indirect dispatches over the list (`collide_covered`, then
// with the redo `store_covered`):
// status[5..8] (x, y, z; 2D beyond 65535 workgroups) for the front of the list, status[9..12] for
// the back. One invocation; covered cells beyond the capacity are counted in status[2] (the run
// stops: their solid term would be missing).
@compute @workgroup_size(1)
fn covered_groups() {
    let front = atomicLoad(&status[4]);
    let back = atomicLoad(&status[8]);
    let capacity = imb_info.w;
    if front + back > capacity {
        atomicAdd(&status[2], front + back - capacity);
    }
    let counts = vec2<u32>(min(front, capacity), min(back, capacity - min(front, capacity)));
    for (var list = 0u; list < 2u; list++) {
        let groups = (counts[list] + 63u) / 64u;
        let x = min(groups, 65535u);
        atomicStore(&status[5u + 4u * list], x);
        atomicStore(&status[6u + 4u * list], select(1u, (groups + x - 1u) / x, x > 0u));
        atomicStore(&status[7u + 4u * list], 1u);
    }
}

