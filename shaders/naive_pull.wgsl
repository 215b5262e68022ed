// Baseline for `lbm-server bench`: the textbook two-lattice D3Q19 kernel (pull streaming, BGK,
// periodic box, unshifted populations, f[i * cells + k]), written as one would in one sitting for
// a CPU driver: the 19 directions unrolled (`//#for`, as in lbm.wgsl: a loop with dynamic
// indexing runs 20x slower on lavapipe), periodic wrap by select, no flags, no branches. Each
// lattice is bound as two ranges, directions 0-9 and 10-18, so that a 128^3 lattice fits the
// 128 MiB per-binding limit of lavapipe. Not used for simulation: it measures what a
// straightforward implementation achieves on the same device.

struct Params {
    n: vec4<u32>,
    omega: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> src_lo: array<f32>;
@group(0) @binding(2) var<storage, read> src_hi: array<f32>;
@group(0) @binding(3) var<storage, read_write> dst_lo: array<f32>;
@group(0) @binding(4) var<storage, read_write> dst_hi: array<f32>;

fn wrap(q: i32, n: i32) -> i32 {
    return select(select(q, q - n, q >= n), q + n, q < 0);
}

fn load(i: u32, k: u32, cells: u32) -> f32 {
    if i < 10u { return src_lo[i * cells + k]; }
    return src_hi[(i - 10u) * cells + k];
}

fn store(i: u32, k: u32, cells: u32, value: f32) {
    if i < 10u {
        dst_lo[i * cells + k] = value;
    } else {
        dst_hi[(i - 10u) * cells + k] = value;
    }
}

@compute @workgroup_size(64)
fn naive_pull(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
              @builtin(local_invocation_index) local: u32) {
    let n = vec3<i32>(params.n.xyz);
    let cells = params.n.x * params.n.y * params.n.z;
    let k = (wg.y * nwg.x + wg.x) * 64u + local;
    if k >= cells { return; }
    let x = i32(k % params.n.x);
    let y = i32((k / params.n.x) % params.n.y);
    let z = i32(k / (params.n.x * params.n.y));
    var f: array<f32, 19>;
    //#for i
    f[{i}] = load({i}u, u32(wrap(x - {i.cx}, n.x) + n.x * (wrap(y - {i.cy}, n.y) + n.y * wrap(z - {i.cz}, n.z))), cells);
    //#end
    var rho = 0.0;
    var u = vec3<f32>(0.0);
    //#for i
    rho += f[{i}];
    u += f[{i}] * vec3<f32>({i.cx}.0, {i.cy}.0, {i.cz}.0);
    //#end
    u /= rho;
    let usq = 1.5 * dot(u, u);
    let omega = params.omega.x;
    //#for i
    {
        let cu = dot(vec3<f32>({i.cx}.0, {i.cy}.0, {i.cz}.0), u);
        let feq = {i.w} * rho * (1.0 + 3.0 * cu + 4.5 * cu * cu - usq);
        store({i}u, k, cells, f[{i}] - omega * (f[{i}] - feq));
    }
    //#end
}
