// The redo's lists of covered cells (imb.wgsl `join_list`) where the device has no subgroup
// operations: the position in particle j's list (FRONT counted by word 16 j of `particle_lists`,
// BACK by 16 j + 1) of each invocation whose cell joins one, one atomic each (list_subgroup.wgsl
// takes one per subgroup and list); 0 for NO_LIST. The counters are particle j's alone: only its
// workgroup of `cover` touches them (on a CPU driver, one core), where a counter shared by every
// particle moved its cache line between the cores at each covered cell.
fn list_position(j: u32, list: u32) -> u32 {
    if list == NO_LIST {
        return 0u;
    }
    return atomicAdd(&particle_lists[16u * j + list], 1u);
}
