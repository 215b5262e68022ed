// The halo exchange of a lattice decomposed over ranks (lbm-server/src/parallel/halo.rs): `pack`
// copies the listed populations (cell, direction) of one layer of cells into a flat buffer, read
// back and sent to the neighbouring rank; `unpack` writes the neighbour's values into the listed
// populations. The populations are bound through the storage's `load{i}` / `store{i}` pair
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

fn halo_entry(wg: vec3<u32>, nwg: vec3<u32>, local: u32) -> u32 {
    return (wg.y * nwg.x + wg.x) * 64u + local;
}

@compute @workgroup_size(64)
fn pack(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let j = halo_entry(wg, nwg, local);
    if j >= arrayLength(&halo_list) { return; }
    let e = halo_list[j];
    halo_values[j] = load_any(e.y, e.x);
}

@compute @workgroup_size(64)
fn unpack(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let j = halo_entry(wg, nwg, local);
    if j >= arrayLength(&halo_list) { return; }
    let e = halo_list[j];
    store_any(e.y, e.x, halo_values[j]);
}
