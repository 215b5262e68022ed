// D3Q19 lattice-Boltzmann step (seed eq. 1-6) with the AA access pattern: one copy of the
// populations, updated in place, alternating an even step (read and write the cell's own slots,
// reversed) and an odd step (read from the neighbours, write to the neighbours).
//
// Populations are stored shifted (f_i - w_i) for single-precision accuracy, one storage buffer per
// direction (structure of arrays, coalesced; no binding ever exceeds the per-binding size limit).
// Boundaries are applied on the way out: a post-collision population that would leave through a
// wall, moving wall, inlet or outlet, or into a solid cell, comes back as the reversed population
// of the same cell, stored where the next step reads it.

struct Params {
    // nx, ny, nz, parity (0 even, 1 odd)
    n: vec4<u32>,
    // boundary type of the faces x_min, x_max, y_min, y_max / z_min, z_max, -, -
    // (0 periodic, 1 wall, 2 moving wall or velocity inlet, 3 pressure outlet)
    face_lo: vec4<u32>,
    face_hi: vec4<u32>,
    // omega (shear, symmetric), omega_minus (TRT antisymmetric), max speed, max density deviation
    relax: vec4<f32>,
    // body force density (Guo), w unused
    force: vec4<f32>,
    // per face: wall velocity xyz, density w
    face_value: array<vec4<f32>, 6>,
}

// Collision operator, fixed when the pipeline is made: 0 BGK, 1 TRT, 2 MRT.
override OPERATOR: u32 = 0u;

@group(0) @binding(0) var<uniform> params: Params;
// One byte per cell, four cells per word: 0 fluid, 1 solid.
@group(0) @binding(1) var<storage, read> flags: array<u32>;
// MRT: A = M^-1 S M (361 values) then B = M^-1 (I - S/2) M (361 values), row-major.
@group(0) @binding(2) var<storage, read> mrt: array<f32>;
// Density and velocity per cell (written by `macroscopic`).
@group(0) @binding(3) var<storage, read_write> fields: array<vec4<f32>>;
// [0]: smallest index of a cell failing the health check (0xffffffff when none).
@group(0) @binding(4) var<storage, read_write> status: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read_write> f0: array<f32>;
@group(0) @binding(6) var<storage, read_write> f1: array<f32>;
@group(0) @binding(7) var<storage, read_write> f2: array<f32>;
@group(0) @binding(8) var<storage, read_write> f3: array<f32>;
@group(0) @binding(9) var<storage, read_write> f4: array<f32>;
@group(0) @binding(10) var<storage, read_write> f5: array<f32>;
@group(0) @binding(11) var<storage, read_write> f6: array<f32>;
@group(0) @binding(12) var<storage, read_write> f7: array<f32>;
@group(0) @binding(13) var<storage, read_write> f8: array<f32>;
@group(0) @binding(14) var<storage, read_write> f9: array<f32>;
@group(0) @binding(15) var<storage, read_write> f10: array<f32>;
@group(0) @binding(16) var<storage, read_write> f11: array<f32>;
@group(0) @binding(17) var<storage, read_write> f12: array<f32>;
@group(0) @binding(18) var<storage, read_write> f13: array<f32>;
@group(0) @binding(19) var<storage, read_write> f14: array<f32>;
@group(0) @binding(20) var<storage, read_write> f15: array<f32>;
@group(0) @binding(21) var<storage, read_write> f16: array<f32>;
@group(0) @binding(22) var<storage, read_write> f17: array<f32>;
@group(0) @binding(23) var<storage, read_write> f18: array<f32>;

const CX = array<i32, 19>(0, 1, -1, 0, 0, 0, 0, 1, -1, 1, -1, 0, 0, 1, -1, 1, -1, 0, 0);
const CY = array<i32, 19>(0, 0, 0, 1, -1, 0, 0, 1, -1, 0, 0, 1, -1, -1, 1, 0, 0, 1, -1);
const CZ = array<i32, 19>(0, 0, 0, 0, 0, 1, -1, 0, 0, 1, -1, 1, -1, 0, 0, -1, 1, -1, 1);
const W = array<f32, 19>(
    1.0 / 3.0,
    1.0 / 18.0, 1.0 / 18.0, 1.0 / 18.0, 1.0 / 18.0, 1.0 / 18.0, 1.0 / 18.0,
    1.0 / 36.0, 1.0 / 36.0, 1.0 / 36.0, 1.0 / 36.0, 1.0 / 36.0, 1.0 / 36.0,
    1.0 / 36.0, 1.0 / 36.0, 1.0 / 36.0, 1.0 / 36.0, 1.0 / 36.0, 1.0 / 36.0,
);

// A link that leaves the fluid: BOUNDARY | face (0-5), or BOUNDARY | 6 for a solid cell.
const BOUNDARY: u32 = 0x80000000u;
const SOLID_LINK: u32 = 6u;

const PERIODIC: u32 = 0u;
const WALL: u32 = 1u;
const MOVING: u32 = 2u;
const PRESSURE: u32 = 3u;

fn load(i: u32, k: u32) -> f32 {
    switch i {
        case 0u: { return f0[k]; }
        case 1u: { return f1[k]; }
        case 2u: { return f2[k]; }
        case 3u: { return f3[k]; }
        case 4u: { return f4[k]; }
        case 5u: { return f5[k]; }
        case 6u: { return f6[k]; }
        case 7u: { return f7[k]; }
        case 8u: { return f8[k]; }
        case 9u: { return f9[k]; }
        case 10u: { return f10[k]; }
        case 11u: { return f11[k]; }
        case 12u: { return f12[k]; }
        case 13u: { return f13[k]; }
        case 14u: { return f14[k]; }
        case 15u: { return f15[k]; }
        case 16u: { return f16[k]; }
        case 17u: { return f17[k]; }
        default: { return f18[k]; }
    }
}

fn store(i: u32, k: u32, v: f32) {
    switch i {
        case 0u: { f0[k] = v; }
        case 1u: { f1[k] = v; }
        case 2u: { f2[k] = v; }
        case 3u: { f3[k] = v; }
        case 4u: { f4[k] = v; }
        case 5u: { f5[k] = v; }
        case 6u: { f6[k] = v; }
        case 7u: { f7[k] = v; }
        case 8u: { f8[k] = v; }
        case 9u: { f9[k] = v; }
        case 10u: { f10[k] = v; }
        case 11u: { f11[k] = v; }
        case 12u: { f12[k] = v; }
        case 13u: { f13[k] = v; }
        case 14u: { f14[k] = v; }
        case 15u: { f15[k] = v; }
        case 16u: { f16[k] = v; }
        case 17u: { f17[k] = v; }
        default: { f18[k] = v; }
    }
}

fn opposite(i: u32) -> u32 {
    if i == 0u { return 0u; }
    return select(i - 1u, i + 1u, (i & 1u) == 1u);
}

fn velocity_of(i: u32) -> vec3<i32> {
    return vec3<i32>(CX[i], CY[i], CZ[i]);
}

fn cell_count() -> u32 {
    return params.n.x * params.n.y * params.n.z;
}

fn is_solid(k: u32) -> bool {
    return ((flags[k >> 2u] >> ((k & 3u) * 8u)) & 0xffu) == 1u;
}

fn face_type(face: u32) -> u32 {
    if face == SOLID_LINK { return WALL; }
    if face < 4u { return params.face_lo[face]; }
    return params.face_hi[face - 4u];
}

// The cell at p + c, or BOUNDARY | face when the link leaves the fluid.
fn neighbour(p: vec3<i32>, c: vec3<i32>) -> u32 {
    let n = vec3<i32>(params.n.xyz);
    var q = p + c;
    for (var a = 0u; a < 3u; a++) {
        if q[a] < 0 || q[a] >= n[a] {
            let face = 2u * a + select(0u, 1u, q[a] >= n[a]);
            if face_type(face) != PERIODIC { return BOUNDARY | face; }
            q[a] = (q[a] + n[a]) % n[a];
        }
    }
    let k = u32(q.x) + params.n.x * (u32(q.y) + params.n.y * u32(q.z));
    if is_solid(k) { return BOUNDARY | SOLID_LINK; }
    return k;
}

fn coords(k: u32) -> vec3<i32> {
    let nx = params.n.x;
    let ny = params.n.y;
    return vec3<i32>(i32(k % nx), i32((k / nx) % ny), i32(k / (nx * ny)));
}

// The cell index of this invocation (2D dispatch for large grids).
fn cell_index(wg: vec3<u32>, nwg: vec3<u32>, local: u32) -> u32 {
    return (wg.y * nwg.x + wg.x) * 64u + local;
}

// Pre-collision populations of cell k at the current time, whatever the step parity.
fn read_populations(k: u32, p: vec3<i32>) -> array<f32, 19> {
    var f: array<f32, 19>;
    for (var i = 0u; i < 19u; i++) {
        if params.n.w == 0u {
            f[i] = load(i, k);
        } else {
            let source = neighbour(p, -velocity_of(i));
            if (source & BOUNDARY) != 0u {
                f[i] = load(i, k);
            } else {
                f[i] = load(opposite(i), source);
            }
        }
    }
    return f;
}

struct Moments {
    rho: f32,
    u: vec3<f32>,
}

// Density and velocity, with the half-force correction of Guo forcing.
fn moments(f: array<f32, 19>) -> Moments {
    var drho = 0.0;
    var j = vec3<f32>(0.0);
    for (var i = 0u; i < 19u; i++) {
        drho += f[i];
        j += f[i] * vec3<f32>(velocity_of(i));
    }
    let rho = 1.0 + drho;
    return Moments(rho, (j + 0.5 * params.force.xyz) / rho);
}

// Shifted equilibrium f_eq_i - w_i.
fn equilibrium(i: u32, m: Moments) -> f32 {
    let cu = dot(vec3<f32>(velocity_of(i)), m.u);
    let uu = dot(m.u, m.u);
    return W[i] * ((m.rho - 1.0) + m.rho * (3.0 * cu + 4.5 * cu * cu - 1.5 * uu));
}

// Guo forcing term (before its relaxation factor).
fn guo_source(i: u32, m: Moments) -> f32 {
    let c = vec3<f32>(velocity_of(i));
    let cu = dot(c, m.u);
    return W[i] * dot(3.0 * (c - m.u) + 9.0 * cu * c, params.force.xyz);
}

fn collide(f: array<f32, 19>, m: Moments) -> array<f32, 19> {
    var neq: array<f32, 19>;
    var src: array<f32, 19>;
    for (var i = 0u; i < 19u; i++) {
        neq[i] = f[i] - equilibrium(i, m);
        src[i] = guo_source(i, m);
    }
    var out: array<f32, 19>;
    let wp = params.relax.x;
    let wm = params.relax.y;
    for (var i = 0u; i < 19u; i++) {
        if OPERATOR == 0u {
            out[i] = f[i] - wp * neq[i] + (1.0 - 0.5 * wp) * src[i];
        } else if OPERATOR == 1u {
            let o = opposite(i);
            let np = 0.5 * (neq[i] + neq[o]);
            let nm = 0.5 * (neq[i] - neq[o]);
            let sp = 0.5 * (src[i] + src[o]);
            let sm = 0.5 * (src[i] - src[o]);
            out[i] = f[i] - wp * np - wm * nm + (1.0 - 0.5 * wp) * sp + (1.0 - 0.5 * wm) * sm;
        } else {
            var relax = 0.0;
            var source = 0.0;
            for (var j = 0u; j < 19u; j++) {
                relax += mrt[i * 19u + j] * neq[j];
                source += mrt[361u + i * 19u + j] * src[j];
            }
            out[i] = f[i] - relax + source;
        }
    }
    return out;
}

// The population that comes back into the cell when post-collision f_i leaves through `face`.
fn bounce(face: u32, i: u32, f_star: f32, m: Moments) -> f32 {
    let kind = face_type(face);
    let c = vec3<f32>(velocity_of(i));
    if kind == MOVING {
        return f_star - 6.0 * W[i] * m.rho * dot(c, params.face_value[face].xyz);
    }
    if kind == PRESSURE {
        let cu = dot(c, m.u);
        let rho_w = params.face_value[face].w;
        return -f_star + 2.0 * W[i] * (rho_w * (1.0 + 4.5 * cu * cu - 1.5 * dot(m.u, m.u)) - 1.0);
    }
    return f_star;
}

@compute @workgroup_size(64)
fn stream_collide(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let k = cell_index(wg, nwg, local);
    if k >= cell_count() || is_solid(k) { return; }
    let p = coords(k);
    let f = read_populations(k, p);
    let m = moments(f);
    let post = collide(f, m);
    let odd = params.n.w == 1u;
    for (var i = 0u; i < 19u; i++) {
        let target_cell = neighbour(p, velocity_of(i));
        if (target_cell & BOUNDARY) != 0u {
            store(opposite(i), k, bounce(target_cell & 0xffu, i, post[i], m));
        } else if odd {
            store(i, target_cell, post[i]);
        } else {
            store(opposite(i), k, post[i]);
        }
    }
}

// Density and velocity of every cell, and the health check: the smallest index of a cell with a
// non-finite value, a density deviation above relax.w or a speed above relax.z goes to status[0].
@compute @workgroup_size(64)
fn macroscopic(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let k = cell_index(wg, nwg, local);
    if k >= cell_count() { return; }
    if is_solid(k) {
        fields[k] = vec4<f32>(1.0, 0.0, 0.0, 0.0);
        return;
    }
    let m = moments(read_populations(k, coords(k)));
    fields[k] = vec4<f32>(m.rho, m.u);
    let speed = length(m.u);
    // NaN fails every comparison: written so that NaN and infinity count as unhealthy.
    let healthy = abs(m.rho - 1.0) <= params.relax.w && speed <= params.relax.z;
    if !healthy {
        atomicMin(&status[0], k);
    }
}
