// The four-cell quads (FP32 storage only, `lattice.storage`: their vector loads and stores move
// four f32 populations).

// The even step of four consecutive fluid cells none of whose links leaves the fluid: each vector
// load or store moves four populations, where llvmpipe loops over the SIMD lanes per access.
@compute @workgroup_size(64)
fn stream_collide_quads(at: Invocation) {
    let j = cell_index(at);
    if j >= params.ranges.w { return; }
    let q = cell_list[params.ranges.x + params.ranges.y + params.ranges.z + j];
    var a: array<f32, 19>;
    var b: array<f32, 19>;
    var c: array<f32, 19>;
    var d: array<f32, 19>;
    //#for i
    {
        let v = q{i}[q];
        a[{i}] = v.x;
        b[{i}] = v.y;
        c[{i}] = v.z;
        d[{i}] = v.w;
    }
    //#end
    let pa = collide(a, moments(a));
    let pb = collide(b, moments(b));
    let pc = collide(c, moments(c));
    let pd = collide(d, moments(d));
    // A skipped cell (SKIP: covered, updated in place before) sends along each link what it read
    // as the opposite link's population, from that very slot: each slot keeps what it holds.
    let skip = skipped_lanes(q);
    //#for i
    q{i.o}[q] = select(vec4<f32>(pa[{i}], pb[{i}], pc[{i}], pd[{i}]), vec4<f32>(a[{i.o}], b[{i.o}], c[{i.o}], d[{i.o}]), skip);
    //#end
}

// The odd step of four consecutive interior cells (nx a multiple of 4, so that a row offset is a
// whole number of vectors): populations along y and z move as vectors; those along x as one vector
// and one scalar load, and four scalar stores (a vector store would overwrite slots of the
// neighbouring quads).
@compute @workgroup_size(64)
fn stream_collide_quads_odd(at: Invocation) {
    let j = cell_index(at);
    if j >= params.quads.w { return; }
    let q = i32(cell_list[params.ranges.x + params.ranges.y + params.ranges.z + params.ranges.w + j]);
    let row = i32(params.n.x / 4u);
    let ny = i32(params.n.y);
    var a: array<f32, 19>;
    var b: array<f32, 19>;
    var c: array<f32, 19>;
    var d: array<f32, 19>;
    //#for i
    {
        // f_i of cell 4q + t comes from slot i.o of cell 4q + t - c_i.
        let e = q - row * ({i.cy} + ny * {i.cz});
        let v = q{i.o}[u32(e)];
        if {i.cx} == 0 {
            a[{i}] = v.x;
            b[{i}] = v.y;
            c[{i}] = v.z;
            d[{i}] = v.w;
        } else if {i.cx} == 1 {
            a[{i}] = q{i.o}[u32(e - 1)].w;
            b[{i}] = v.x;
            c[{i}] = v.y;
            d[{i}] = v.z;
        } else {
            a[{i}] = v.y;
            b[{i}] = v.z;
            c[{i}] = v.w;
            d[{i}] = q{i.o}[u32(e + 1)].x;
        }
    }
    //#end
    let pa = collide(a, moments(a));
    let pb = collide(b, moments(b));
    let pc = collide(c, moments(c));
    let pd = collide(d, moments(d));
    // A skipped cell (SKIP) sends along link i what it read as the opposite link's population:
    // slot i of cell 4q + t + c_i, which it was read from, keeps what it holds.
    let skip = skipped_lanes(u32(q));
    //#for i
    {
        // post_i of cell 4q + t goes to slot i of cell 4q + t + c_i.
        let e = q + row * ({i.cy} + ny * {i.cz});
        let v = select(vec4<f32>(pa[{i}], pb[{i}], pc[{i}], pd[{i}]), vec4<f32>(a[{i.o}], b[{i.o}], c[{i.o}], d[{i.o}]), skip);
        if {i.cx} == 0 {
            q{i}[u32(e)] = v;
        } else if {i.cx} == 1 {
            q{i}[u32(e)].y = v.x;
            q{i}[u32(e)].z = v.y;
            q{i}[u32(e)].w = v.z;
            q{i}[u32(e + 1)].x = v.w;
        } else {
            q{i}[u32(e - 1)].w = v.x;
            q{i}[u32(e)].x = v.y;
            q{i}[u32(e)].y = v.z;
            q{i}[u32(e)].z = v.w;
        }
    }
    //#end
}
