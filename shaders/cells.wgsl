// The per-cell kernel (`lattice.kernel = "cells"`), shaped for GPUs: one invocation per cell of the
// grid in one dispatch per step, no cell list and no four-cell quads, the AA pattern of lbm.wgsl
// (in place, the even step in the cell's own slots, the odd step at the neighbours). Each
// invocation reads its cell's flags word: solid cells return; cells none of whose links leaves
// the fluid or wraps (the bulk) read and write at fixed index offsets; the others (walls, periodic
// faces, beside solids) take the general path of `stream_collide` (`update_cell`). A warp diverges only where it
// holds such a cell. The arithmetic is `moments`, `collide` and `solid_term`, as in the other
// kernels: every kernel leaves the same populations, bit for bit, whatever the storage or the way
// of the covered cells (the fused solid term, the redo's, or the skip's `skipped`).
//
// KIND 1 takes the cells of the cell list instead of every cell: one region of a step split into
// regions (the shell and the interior of a block whose halo exchange overlaps the interior's
// update), each cell computed as in KIND 0, bit for bit.
//
// Where a CPU driver such as lavapipe runs both sides of every branch, the quads' kernels
// (lbm.wgsl, quads.wgsl), split by cell class into branch-free dispatches, are the faster ones;
// the run's start-up trial (lbm-server/src/trials.rs) times both on the device.

@compute @workgroup_size(64)
fn stream_collide_cells(at: Invocation) {
    var k = cell_index(at);
    if KIND == 1u {
        // A region of the step (lbm-server/src/lbm/gpu/region.rs): the cells of its list.
        if k >= params.ranges.x + params.ranges.y + params.ranges.z { return; }
        k = cell_list[k];
    } else if k >= cell_count() {
        return;
    }
    let flag = flags[k];
    if (flag & SOLID) != 0u || skipped(k) { return; }
    if (flag & (WRAPS | 0x7ffffu)) != 0u {
        update_cell(k, flag);
        return;
    }
    let odd = params.n.w == 1u;
    let f = read_bulk(k, odd);
    let m = moments(f);
    store_bulk(k, odd, solid_term(k, f, m, collide(f, m)));
}
