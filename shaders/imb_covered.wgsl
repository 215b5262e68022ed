// The covered cells' own passes of the immersed moving boundary (imb.wgsl has the coupling's
// bindings and the cover; appended with it): with the redo and SKIP the list of covered cells
// walked by `collide_covered` (the collision with the solid term from the pre-collision
// populations) and the redo's `store_covered`; the cover mask's words and SKIP's test of a quad's
// lanes.

// The entry of `saved` of an invocation over the list, or NO_CELL past the end of its list.
fn listed(at: Invocation) -> u32 {
    return saved_entry(cell_index(at));
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

// Which covered cells `store_covered` writes: every one (0), or in a step of a block split by
// region for the overlapped halo exchange (lbm-server/src/lbm/imb/by_region.rs) those of the
// shell (1: after the shell's fluid update, before the exchange reads it) or the others (2: after
// the interior's).
override STORE_PART: u32 = 0u;

// After the fluid step, which updated the covered cells without the solid term: each covered cell's
// populations from `collide_covered` go where the next step reads them, over the fluid kernels'
// (the AA pattern: the same slots, which no other cell touches in this step).
@compute @workgroup_size(64)
fn store_covered(at: Invocation) {
    let e = listed(at);
    if e == NO_CELL { return; }
    if STORE_PART != 0u && in_shell(saved_word(list_cell(e))) != (STORE_PART == 1u) { return; }
    let c = kept(e);
    store_populations(c.k, c.out);
}

// Whether cell k of a block is in its shell, the region of a split step updated first: outside
// the box INTERIOR_LO_* to INTERIOR_HI_* that lbm-server/src/parallel/halo.rs `Halo::interior`
// draws (the cells within two layers of a face with a ghost layer).
fn in_shell(k: u32) -> bool {
    let x = coords(k);
    let lo = vec3<i32>(INTERIOR_LO_X, INTERIOR_LO_Y, INTERIOR_LO_Z);
    let hi = vec3<i32>(INTERIOR_HI_X, INTERIOR_HI_Y, INTERIOR_HI_Z);
    return any(x < lo) || any(x >= hi);
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

