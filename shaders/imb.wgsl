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
fn cover(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let j = wg.y * nwg.x + wg.x;
    if j >= imb_info.x { return; }
    let p = particles[j];
    let m = p.edge;
    let origin = box_origin(p);
    let cells = m * m * m;
    // Every invocation of the workgroup takes the same turns (`list_position` may gather a subgroup).
    for (var start = 0u; start < cells; start += 64u) {
        let t = start + local;
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

// An invocation of a kernel over the list of covered cells.
struct Invocation {
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
}

// The entry of `saved` of an invocation over the list, or NO_CELL past the end of its list.
fn listed(at: Invocation) -> u32 {
    return saved_entry(cell_index(at.wg, at.nwg, at.local));
}

// The entry of `saved` of invocation j, or NO_CELL past the end of its list. KIND: bit 0 the
// parity, bit 1 the back of the list (cells with a link that leaves the fluid or wraps).
fn saved_entry(j: u32) -> u32 {
    let capacity = imb_info.w;
    let front = min(atomicLoad(&status[4]), capacity);
    if KIND < 2u {
        return select(NO_CELL, j, j < front);
    }
    let back = min(atomicLoad(&status[8]), capacity - front);
    return select(NO_CELL, capacity - 1u - j, j < back);
}

// Where entry e of the list (of capacity imb_info.w) keeps its cell, and the population it sends
// along direction i.
fn list_cell(e: u32) -> u32 {
    return select(20u * e, e, BY_POPULATION);
}

fn population(e: u32, i: u32) -> u32 {
    return select(20u * e + 1u + i, imb_info.w * (i + 1u) + e, BY_POPULATION);
}

// Before the fluid step: each covered cell's collision with the solid term, from its
// pre-collision populations where the fluid kernels will read them; what it sends along each link
// (bounced back where the link leaves the fluid) is kept in `saved` until `store_covered` writes
// it over the fluid kernels' result, or (SKIP) stored in place at once. The loads need nothing
// else: they go back to the host while the fluid kernels run.
@compute @workgroup_size(64)
fn collide_covered(at: Invocation) {
    let e = listed(at);
    if e == NO_CELL { return; }
    let k = saved_word(list_cell(e));
    let p = coords(k);
    var f: array<f32, 19>;
    // Without branches (llvmpipe would run both sides): in the odd step of a cell with a link that
    // leaves the fluid, both candidate slots are read and the right one kept.
    if KIND == 0u || KIND == 2u {
        //#for i
        f[{i}] = load{i}(k);
        //#end
    } else if KIND == 1u {
        //#for i
        f[{i}] = load{i.o}(u32(i32(k) - offset(vec3<i32>({i.cx}, {i.cy}, {i.cz}))));
        //#end
    } else {
        let flag = flags[k];
        //#for i
        {
            let c = vec3<i32>({i.cx}, {i.cy}, {i.cz});
            f[{i}] = select(load{i.o}(wrapped(p - c)), load{i}(k), leaves(flag, {i.o}u));
        }
        //#end
    }
    let m = moments(f);
    let post = immersed_boundary(k, f, m, collide(f, m));
    var out = post;
    if KIND >= 2u {
        out = sent(p, flags[k], post, m);
    }
    if SKIP {
        store_populations(k, out);
    } else {
        keep(e, k, out);
    }
}

// Covered cell k's populations `out` kept in entry e of the list until `store_covered`: each in its
// population's run (BY_POPULATION), or the cell's record written as five vectors.
fn keep(e: u32, k: u32, out: array<f32, 19>) {
    if BY_POPULATION {
        //#for i
        set_saved_word(population(e, {i}u), bitcast<u32>(out[{i}]));
        //#end
    } else {
        var w: array<u32, 20>;
        w[0] = k;
        //#for i
        w[{i} + 1] = bitcast<u32>(out[{i}]);
        //#end
        saved[5u * e] = vec4<u32>(w[0], w[1], w[2], w[3]);
        saved[5u * e + 1u] = vec4<u32>(w[4], w[5], w[6], w[7]);
        saved[5u * e + 2u] = vec4<u32>(w[8], w[9], w[10], w[11]);
        saved[5u * e + 3u] = vec4<u32>(w[12], w[13], w[14], w[15]);
        saved[5u * e + 4u] = vec4<u32>(w[16], w[17], w[18], w[19]);
    }
}

// A covered cell and the populations `keep` kept for it.
struct Kept {
    k: u32,
    out: array<f32, 19>,
}

// Entry e of the list: its cell and the populations kept (`keep`).
fn kept(e: u32) -> Kept {
    var c: Kept;
    if BY_POPULATION {
        c.k = saved_word(list_cell(e));
        //#for i
        c.out[{i}] = bitcast<f32>(saved_word(population(e, {i}u)));
        //#end
    } else {
        let r = array<vec4<u32>, 5>(
            saved[5u * e],
            saved[5u * e + 1u],
            saved[5u * e + 2u],
            saved[5u * e + 3u],
            saved[5u * e + 4u],
        );
        c.k = r[0].x;
        //#for i
        c.out[{i}] = bitcast<f32>(r[({i} + 1) / 4][({i} + 1) % 4]);
        //#end
    }
    return c;
}

// In the fluid kernels (lbm.wgsl): whether cell k is left alone, `collide_covered` having updated
// it already (SKIP, its bit of the cover mask set). One mask word serves 32 consecutive cells.
fn skipped(k: u32) -> bool {
    if SKIP {
        return (atomicLoad(&covered[mask_word(k)]) & mask_bit(k)) != 0u;
    }
    return false;
}

// What covered cell k sends along each link (`out`, lbm.wgsl's `sent`), stored where the next step
// reads it: KIND bit 0 the parity, bit 1 the list's back (the cells with a link that leaves the
// fluid or wraps: lbm.wgsl's `store_sent`), the front's neighbours at fixed index offsets.
fn store_populations(k: u32, out: array<f32, 19>) {
    if KIND == 0u || KIND == 2u {
        //#for i
        store{i.o}(k, out[{i}]);
        //#end
    } else if KIND == 1u {
        //#for i
        store{i}(u32(i32(k) + offset(vec3<i32>({i.cx}, {i.cy}, {i.cz}))), out[{i}]);
        //#end
    } else {
        store_sent(k, coords(k), flags[k], out);
    }
}

// After the fluid step, which updated the covered cells without the solid term: each covered cell's
// populations from `collide_covered` go where the next step reads them, over the fluid kernels'
// (the AA pattern: the same slots, which no other cell touches in this step).
@compute @workgroup_size(64)
fn store_covered(at: Invocation) {
    let e = listed(at);
    if e == NO_CELL { return; }
    let c = kept(e);
    store_populations(c.k, c.out);
}

// SKIP: which of the four cells of quad q (cells 4q to 4q + 3, four bits of one mask word) the
// fluid kernels leave alone.
fn skipped_lanes(q: u32) -> vec4<bool> {
    if SKIP {
        let bits = atomicLoad(&covered[mask_word(4u * q)]) >> ((q & 7u) * 4u);
        return (vec4<u32>(bits) & vec4<u32>(1u, 2u, 4u, 8u)) != vec4<u32>(0u);
    }
    return vec4<bool>(false);
}

// The word of the cover mask that holds cell k's bit, and the bit.
fn mask_word(k: u32) -> u32 {
    return k >> 5u;
}

fn mask_bit(k: u32) -> u32 {
    return 1u << (k & 31u);
}

// In the fluid kernels (lbm.wgsl): the collision `post` of cell k, with the solid term when FUSED
// and particles cover the cell. One mask word serves 32 consecutive cells: a warp reads it once.
fn solid_term(k: u32, f: array<f32, 19>, m: Moments, post: array<f32, 19>) -> array<f32, 19> {
    if FUSED {
        if (atomicLoad(&covered[mask_word(k)]) & mask_bit(k)) != 0u {
            return immersed_boundary(k, f, m, post);
        }
    }
    return post;
}

// The collision of a cell covered by particles (seed eq. 7): the fluid part of `post` (the
// operator's relaxation and source) is weighted by 1 - sum B, and each particle adds B_s Omega_s
// (`solid_collision`). The particles in the order of their keys (`hold_slot`'s order: the sums do
// not depend on the order of arrival), their weights B (eq. 7) from their solid fractions with the
// total capped at 1. The first two slots' keys are read once (an empty slot is 0: the cell's
// count, `slot_count`) and their particles held through the three sums (the second looked up
// where the cell has one); the others (slots 3 and 4: rare) are looked up again for each,
// since an array indexed by slot would live in memory on llvmpipe, each access a loop over the
// SIMD lanes. No loop over the slots bounded by the cell's count: llvmpipe runs a loop's body at
// least once, masked, so each such loop cost every covered cell a particle's lookup and, the
// third, a solid collision, where most cells have one particle.
fn immersed_boundary(k: u32, f: array<f32, 19>, m: Moments, post: array<f32, 19>) -> array<f32, 19> {
    let first_key = atomicLoad(&slots[k * SLOTS]);
    if first_key == 0u { return post; }
    var second_key = first_key;
    if SLOTS > 1u {
        second_key = atomicLoad(&slots[k * SLOTS + 1u]);
    }
    let count = slot_count(k, second_key);
    let first = cover_of(k, first_key);
    var second = first;
    if count > 1u {
        second = cover_of(k, second_key);
    }
    let scale = slot_scale(k, count, first.eps, second.eps);
    let b_first = weighting(first.eps * scale);
    let b_second = weighting(second.eps * scale);
    var b_total = b_first;
    if count > 1u {
        b_total += b_second;
    }
    for (var s = 2u; s < SLOTS; s++) {
        if s < count {
            b_total += weighting(slot_cover(k, s).eps * scale);
        }
    }
    var out: array<f32, 19>;
    //#for i
    out[{i}] = f[{i}] - (1.0 - b_total) * (f[{i}] - post[{i}]);
    //#end
    let own = own_collision(f, m, post);
    out = solid_collision(first.p, first.t, first.x, b_first, f, m, own, out);
    if count > 1u {
        out = solid_collision(second.p, second.t, second.x, b_second, f, m, own, out);
    }
    for (var s = 2u; s < SLOTS; s++) {
        if s < count {
            let c = slot_cover(k, s);
            out = solid_collision(c.p, c.t, c.x, weighting(c.eps * scale), f, m, own, out);
        }
    }
    return out;
}

// The factor that caps the total solid fraction of cell k's `count` particles at 1 (the first
// two's fractions given), the fractions summed in slot order.
fn slot_scale(k: u32, count: u32, first: f32, second: f32) -> f32 {
    var eps_total = first;
    if count > 1u {
        eps_total += second;
    }
    for (var s = 2u; s < SLOTS; s++) {
        if s < count {
            eps_total += slot_cover(k, s).eps;
        }
    }
    return select(1.0, 1.0 / eps_total, eps_total > 1.0);
}

// A particle covering a cell, with the cell's offset in its box, the cell's centre there and the
// cell's solid fraction.
struct Cover {
    p: Particle,
    t: vec3<i32>,
    x: vec3<f32>,
    eps: f32,
}

// How many particles covered cell k hold its slots (its first slot held), its second slot's key
// given (0 where empty): the slots fill in order (`hold_slot`).
fn slot_count(k: u32, second_key: u32) -> u32 {
    var count = 1u;
    if SLOTS > 1u && second_key != 0u {
        count = 2u;
    }
    for (var s = 2u; s < SLOTS; s++) {
        if atomicLoad(&slots[k * SLOTS + s]) != 0u {
            count = s + 1u;
        }
    }
    return count;
}

// The particle of slot s of cell k (`cover_of`).
fn slot_cover(k: u32, s: u32) -> Cover {
    return cover_of(k, atomicLoad(&slots[k * SLOTS + s]));
}

// The particle of the slot key `key` of cell k, and its solid fraction as `cover` computed it (the
// same function of the same values: the cell centre in the particle's box, one period away where
// the box wraps).
fn cover_of(k: u32, key: u32) -> Cover {
    let p = particles[slot_particle(key)];
    let t = box_offset(k, p);
    let x = vec3<f32>(box_origin(p) + t) + 0.5;
    return Cover(p, t, x, solid_fraction(x, p.pos_r.xyz, p.pos_r.w));
}

// With SUPERPOSITION, what the solid term keeps of the fluid's own collision, post - S - f (S: the
// body force's part of post, `forcing`); zero otherwise.
fn own_collision(f: array<f32, 19>, m: Moments, post: array<f32, 19>) -> array<f32, 19> {
    var own: array<f32, 19>;
    if SUPERPOSITION {
        var source: array<f32, 19>;
        if FORCE {
            source = forcing(m);
        }
        //#for i
        own[{i}] = post[{i}] - source[{i}] - f[{i}];
        //#end
    }
    return own;
}

// Particle p's solid term in a covered cell (its offset t in the particle's box, its centre x,
// the particle's weight b), added to `out`: b Omega_i with Omega_i = f_ibar - f_i + f_eq_i(rho,
// u_s) - f_eq_ibar(rho, u) (seed eq. 8), or with SUPERPOSITION Omega_i = f_eq_i(rho, u_s) -
// f_eq_i(rho, u) + own_i, where u_s is the solid's velocity at the cell centre (eq. 9, at x
// rather than half a link on). The momentum it takes from the fluid, -b sum_i Omega_i c_i (the
// cell's term of eq. 10), goes to the particle's pair of this cell for `reduce`.
fn solid_collision(
    p: Particle,
    t: vec3<i32>,
    x: vec3<f32>,
    b: f32,
    f: array<f32, 19>,
    m: Moments,
    own: array<f32, 19>,
    fluid: array<f32, 19>,
) -> array<f32, 19> {
    var out = fluid;
    let solid = p.vel.xyz + cross(p.omega.xyz, x - p.pos_r.xyz);
    // f_eq_i(rho, u_s) - f_eq_ibar(rho, u) = w_i rho (3 c.sum + 4.5 (c.sum)(c.diff) - 1.5 sum.diff)
    // with sum = u_s + u, diff = u_s - u (eq. 3); f_eq_i(rho, u_s) - f_eq_i(rho, u) the same with
    // 3 c.diff in place of 3 c.sum.
    let sum = solid + m.u;
    let diff = solid - m.u;
    let scalar = -1.5 * dot(sum, diff);
    var momentum = vec3<f32>(0.0);
    //#for i
    {
        let c = vec3<f32>({i.cx}.0, {i.cy}.0, {i.cz}.0);
        let cs = dot(c, sum);
        let cd = dot(c, diff);
        var omega: f32;
        if SUPERPOSITION {
            omega = b * ({i.w} * m.rho * (3.0 * cd + 4.5 * cs * cd + scalar) + own[{i}]);
        } else {
            omega = b * (f[{i.o}] - f[{i}] + {i.w} * m.rho * (3.0 * cs + 4.5 * cs * cd + scalar));
        }
        out[{i}] += omega;
        momentum += omega * c;
    }
    //#end
    let b_ = vec3<u32>(t);
    let m_ = p.edge;
    pairs[p.first + b_.x + m_ * (b_.y + m_ * b_.z)] = vec4<f32>(-momentum, 1.0);
    return out;
}

// Invocations of `reduce` per particle, each over every SLICES-th cell of the particle's box.
const SLICES: u32 = 8u;

// The six numbers of particle j's load from `reduce`'s partial sums: after the N particles' loads,
// SLICES partial loads per particle (`loads` holds 6 (1 + SLICES) numbers per particle).
fn partial_load(j: u32, s: u32) -> u32 {
    return 6u * (imb_info.x + SLICES * j + s);
}

// SLICES invocations per particle: each sums the force (seed eq. 10) and torque (eq. 11: the arm
// from the particle's centre to the cell's, times the cell's force) of its slice of the particle's
// bounding box (box cells s, s + SLICES, s + 2 SLICES, ...: neighbouring invocations read
// neighbouring pairs) in a fixed order, and clears the slots (and FUSED the mask bits) of the
// covered cells of its slice for the next step. `sum_loads` adds the slices. No floating-point atomics: the
// same result every run. Many invocations of few cells each, rather than one per particle over its
// whole box: a GPU waits on one memory access per cell, and overlaps those of its many invocations.
@compute @workgroup_size(64)
fn reduce(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let i = cell_index(wg, nwg, local);
    let j = i / SLICES;
    let slice = i % SLICES;
    if j >= imb_info.x { return; }
    let p = particles[j];
    let m = p.edge;
    let origin = box_origin(p);
    var force = vec3<f32>(0.0);
    var torque = vec3<f32>(0.0);
    for (var t = slice; t < m * m * m; t += SLICES) {
        let pair = pairs[p.first + t];
        if pair.w != 0.0 {
            let q = box_cell(origin, m, t);
            let arm = vec3<f32>(q) + 0.5 - p.pos_r.xyz;
            force += pair.xyz;
            torque += cross(arm, pair.xyz);
            clear_cover(lattice_cell(q));
        }
    }
    let at = partial_load(j, slice);
    let sum = array<f32, 6>(force.x, force.y, force.z, torque.x, torque.y, torque.z);
    for (var k = 0u; k < 6u; k++) {
        loads[at + k] = sum[k];
    }
}

// One invocation per particle: its load, the sum of its slices' in slice order (the sums over the
// covered cells of eq. 10-11 completed).
@compute @workgroup_size(64)
fn sum_loads(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let j = cell_index(wg, nwg, local);
    if j >= imb_info.x { return; }
    var sum = array<f32, 6>(0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for (var s = 0u; s < SLICES; s++) {
        let at = partial_load(j, s);
        for (var k = 0u; k < 6u; k++) {
            sum[k] += loads[at + k];
        }
    }
    for (var k = 0u; k < 6u; k++) {
        loads[6u * j + k] = sum[k];
    }
}

// Cell k's slots and (FUSED) mask bit back to zero (NO_CELL: a cell of another rank's block,
// whose pair rank 0 reduces from the gathered pairs, `reduce_gathered`).
fn clear_cover(k: u32) {
    if k == NO_CELL { return; }
    if FUSED {
        atomicAnd(&covered[mask_word(k)], ~mask_bit(k));
    }
    for (var s = 0u; s < SLOTS; s++) {
        atomicStore(&slots[k * SLOTS + s], 0u);
    }
}
