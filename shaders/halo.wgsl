// The halo exchange of a lattice decomposed over ranks (lbm-server/src/parallel/halo.rs): `halo`
// packs the listed populations (cell, direction) of one layer of cells into a flat buffer, read
// back and sent to the neighbouring rank, or with UNPACK writes the neighbour's values into the
// listed populations. The populations are bound through the storage's `load{i}` / `store{i}` pair
// (storage_fp32.wgsl, or storage_fp16.wgsl with fp16s.wgsl or fp16c.wgsl), in group 0 as the
// lattice's kernels bind them; a value round-trips through f32 exactly in every storage.

// (cell, direction) of each population of the layer, in the order both ranks list them.
@group(1) @binding(0) var<storage, read> halo_list: array<vec2<u32>>;
@group(1) @binding(1) var<storage, read_write> halo_values: array<f32>;

fn load_any(i: u32, k: u32) -> f32 {
    switch i {
        //#for d
        case {d}u: { return load{d}(k); }
        //#end
        default: { return 0.0; }
    }
}

fn store_any(i: u32, k: u32, value: f32) {
    switch i {
        //#for d
        case {d}u: { store{d}(k, value); }
        //#end
        default: {}
    }
}

// Unpack (write the values into the populations) rather than pack, fixed when the pipeline is
// made.
override UNPACK: bool = false;

@compute @workgroup_size(64)
fn halo(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let j = (wg.y * nwg.x + wg.x) * 64u + local;
    if j >= arrayLength(&halo_list) { return; }
    let e = halo_list[j];
    if UNPACK {
        store_any(e.y, e.x, halo_values[j]);
    } else {
        halo_values[j] = load_any(e.y, e.x);
    }
}
