// An indirect dispatch's four words for `groups` workgroups of 64: (x, y, 1, 0) with x ≤ 65535
// and the rest in y (oit-gpu's `dispatch_size`, whose `raster_args` writes the same for a frame
// set up on the host). The compute path's setup (`setup_finish_main`) and its classification of
// work items (`classify_finish_main`) write their raster dispatches with it.
fn dispatch_words(groups: u32) -> vec4<u32> {
    if (groups <= 65535u) {
        return vec4<u32>(groups, 1u, 1u, 0u);
    }
    return vec4<u32>(65535u, (groups + 65534u) / 65535u, 1u, 0u);
}
