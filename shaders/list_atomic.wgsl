// The redo's list of covered cells (imb.wgsl `join_list`) where the device has no subgroup
// operations: the position in its list (FRONT counted by status[4], BACK by status[8]) of each
// invocation whose cell joins one, one atomic each (list_subgroup.wgsl takes one per subgroup and
// list); 0 for NO_LIST. One atomic per invocation on the list's own counter: on llvmpipe each
// atomic is a loop over the SIMD lanes, one such loop rather than one per list.
fn list_position(list: u32) -> u32 {
    if list == NO_LIST {
        return 0u;
    }
    return atomicAdd(&status[4u + 4u * list], 1u);
}
