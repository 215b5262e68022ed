// The particles' loads (seed eq. 10-11), appended with imb.wgsl: `reduce` sums each particle's
// force and torque over slices of its box in a fixed order and clears the covers of its cells,
// `sum_loads` adds the slices.

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
fn reduce(at: Invocation) {
    let i = cell_index(at);
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
    let first = partial_load(j, slice);
    let sum = array<f32, 6>(force.x, force.y, force.z, torque.x, torque.y, torque.z);
    for (var k = 0u; k < 6u; k++) {
        loads[first + k] = sum[k];
    }
}

// One invocation per particle: its load, the sum of its slices' in slice order (the sums over the
// covered cells of eq. 10-11 completed).
@compute @workgroup_size(64)
fn sum_loads(at: Invocation) {
    let j = cell_index(at);
    if j >= imb_info.x { return; }
    var sum = array<f32, 6>(0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for (var s = 0u; s < SLICES; s++) {
        let first = partial_load(j, s);
        for (var k = 0u; k < 6u; k++) {
            sum[k] += loads[first + k];
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
