// Immersed moving boundary (partially saturated cells; Noble & Torczynski 1998, Owen et al. 2011;
// seed eq. 7-11). Appended to lbm.wgsl when a scene couples particles.
//
// Per step: `uncover` clears the cells the particles covered last step, `cover` computes the solid
// fraction of every cell in each particle's bounding box (work = particles x cells covered, never
// cells x particles), registers up to SLOTS particles per cell and lists the covered cells, `save`
// keeps the pre-collision populations of the covered cells, the fluid kernels of lbm.wgsl update every cell as without
// particles, `stream_collide_covered` redoes each covered cell from its saved populations with the
// solid collision term (the AA pattern: a cell reads and writes the same 19 slots, which no other
// cell touches in that step, so the second write simply replaces the first), and `reduce` sums each
// particle's force and torque in a fixed order (no floating-point atomics: the result is the same
// every run).

// Particles a cell can hold (1-4).
override SLOTS: u32 = 2u;
// Solid weighting: false = Noble & Torczynski B(eps, tau), true = the seed's B = eps.
override SEED_WEIGHTING: bool = false;

struct Particle {
    // centre in lattice units (cell i spans [i, i + 1]) and radius
    pos_r: vec4<f32>,
    vel: vec4<f32>,
    omega: vec4<f32>,
    // first pair index, bounding box edge m (cells), -, -
    box_: vec4<u32>,
    // out: hydrodynamic force and torque about the centre (lattice units)
    force: vec4<f32>,
    torque: vec4<f32>,
}

// One cell of a particle's bounding box.
struct Pair {
    cell: u32,
    particle: u32,
    eps: f32,
    pad: f32,
    // momentum the fluid gave the particle in this cell during the step
    force: vec4<f32>,
}

// A covered cell and its pre-collision populations (`save`).
struct Saved {
    cell: u32,
    f: array<f32, 19>,
}

@group(0) @binding(24) var<storage, read_write> particles: array<Particle>;
@group(0) @binding(25) var<storage, read_write> pairs: array<Pair>;
// Per cell: how many particles cover it this step.
@group(0) @binding(26) var<storage, read_write> covered: array<atomic<u32>>;
// Per cell: SLOTS pair indices.
@group(0) @binding(27) var<storage, read_write> slots: array<u32>;
// particles, pairs, pairs of the previous step, capacity of `saved`
@group(0) @binding(28) var<storage, read> imb_info: vec4<u32>;
// The covered cells of this step, each once, in the order `cover` found them, over the `fields`
// buffer (binding 3), which only `macroscopic` uses and which it rewrites: from the front those
// none of whose links leaves the fluid (status[4] of them), from the back the others (status[8]).
@group(0) @binding(3) var<storage, read_write> saved: array<Saved>;

const NO_CELL: u32 = 0xffffffffu;
// Sub-samples per cell edge for the solid fraction of cells cut by the surface.
const SAMPLES: u32 = 4u;

// Fraction of the cell centred at `x` inside the sphere: exact 0 or 1 away from the surface,
// SAMPLES^3 sub-cell points where the surface cuts the cell.
fn solid_fraction(x: vec3<f32>, centre: vec3<f32>, r: f32) -> f32 {
    let d = length(x - centre);
    if d >= r + 0.8660254 { return 0.0; }
    if d <= r - 0.8660254 { return 1.0; }
    var inside = 0u;
    let step = 1.0 / f32(SAMPLES);
    for (var a = 0u; a < SAMPLES; a++) {
        for (var b = 0u; b < SAMPLES; b++) {
            for (var c = 0u; c < SAMPLES; c++) {
                let p = x - 0.5 + (vec3<f32>(f32(a), f32(b), f32(c)) + 0.5) * step;
                let v = p - centre;
                if dot(v, v) <= r * r { inside++; }
            }
        }
    }
    return f32(inside) / f32(SAMPLES * SAMPLES * SAMPLES);
}

// Weight of the solid collision for solid fraction eps.
fn weighting(eps: f32) -> f32 {
    if SEED_WEIGHTING { return eps; }
    let t = 1.0 / params.relax.x - 0.5;
    return eps * t / ((1.0 - eps) + t);
}

@compute @workgroup_size(64)
fn uncover(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let t = cell_index(wg, nwg, local);
    if t >= imb_info.z { return; }
    let cell = pairs[t].cell;
    if cell != NO_CELL { atomicStore(&covered[cell], 0u); }
}

// One workgroup per particle, its threads over the particle's bounding box.
@compute @workgroup_size(64)
fn cover(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let j = wg.y * nwg.x + wg.x;
    if j >= imb_info.x { return; }
    let p = particles[j];
    let m = p.box_.y;
    let origin = vec3<i32>(floor(p.pos_r.xyz - p.pos_r.w)) - vec3<i32>(1);
    let n = vec3<i32>(params.n.xyz);
    for (var t = local; t < m * m * m; t += 64u) {
        let q = origin + vec3<i32>(i32(t % m), i32((t / m) % m), i32(t / (m * m)));
        let index = p.box_.x + t;
        var cell = NO_CELL;
        var fraction = 0.0;
        if all(q >= vec3<i32>(0)) && all(q < n) {
            let k = u32(q.x) + params.n.x * (u32(q.y) + params.n.y * u32(q.z));
            let eps = solid_fraction(vec3<f32>(q) + 0.5, p.pos_r.xyz, p.pos_r.w);
            if eps > 0.0 && (flags[k] & SOLID) == 0u {
                let slot = atomicAdd(&covered[k], 1u);
                if slot == 0u {
                    // First to cover the cell: it joins the list of covered cells (a cell that
                    // would not fit is counted by `covered_groups`).
                    if (flags[k] & 0x7ffffu) == 0u {
                        let e = atomicAdd(&status[4], 1u);
                        if e < imb_info.w { saved[e].cell = k; }
                    } else {
                        let e = atomicAdd(&status[8], 1u);
                        if e < imb_info.w { saved[imb_info.w - 1u - e].cell = k; }
                    }
                }
                if slot < SLOTS {
                    slots[k * SLOTS + slot] = index;
                    cell = k;
                    fraction = eps;
                } else {
                    atomicAdd(&status[1], 1u);
                }
            }
        }
        // Field by field: the populations are written by `save`.
        pairs[index].cell = cell;
        pairs[index].particle = j;
        pairs[index].eps = fraction;
        pairs[index].force = vec4<f32>(0.0);
    }
}

// The covered cells' workgroups for the indirect dispatches of `save` and `stream_collide_covered`:
// status[5..8] (x, y, z; 2D beyond 65535 workgroups) for the front of the list, status[9..12] for
// the back. One invocation; cells beyond the capacity count as dropped covers.
@compute @workgroup_size(1)
fn covered_groups() {
    let front = atomicLoad(&status[4]);
    let back = atomicLoad(&status[8]);
    let capacity = imb_info.w;
    if front + back > capacity {
        atomicAdd(&status[1], front + back - capacity);
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

// The entry of `saved` of invocation j, or NO_CELL past the end of its list. KIND: bit 0 the
// parity, bit 1 the back of the list (cells with a link that leaves the fluid).
fn saved_entry(j: u32) -> u32 {
    let capacity = imb_info.w;
    let front = min(atomicLoad(&status[4]), capacity);
    if KIND < 2u {
        return select(NO_CELL, j, j < front);
    }
    let back = min(atomicLoad(&status[8]), capacity - front);
    return select(NO_CELL, capacity - 1u - j, j < back);
}

// Before the fluid step: the pre-collision populations of each covered cell.
@compute @workgroup_size(64)
fn save(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let e = saved_entry(cell_index(wg, nwg, local));
    if e == NO_CELL { return; }
    let k = saved[e].cell;
    let p = coords(k);
    // Without branches (llvmpipe would run both sides): in the odd step of a cell with a link that
    // leaves the fluid, both candidate slots are read and the right one kept.
    if KIND == 0u || KIND == 2u {
        //#for i
        saved[e].f[{i}] = f{i}[k];
        //#end
    } else if KIND == 1u {
        //#for i
        saved[e].f[{i}] = f{i.o}[wrapped(p - vec3<i32>({i.cx}, {i.cy}, {i.cz}))];
        //#end
    } else {
        let flag = flags[k];
        //#for i
        {
            let c = vec3<i32>({i.cx}, {i.cy}, {i.cz});
            saved[e].f[{i}] = select(f{i.o}[wrapped(p - c)], f{i}[k], leaves(flag, {i.o}u));
        }
        //#end
    }
}

// The face (or SOLID_LINK) a link from p along c leaves through, for a link that leaves the fluid:
// `neighbour` without its load of the neighbour's flags.
fn link_face(p: vec3<i32>, c: vec3<i32>) -> u32 {
    let n = vec3<i32>(params.n.xyz);
    let q = p + c;
    var face = crossed(0xffu, q.x, n.x, 0u);
    face = crossed(face, q.y, n.y, 1u);
    face = crossed(face, q.z, n.z, 2u);
    return select(face, SOLID_LINK, face == 0xffu);
}

// After the fluid step, which updated the covered cells without the solid term: each covered cell
// is redone from its saved populations, with the solid term, over the fluid kernels' result.
@compute @workgroup_size(64)
fn stream_collide_covered(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let e = saved_entry(cell_index(wg, nwg, local));
    if e == NO_CELL { return; }
    let k = saved[e].cell;
    var f: array<f32, 19>;
    //#for i
    f[{i}] = saved[e].f[{i}];
    //#end
    let m = moments(f);
    let post = immersed_boundary(k, f, m, collide(f, m));
    let p = coords(k);
    if KIND == 0u {
        //#for i
        f{i.o}[k] = post[{i}];
        //#end
    } else if KIND == 1u {
        //#for i
        f{i}[wrapped(p + vec3<i32>({i.cx}, {i.cy}, {i.cz}))] = post[{i}];
        //#end
    } else {
        // As `write_populations`, without the flag loads of `neighbour`.
        let flag = flags[k];
        //#for i
        {
            let c = vec3<i32>({i.cx}, {i.cy}, {i.cz});
            if leaves(flag, {i}u) {
                f{i.o}[k] = bounce(link_face(p, c), vec3<f32>(c), {i.w}, post[{i}], m);
            } else if KIND == 3u {
                f{i}[wrapped(p + c)] = post[{i}];
            } else {
                f{i.o}[k] = post[{i}];
            }
        }
        //#end
    }
}

// The collision of a cell covered by particles: the fluid part of `post` (the operator's
// relaxation and source) is weighted by 1 - sum B, and each particle adds B_s Omega_s with
// Omega_i = f_ibar - f_i + f_eq_i(rho, u_s) - f_eq_ibar(rho, u) (seed eq. 7-8).
fn immersed_boundary(k: u32, f: array<f32, 19>, m: Moments, post: array<f32, 19>) -> array<f32, 19> {
    let count = min(atomicLoad(&covered[k]), SLOTS);
    if count == 0u { return post; }
    // Pair indices in ascending order: sums do not depend on the order of insertion.
    var ids: array<u32, 4>;
    for (var s = 0u; s < count; s++) {
        var id = slots[k * SLOTS + s];
        var q = s;
        while q > 0u && ids[q - 1u] > id {
            ids[q] = ids[q - 1u];
            q--;
        }
        ids[q] = id;
    }
    // Total solid fraction capped at 1.
    var eps_total = 0.0;
    for (var s = 0u; s < count; s++) { eps_total += pairs[ids[s]].eps; }
    let scale = select(1.0, 1.0 / eps_total, eps_total > 1.0);
    var b: array<f32, 4>;
    var b_total = 0.0;
    for (var s = 0u; s < count; s++) {
        b[s] = weighting(pairs[ids[s]].eps * scale);
        b_total += b[s];
    }
    var out: array<f32, 19>;
    //#for i
    out[{i}] = f[{i}] - (1.0 - b_total) * (f[{i}] - post[{i}]);
    //#end
    let x = vec3<f32>(coords(k)) + 0.5;
    for (var s = 0u; s < count; s++) {
        let p = particles[pairs[ids[s]].particle];
        let solid = Moments(m.rho, p.vel.xyz + cross(p.omega.xyz, x - p.pos_r.xyz));
        var momentum = vec3<f32>(0.0);
        //#for i
        {
            let c = vec3<f32>({i.cx}.0, {i.cy}.0, {i.cz}.0);
            let omega = b[s] * (f[{i.o}] - f[{i}] + equilibrium(c, {i.w}, solid) - equilibrium(-c, {i.w}, m));
            out[{i}] += omega;
            momentum += omega * c;
        }
        //#end
        pairs[ids[s]].force = vec4<f32>(-momentum, 0.0);
    }
    return out;
}

// One thread per particle: force and torque summed over its bounding box in a fixed order.
@compute @workgroup_size(64)
fn reduce(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let j = cell_index(wg, nwg, local);
    if j >= imb_info.x { return; }
    let p = particles[j];
    let m = p.box_.y;
    var force = vec3<f32>(0.0);
    var torque = vec3<f32>(0.0);
    for (var t = 0u; t < m * m * m; t++) {
        let cell = pairs[p.box_.x + t].cell;
        if cell != NO_CELL {
            let pair_force = pairs[p.box_.x + t].force.xyz;
            let arm = vec3<f32>(coords(cell)) + 0.5 - p.pos_r.xyz;
            force += pair_force;
            torque += cross(arm, pair_force);
        }
    }
    particles[j].force = vec4<f32>(force, 0.0);
    particles[j].torque = vec4<f32>(torque, 0.0);
}
