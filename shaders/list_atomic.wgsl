// The redo's list of covered cells (imb.wgsl `join_list`) where the device has no subgroup
// operations: an entry of the list counted by status[counter] for each invocation that wants one,
// one atomic each (list_subgroup.wgsl takes one per subgroup).
fn list_entry(want: bool, counter: u32) -> u32 {
    if !want {
        return 0u;
    }
    return atomicAdd(&status[counter], 1u);
}
