// The redo's list of covered cells (imb.wgsl `join_list`) where the device has subgroup operations
// (wgpu's Features::SUBGROUP; naga 30 takes the builtins without `enable subgroups;`, which it
// refuses as not yet supported): an entry of the list counted by
// status[counter] for each invocation that wants one, with one atomic per subgroup, whose first
// invocation reserves the entries of all. With one atomic per cell every covered cell of a step
// went through the same counter, which a GPU serialises (1.8 million a step at 32^3 spheres of 4
// cells). Every invocation of the subgroup calls it together, wanting an entry or not.
fn list_entry(want: bool, counter: u32) -> u32 {
    let one = select(0u, 1u, want);
    let rank = subgroupExclusiveAdd(one);
    let total = subgroupAdd(one);
    // The subgroup's first active invocation (naga 30 has no subgroupElect), whose value
    // subgroupBroadcastFirst hands to all.
    let leader = subgroupExclusiveAdd(1u) == 0u;
    var first = 0u;
    if leader && total > 0u {
        first = atomicAdd(&status[counter], total);
    }
    return subgroupBroadcastFirst(first) + rank;
}

// The position in its list (FRONT counted by status[4], BACK by status[8]) of each invocation
// whose cell joins one (`list`), 0 for NO_LIST: one atomic per subgroup and list.
fn list_position(list: u32) -> u32 {
    let front = list_entry(list == FRONT, 4u);
    let back = list_entry(list == BACK, 8u);
    return select(back, front, list == FRONT);
}
