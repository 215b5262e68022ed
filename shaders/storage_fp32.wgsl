// FP32 storage of the populations (`lattice.storage = "fp32"`, the default): one f32 per
// population, f_i - w_i, in one storage buffer per direction (structure of arrays). Every kernel
// reads and writes the populations through `load{i}` and `store{i}` (the storage's pair, one
// per direction: a static buffer access each, unrolled).
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
// The population buffers seen four cells at a time, for the four-cell quads (quads.wgsl: FP32
// only).
@group(0) @binding(5) var<storage, read_write> q0: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> q1: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> q2: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> q3: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read_write> q4: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read_write> q5: array<vec4<f32>>;
@group(0) @binding(11) var<storage, read_write> q6: array<vec4<f32>>;
@group(0) @binding(12) var<storage, read_write> q7: array<vec4<f32>>;
@group(0) @binding(13) var<storage, read_write> q8: array<vec4<f32>>;
@group(0) @binding(14) var<storage, read_write> q9: array<vec4<f32>>;
@group(0) @binding(15) var<storage, read_write> q10: array<vec4<f32>>;
@group(0) @binding(16) var<storage, read_write> q11: array<vec4<f32>>;
@group(0) @binding(17) var<storage, read_write> q12: array<vec4<f32>>;
@group(0) @binding(18) var<storage, read_write> q13: array<vec4<f32>>;
@group(0) @binding(19) var<storage, read_write> q14: array<vec4<f32>>;
@group(0) @binding(20) var<storage, read_write> q15: array<vec4<f32>>;
@group(0) @binding(21) var<storage, read_write> q16: array<vec4<f32>>;
@group(0) @binding(22) var<storage, read_write> q17: array<vec4<f32>>;
@group(0) @binding(23) var<storage, read_write> q18: array<vec4<f32>>;

//#for i
fn load{i}(k: u32) -> f32 {
    return f{i}[k];
}

fn store{i}(k: u32, value: f32) {
    f{i}[k] = value;
}

// The stored bits of a population (the halo exchange moves them: halo.wgsl).
fn load_bits{i}(k: u32) -> u32 {
    return bitcast<u32>(f{i}[k]);
}

fn store_bits{i}(k: u32, bits: u32) {
    f{i}[k] = bitcast<f32>(bits);
}
//#end
