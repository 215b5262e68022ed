// The halo exchange of a lattice decomposed over ranks (lbm-server/src/parallel/halo.rs): `halo`
// packs the stored bits of the listed populations (cell, direction) of one layer of cells into a
// flat buffer of words, read back and sent to the neighbouring rank, or with UNPACK writes the
// neighbour's words into the listed populations. The populations are bound through the storage's
// `load_bits{i}` / `store_bits{i}` pair (storage_fp32.wgsl: 32 bits, one population per word;
// storage_fp16.wgsl: 16 bits, two per word, the first in the low half), in group 0 as the
// lattice's kernels bind them: a message carries the storage's own bits, no conversion.

// (cell, direction) of each population of the layer, in the order both ranks list them.
@group(1) @binding(0) var<storage, read> halo_list: array<vec2<u32>>;
@group(1) @binding(1) var<storage, read_write> halo_words: array<u32>;

fn load_bits_any(i: u32, k: u32) -> u32 {
    switch i {
        //#for d
        case {d}u: { return load_bits{d}(k); }
        //#end
        default: { return 0u; }
    }
}

fn store_bits_any(i: u32, k: u32, bits: u32) {
    switch i {
        //#for d
        case {d}u: { store_bits{d}(k, bits); }
        //#end
        default: {}
    }
}

// Unpack (write the words into the populations) rather than pack, fixed when the pipeline is
// made.
override UNPACK: bool = false;
// Populations per word: 1 with 32-bit storage, 2 with 16-bit storage.
override PER_WORD: u32 = 1u;

@compute @workgroup_size(64)
fn halo(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let j = (wg.y * nwg.x + wg.x) * 64u + local;
    let len = arrayLength(&halo_list);
    if j * PER_WORD >= len { return; }
    let bits = 32u / PER_WORD;
    let mask = select(0xffffu, 0xffffffffu, PER_WORD == 1u);
    var word = 0u;
    if UNPACK {
        word = halo_words[j];
    }
    for (var p = 0u; p < PER_WORD; p++) {
        let n = j * PER_WORD + p;
        if n >= len { break; }
        let e = halo_list[n];
        if UNPACK {
            store_bits_any(e.y, e.x, (word >> (p * bits)) & mask);
        } else {
            word |= load_bits_any(e.y, e.x) << (p * bits);
        }
    }
    if !UNPACK {
        halo_words[j] = word;
    }
}
