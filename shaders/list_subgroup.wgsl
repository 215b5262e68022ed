// The redo's lists of covered cells (imb.wgsl `join_list`) where the device has subgroup operations
// (wgpu's Features::SUBGROUP; naga 30 takes the builtins without `enable subgroups;`, which it
// refuses as not yet supported): an entry of the list counted by word `counter` of
// `particle_lists` for each invocation that wants one, with one atomic per subgroup, whose first
// invocation reserves the entries of all (a GPU serialises the atomics on one address: one per
// subgroup rather than one per covered cell). Every invocation of the subgroup calls it together, wanting an entry or not.
fn list_entry(want: bool, counter: u32) -> u32 {
    let one = select(0u, 1u, want);
    let rank = subgroupExclusiveAdd(one);
    let total = subgroupAdd(one);
    // The subgroup's first active invocation (naga 30 has no subgroupElect), whose value
    // subgroupBroadcastFirst hands to all.
    let leader = subgroupExclusiveAdd(1u) == 0u;
    var first = 0u;
    if leader && total > 0u {
        first = atomicAdd(&particle_lists[counter], total);
    }
    return subgroupBroadcastFirst(first) + rank;
}

// The position in particle j's list (FRONT counted by word 16 j of `particle_lists`, BACK by
// 16 j + 1) of each invocation whose cell joins one (`list`), 0 for NO_LIST: one atomic per
// subgroup and list.
fn list_position(j: u32, list: u32) -> u32 {
    let front = list_entry(list == FRONT, 16u * j);
    let back = list_entry(list == BACK, 16u * j + 1u);
    return select(back, front, list == FRONT);
}
