// 16-bit storage of the populations (`lattice.storage = "fp16s"` or `"fp16c"`): f_i - w_i in 16
// bits, two cells to a u32 word (cell 2m in the low half, 2m + 1 in the high half), one storage
// buffer per direction; the arithmetic stays in f32. `encode16` and `decode16` (fp16s.wgsl or
// fp16c.wgsl) convert one value. Core WGSL has no 16-bit store, and in the AA pattern the two
// cells of a word are written by different invocations (in the odd step slot i of cell x is
// written by cell x - c_i): a store is therefore two atomics on the word, which clear the cell's
// half and set it, leaving the other half to its own writer. No other invocation touches the
// cell's half in a step (the AA pattern), so the load needs no more than one atomic load.
@group(0) @binding(5) var<storage, read_write> f0: array<atomic<u32>>;
@group(0) @binding(6) var<storage, read_write> f1: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> f2: array<atomic<u32>>;
@group(0) @binding(8) var<storage, read_write> f3: array<atomic<u32>>;
@group(0) @binding(9) var<storage, read_write> f4: array<atomic<u32>>;
@group(0) @binding(10) var<storage, read_write> f5: array<atomic<u32>>;
@group(0) @binding(11) var<storage, read_write> f6: array<atomic<u32>>;
@group(0) @binding(12) var<storage, read_write> f7: array<atomic<u32>>;
@group(0) @binding(13) var<storage, read_write> f8: array<atomic<u32>>;
@group(0) @binding(14) var<storage, read_write> f9: array<atomic<u32>>;
@group(0) @binding(15) var<storage, read_write> f10: array<atomic<u32>>;
@group(0) @binding(16) var<storage, read_write> f11: array<atomic<u32>>;
@group(0) @binding(17) var<storage, read_write> f12: array<atomic<u32>>;
@group(0) @binding(18) var<storage, read_write> f13: array<atomic<u32>>;
@group(0) @binding(19) var<storage, read_write> f14: array<atomic<u32>>;
@group(0) @binding(20) var<storage, read_write> f15: array<atomic<u32>>;
@group(0) @binding(21) var<storage, read_write> f16: array<atomic<u32>>;
@group(0) @binding(22) var<storage, read_write> f17: array<atomic<u32>>;
@group(0) @binding(23) var<storage, read_write> f18: array<atomic<u32>>;

//#for i
fn load{i}(k: u32) -> f32 {
    return decode16(load_bits{i}(k));
}

fn store{i}(k: u32, value: f32) {
    store_bits{i}(k, encode16(value));
}

// The stored 16 bits of a population (the halo exchange moves them: halo.wgsl).
fn load_bits{i}(k: u32) -> u32 {
    return (atomicLoad(&f{i}[k >> 1u]) >> ((k & 1u) * 16u)) & 0xffffu;
}

fn store_bits{i}(k: u32, bits: u32) {
    let shift = (k & 1u) * 16u;
    atomicAnd(&f{i}[k >> 1u], ~(0xffffu << shift));
    atomicOr(&f{i}[k >> 1u], bits << shift);
}
//#end
