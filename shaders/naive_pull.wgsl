// Baseline for `lbm-server bench`: the textbook two-lattice D3Q19 kernel (pull streaming, BGK,
// periodic box, unshifted populations in one array per lattice, f[i * cells + k]). Not used for
// simulation: it measures what a straightforward implementation achieves on the same device.

struct Params {
    n: vec4<u32>,
    omega: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> src: array<f32>;
@group(0) @binding(2) var<storage, read_write> dst: array<f32>;

const CX = array<i32, 19>(0, 1, -1, 0, 0, 0, 0, 1, -1, 1, -1, 0, 0, 1, -1, 1, -1, 0, 0);
const CY = array<i32, 19>(0, 0, 0, 1, -1, 0, 0, 1, -1, 0, 0, 1, -1, -1, 1, 0, 0, 1, -1);
const CZ = array<i32, 19>(0, 0, 0, 0, 0, 1, -1, 0, 0, 1, -1, 1, -1, 0, 0, -1, 1, -1, 1);
const W = array<f32, 19>(
    1.0 / 3.0,
    1.0 / 18.0, 1.0 / 18.0, 1.0 / 18.0, 1.0 / 18.0, 1.0 / 18.0, 1.0 / 18.0,
    1.0 / 36.0, 1.0 / 36.0, 1.0 / 36.0, 1.0 / 36.0, 1.0 / 36.0, 1.0 / 36.0,
    1.0 / 36.0, 1.0 / 36.0, 1.0 / 36.0, 1.0 / 36.0, 1.0 / 36.0, 1.0 / 36.0,
);

fn wrap(q: i32, n: i32) -> u32 {
    return u32(select(select(q, q - n, q >= n), q + n, q < 0));
}

@compute @workgroup_size(64)
fn naive_pull(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
              @builtin(local_invocation_index) local: u32) {
    let n = params.n.xyz;
    let cells = n.x * n.y * n.z;
    let k = (wg.y * nwg.x + wg.x) * 64u + local;
    if k >= cells { return; }
    let x = k % n.x;
    let y = (k / n.x) % n.y;
    let z = k / (n.x * n.y);
    var f: array<f32, 19>;
    var rho = 0.0;
    var u = vec3<f32>(0.0);
    for (var i = 0u; i < 19u; i++) {
        let sx = wrap(i32(x) - CX[i], i32(n.x));
        let sy = wrap(i32(y) - CY[i], i32(n.y));
        let sz = wrap(i32(z) - CZ[i], i32(n.z));
        f[i] = src[i * cells + sx + n.x * (sy + n.y * sz)];
        rho += f[i];
        u += f[i] * vec3<f32>(f32(CX[i]), f32(CY[i]), f32(CZ[i]));
    }
    u /= rho;
    for (var i = 0u; i < 19u; i++) {
        let cu = dot(vec3<f32>(f32(CX[i]), f32(CY[i]), f32(CZ[i])), u);
        let feq = W[i] * rho * (1.0 + 3.0 * cu + 4.5 * cu * cu - 1.5 * dot(u, u));
        dst[i * cells + k] = f[i] - params.omega.x * (f[i] - feq);
    }
}
