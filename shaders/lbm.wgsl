// D3Q19 lattice-Boltzmann step (seed eq. 1-6) with the AA access pattern: one copy of the
// populations, updated in place, alternating an even step (read and write the cell's own slots,
// reversed) and an odd step (read from the neighbours, write to the neighbours).
//
// Populations are stored shifted (f_i - w_i) for single-precision accuracy, one storage buffer per
// direction (structure of arrays, coalesced; no binding ever exceeds the per-binding size limit),
// declared with their `load{i}` and `store{i}` by the storage (storage_fp32.wgsl, or
// storage_fp16.wgsl with fp16s.wgsl or fp16c.wgsl: `lattice.storage`).
// Lines between `//#for i` and `//#end` are repeated for the 19 directions before compilation
// (lbm-server/src/lbm/unroll.rs), with {i} the direction, {i.o} its opposite, {i.cx} {i.cy} {i.cz}
// its velocity c_i (seed eq. 2) and {i.w} its weight w_i (of eq. 3): every population is then a
// register and every buffer access static, which CPU drivers such as lavapipe need to be fast.
//
// The seed's equations: the collision of eq. 1 in `collide` (BGK: omega = 1/tau, params.relax.x,
// with tau from the viscosity by eq. 4 on the host) with its force term G_i in `guo_source` and
// `forcing`, its streaming in `store_sent` and `read_populations`, the equilibrium (eq. 3) in
// `collide` and `equilibrium`, density (eq. 5) and velocity (eq. 6) in `moments`.
//
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
    // cell list: interior, wrapping and boundary cell counts, quad count
    ranges: vec4<u32>,
    // interior and wrapping cells that belong to a quad (first of the interior ones, last of the
    // wrapping ones), interior cells that belong to an interior quad (first of all), interior quads
    quads: vec4<u32>,
    // the cells of the odd step through the periodic wrap: first, count (with interior quads, also
    // the interior cells outside them: one dispatch fewer), -, -
    wrapped: vec4<u32>,
}

// Collision operator, fixed when the pipeline is made: 0 BGK, 1 TRT, 2 MRT.
override OPERATOR: u32 = 0u;
// The cells `stream_collide_fluid` updates, fixed when the pipeline is made: 0 the even step of the
// interior and wrapping cells, 1 the odd step of the interior cells, 2 the odd step of the wrapping cells.
override KIND: u32 = 0u;
// A body force (Guo forcing): false when it is zero, which saves its source term.
override FORCE: bool = true;

@group(0) @binding(0) var<uniform> params: Params;
// One word per cell: bit i (0-18) set when link i leaves the fluid (a face that is not periodic,
// or a solid cell), SOLID for a solid cell, WRAPS for a cell on a periodic face, GHOST for a cell
// of a ghost layer.
@group(0) @binding(1) var<storage, read> flags: array<u32>;
// MRT: A = M^-1 S M (361 values) then B = M^-1 (I - S/2) M (361 values), row-major, four to a
// vec4. A uniform buffer: a load at a constant offset is one scalar load, where a storage load is
// a loop over the SIMD lanes on llvmpipe.
@group(0) @binding(2) var<uniform> mrt: array<vec4<f32>, 181>;
// Density and velocity per cell (written by `macroscopic`).
@group(0) @binding(3) var<storage, read_write> fields: array<vec4<f32>>;
// [0]: smallest index of a cell failing the health check (0xffffffff when none).
@group(0) @binding(4) var<storage, read_write> status: array<atomic<u32>>;
// (24-28: imb.wgsl.) The fluid cells by class, each class in increasing order: interior (no link
// leaves the fluid or wraps), wrapping (no link leaves the fluid, some wrap), boundary (the rest);
// then the quads: q such that cells 4q to 4q + 3 are interior or wrapping (without particles);
// then the interior quads, whose four cells are interior (when nx is a multiple of 4).
@group(0) @binding(29) var<storage, read> cell_list: array<u32>;

// A link that leaves the fluid: BOUNDARY | face (0-5), or BOUNDARY | 6 for a solid cell.
const BOUNDARY: u32 = 0x80000000u;
const SOLID_LINK: u32 = 6u;

const SOLID: u32 = 0x80000u;
const WRAPS: u32 = 0x100000u;
// A cell of a ghost layer: a neighbouring rank's, its populations written by the halo exchange
// (halo.wgsl); left out of the health check.
const GHOST: u32 = 0x200000u;

const PERIODIC: u32 = 0u;
const WALL: u32 = 1u;
const MOVING: u32 = 2u;
const PRESSURE: u32 = 3u;

fn cell_count() -> u32 {
    return params.n.x * params.n.y * params.n.z;
}

fn is_solid(k: u32) -> bool {
    return (flags[k] & SOLID) != 0u;
}

fn leaves(flag: u32, i: u32) -> bool {
    return ((flag >> i) & 1u) != 0u;
}

fn face_type(face: u32) -> u32 {
    if face == SOLID_LINK { return WALL; }
    if face < 4u { return params.face_lo[face]; }
    return params.face_hi[face - 4u];
}

// The face a link crosses along one axis, or 0xff; keeps the face of highest type.
fn crossed(face: u32, q: i32, n: i32, axis: u32) -> u32 {
    if q >= 0 && q < n { return face; }
    let f = 2u * axis + select(0u, 1u, q >= n);
    let kind = face_type(f);
    if kind == PERIODIC || (face != 0xffu && kind <= face_type(face)) { return face; }
    return f;
}

// Periodic wrap of a coordinate at most one cell outside [0, n) (no division: CPU drivers
// cannot vectorise it).
fn wrap(q: i32, n: i32) -> u32 {
    return u32(select(select(q, q - n, q >= n), q + n, q < 0));
}

// The cell at p + c, or BOUNDARY | face when the link leaves the fluid. A link through an edge
// or corner takes the crossed face of highest type (wall < moving wall or inlet < outlet), so
// that, e.g., a moving lid owns its edge links and conserves mass.
fn neighbour(p: vec3<i32>, c: vec3<i32>) -> u32 {
    let face = crossed_face(p, c);
    if face != 0xffu { return BOUNDARY | face; }
    let k = wrapped(p + c);
    if is_solid(k) { return BOUNDARY | SOLID_LINK; }
    return k;
}

// The face a link from p along c crosses (see `neighbour`), or 0xff when it stays in the box.
fn crossed_face(p: vec3<i32>, c: vec3<i32>) -> u32 {
    let n = vec3<i32>(params.n.xyz);
    let q = p + c;
    var face = crossed(0xffu, q.x, n.x, 0u);
    face = crossed(face, q.y, n.y, 1u);
    return crossed(face, q.z, n.z, 2u);
}

// The face (or SOLID_LINK) a link from p along c leaves through, for a link known to leave the
// fluid: `neighbour` without its load of the neighbour's flags.
fn link_face(p: vec3<i32>, c: vec3<i32>) -> u32 {
    let face = crossed_face(p, c);
    return select(face, SOLID_LINK, face == 0xffu);
}

// The cell along c from cell k (at p), for a link that stays in the fluid.
fn next_cell(k: u32, p: vec3<i32>, c: vec3<i32>, flag: u32) -> u32 {
    if (flag & WRAPS) != 0u { return neighbour(p, c); }
    return u32(i32(k) + offset(c));
}

fn coords(k: u32) -> vec3<i32> {
    let nx = params.n.x;
    let ny = params.n.y;
    return vec3<i32>(i32(k % nx), i32((k / nx) % ny), i32(k / (nx * ny)));
}

// An invocation of a kernel of 64-invocation workgroups, dispatched in rows of workgroups (2D
// for large grids).
struct Invocation {
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
}

// The index of the invocation's workgroup in the dispatch.
fn workgroup_index(at: Invocation) -> u32 {
    return at.wg.y * at.nwg.x + at.wg.x;
}

// The index of the invocation in the dispatch (the cell, quad or entry it takes).
fn cell_index(at: Invocation) -> u32 {
    return workgroup_index(at) * 64u + at.local;
}

// Pre-collision populations of cell k (at p: its coordinates, found once per cell, since they
// take three integer divisions) at the current time, whatever the step parity (the odd step
// reads f_i streamed from x - c_i, seed eq. 1).
fn read_populations(k: u32, p: vec3<i32>, flag: u32) -> array<f32, 19> {
    var f: array<f32, 19>;
    if params.n.w == 0u {
        //#for i
        f[{i}] = load{i}(k);
        //#end
    } else {
        //#for i
        if leaves(flag, {i.o}u) {
            f[{i}] = load{i}(k);
        } else {
            f[{i}] = load{i.o}(next_cell(k, p, -vec3<i32>({i.cx}, {i.cy}, {i.cz}), flag));
        }
        //#end
    }
    return f;
}

// Index offset of the neighbour along c, for cells whose links neither leave the fluid nor wrap.
fn offset(c: vec3<i32>) -> i32 {
    return c.x + i32(params.n.x) * (c.y + i32(params.n.y) * c.z);
}

struct Moments {
    rho: f32,
    u: vec3<f32>,
}

// Density (seed eq. 5) and velocity (eq. 6), with the half-force correction of Guo forcing.
fn moments(f: array<f32, 19>) -> Moments {
    var drho = 0.0;
    var j = vec3<f32>(0.0);
    //#for i
    drho += f[{i}];
    j += f[{i}] * vec3<f32>({i.cx}.0, {i.cy}.0, {i.cz}.0);
    //#end
    let rho = 1.0 + drho;
    return Moments(rho, (j + 0.5 * params.force.xyz) / rho);
}

// Shifted equilibrium f_eq_i - w_i (seed eq. 3) of direction c with weight w.
fn equilibrium(c: vec3<f32>, w: f32, m: Moments) -> f32 {
    let cu = dot(c, m.u);
    return w * ((m.rho - 1.0) + m.rho * (3.0 * cu + 4.5 * cu * cu - 1.5 * dot(m.u, m.u)));
}

// Guo forcing term of direction c with weight w (seed eq. 1's G_i, before its relaxation factor).
fn guo_source(c: vec3<f32>, w: f32, m: Moments) -> f32 {
    return w * dot(3.0 * (c - m.u) + 9.0 * dot(c, m.u) * c, params.force.xyz);
}

// The collision of seed eq. 1, f_i - omega (f_i - f_eq_i) + G_i, by the operator: BGK (omega =
// 1/tau), TRT (the symmetric and antisymmetric parts of f - f_eq relaxed apart) or MRT (in moment
// space), with the body force's source when FORCE.
fn collide(f: array<f32, 19>, m: Moments) -> array<f32, 19> {
    // f_eq_i - w_i = w_i (a + cu (b + d cu)) with cu = c_i . u (eq. 3): per-cell factors computed
    // once.
    let a = (m.rho - 1.0) - 1.5 * m.rho * dot(m.u, m.u);
    let b = 3.0 * m.rho;
    let d = 4.5 * m.rho;
    var neq: array<f32, 19>;
    //#for i
    {
        let cu = dot(vec3<f32>({i.cx}.0, {i.cy}.0, {i.cz}.0), m.u);
        neq[{i}] = f[{i}] - {i.w} * (a + cu * (b + d * cu));
    }
    //#end
    var out: array<f32, 19>;
    let wp = params.relax.x;
    let wm = params.relax.y;
    if OPERATOR == 0u {
        //#for i
        out[{i}] = f[{i}] - wp * neq[{i}];
        //#end
    } else if OPERATOR == 1u {
        //#for i
        out[{i}] = f[{i}] - 0.5 * (wp * (neq[{i}] + neq[{i.o}]) + wm * (neq[{i}] - neq[{i.o}]));
        //#end
    } else {
        //#for i
        out[{i}] = f[{i}] - mrt_row({i}u, neq);
        //#end
    }
    if FORCE {
        let source = forcing(m);
        //#for i
        out[{i}] += source[{i}];
        //#end
    }
    return out;
}

// The body force's part of the collision: Guo's source through the operator's relaxation
// factors (what `collide` adds when FORCE).
fn forcing(m: Moments) -> array<f32, 19> {
    var src: array<f32, 19>;
    //#for i
    src[{i}] = guo_source(vec3<f32>({i.cx}.0, {i.cy}.0, {i.cz}.0), {i.w}, m);
    //#end
    let wp = params.relax.x;
    let wm = params.relax.y;
    var out: array<f32, 19>;
    if OPERATOR == 0u {
        //#for i
        out[{i}] = (1.0 - 0.5 * wp) * src[{i}];
        //#end
    } else if OPERATOR == 1u {
        //#for i
        out[{i}] = 0.5 * ((1.0 - 0.5 * wp) * (src[{i}] + src[{i.o}]) + (1.0 - 0.5 * wm) * (src[{i}] - src[{i.o}]));
        //#end
    } else {
        //#for i
        out[{i}] = mrt_row(19u + {i}u, src);
        //#end
    }
    return out;
}

// Row r of the MRT matrices (A for r < 19, B for r >= 19) applied to v.
fn mrt_row(r: u32, v: array<f32, 19>) -> f32 {
    var sum = 0.0;
    //#for j
    sum += mrt[(r * 19u + {j}u) / 4u][(r * 19u + {j}u) % 4u] * v[{j}];
    //#end
    return sum;
}

// The population that comes back into the cell when post-collision f_i (velocity c, weight w)
// leaves through `face`.
fn bounce(face: u32, c: vec3<f32>, w: f32, f_star: f32, m: Moments) -> f32 {
    let kind = face_type(face);
    if kind == MOVING {
        return f_star - 6.0 * w * m.rho * dot(c, params.face_value[face].xyz);
    }
    if kind == PRESSURE {
        // Equilibrium outflow: f_ibar = f_eq_ibar(rho_w, u), no non-equilibrium comes back in
        // (anti-bounce-back sent it back, and near tau = 1/2 a wake's blew up there); u is the
        // cell's velocity less any part into the fluid (no backflow through the outlet).
        var outward = vec3<f32>(0.0);
        outward[face / 2u] = select(-1.0, 1.0, face % 2u == 1u);
        let u = m.u - min(dot(m.u, outward), 0.0) * outward;
        let cu = dot(c, u);
        let rho_w = params.face_value[face].w;
        return w * ((rho_w - 1.0) + rho_w * (-3.0 * cu + 4.5 * cu * cu - 1.5 * dot(u, u)));
    }
    return f_star;
}

// The step of cells with a link that leaves the fluid (boundary part of the cell list), either
// parity. llvmpipe (lavapipe) executes both sides of every branch: the fluid cells, far more, go
// through the branch-free `stream_collide_fluid` instead. With particles, either these kernels
// give the covered cells their solid term (FUSED, `solid_term` in imb_solid_term.wgsl: one bit tested per
// cell), or they update every cell without it and `store_covered` (imb_covered.wgsl) then writes the
// covered cells' own collision, made before them by `collide_covered`, over theirs, or (SKIP) they
// leave alone the covered cells, which `collide_covered` updated in place before them.
@compute @workgroup_size(64)
fn stream_collide(at: Invocation) {
    let j = cell_index(at);
    if j >= params.ranges.z { return; }
    let k = cell_list[params.ranges.x + params.ranges.y + j];
    if skipped(k) { return; }
    update_cell(k, flags[k]);
}

// The step of fluid cell k (flags `flag`), either parity, whatever its links: read, collide (with
// the solid term), and send, with the boundaries of links that leave the fluid.
fn update_cell(k: u32, flag: u32) {
    let p = coords(k);
    let f = read_populations(k, p, flag);
    let m = moments(f);
    write_populations(k, p, flag, solid_term(k, f, m, collide(f, m)), m);
}

// Stores the post-collision populations of cell k (at p) where the next step reads them, either
// parity, with the boundaries of links that leave the fluid.
fn write_populations(k: u32, p: vec3<i32>, flag: u32, post: array<f32, 19>, m: Moments) {
    store_sent(k, p, flag, sent(p, flag, post, m));
}

// What cell k (at p) sends along each link: its post-collision population, or where the link
// leaves the fluid, what comes back through the boundary (`bounce`).
fn sent(p: vec3<i32>, flag: u32, post: array<f32, 19>, m: Moments) -> array<f32, 19> {
    var out = post;
    //#for i
    if leaves(flag, {i}u) {
        let face = link_face(p, vec3<i32>({i.cx}, {i.cy}, {i.cz}));
        out[{i}] = bounce(face, vec3<f32>({i.cx}.0, {i.cy}.0, {i.cz}.0), {i.w}, post[{i}], m);
    }
    //#end
    return out;
}

// Stores what cell k (at p) sends along each link (`sent`) where the next step reads it, either
// parity: the streaming of seed eq. 1, to f_i(x + c_i, t + 1), or back into the cell where the
// link leaves the fluid.
fn store_sent(k: u32, p: vec3<i32>, flag: u32, out: array<f32, 19>) {
    let odd = params.n.w == 1u;
    //#for i
    if leaves(flag, {i}u) || !odd {
        store{i.o}(k, out[{i}]);
    } else {
        store{i}(next_cell(k, p, vec3<i32>({i.cx}, {i.cy}, {i.cz}), flag), out[{i}]);
    }
    //#end
}

// The step of the cells none of whose links leaves the fluid, from the cell list, without flags
// or branches (KIND is a constant): the cell's own slots in the even step; in the odd step the
// neighbours at fixed index offsets (interior cells) or through the periodic wrap (wrapping cells).
@compute @workgroup_size(64)
fn stream_collide_fluid(at: Invocation) {
    let j = cell_index(at);
    var start = params.quads.x;
    var count = params.ranges.x + params.ranges.y - params.quads.x - params.quads.y;
    if KIND == 1u {
        start = params.quads.z;
        count = params.ranges.x - params.quads.z;
    } else if KIND == 2u {
        start = params.wrapped.x;
        count = params.wrapped.y;
    }
    if j >= count { return; }
    let k = cell_list[start + j];
    if skipped(k) { return; }
    let p = coords(k);
    var f: array<f32, 19>;
    if KIND == 2u {
        //#for i
        f[{i}] = load{i.o}(wrapped(p - vec3<i32>({i.cx}, {i.cy}, {i.cz})));
        //#end
    } else {
        f = read_bulk(k, KIND == 1u);
    }
    let m = moments(f);
    let post = solid_term(k, f, m, collide(f, m));
    if KIND == 2u {
        //#for i
        store{i}(wrapped(p + vec3<i32>({i.cx}, {i.cy}, {i.cz})), post[{i}]);
        //#end
    } else {
        store_bulk(k, KIND == 1u, post);
    }
}

// The pre-collision populations of cell k, none of whose links leaves the fluid or wraps: its own
// slots in the even step, its neighbours' at fixed index offsets in the odd step.
fn read_bulk(k: u32, odd: bool) -> array<f32, 19> {
    var f: array<f32, 19>;
    if odd {
        //#for i
        f[{i}] = load{i.o}(u32(i32(k) - offset(vec3<i32>({i.cx}, {i.cy}, {i.cz}))));
        //#end
    } else {
        //#for i
        f[{i}] = load{i}(k);
        //#end
    }
    return f;
}

// Stores the post-collision populations of cell k (as `read_bulk`'s) where the next step reads
// them: the cell's own slots reversed in the even step, the neighbours' in the odd step.
fn store_bulk(k: u32, odd: bool, post: array<f32, 19>) {
    if odd {
        //#for i
        store{i}(u32(i32(k) + offset(vec3<i32>({i.cx}, {i.cy}, {i.cz}))), post[{i}]);
        //#end
    } else {
        //#for i
        store{i.o}(k, post[{i}]);
        //#end
    }
}

// The cell at q, at most one cell outside the grid along each axis, wrapped periodically.
fn wrapped(q: vec3<i32>) -> u32 {
    let n = vec3<i32>(params.n.xyz);
    return wrap(q.x, n.x) + params.n.x * (wrap(q.y, n.y) + params.n.y * wrap(q.z, n.z));
}

// Density and velocity (seed eq. 5-6) of every cell, and the health check: the smallest index of
// a cell with a non-finite value, a density deviation above relax.w or a speed above relax.z goes
// to status[0] (a ghost cell's, another rank's to check, excepted).
@compute @workgroup_size(64)
fn macroscopic(at: Invocation) {
    let k = cell_index(at);
    if k >= cell_count() { return; }
    let flag = flags[k];
    if (flag & SOLID) != 0u {
        fields[k] = vec4<f32>(1.0, 0.0, 0.0, 0.0);
        return;
    }
    let m = moments(read_populations(k, coords(k), flag));
    fields[k] = vec4<f32>(m.rho, m.u);
    let speed = length(m.u);
    // NaN fails every comparison: written so that NaN and infinity count as unhealthy.
    let healthy = abs(m.rho - 1.0) <= params.relax.w && speed <= params.relax.z;
    if !healthy && (flag & GHOST) == 0u {
        atomicMin(&status[0], k);
    }
}
