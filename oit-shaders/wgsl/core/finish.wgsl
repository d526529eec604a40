// module finish (kernels): core/finish.wgsl
// The last kernels of every frame: the state becomes sRGB8 pixels; totals for the stats.
@group(0) @binding(2) var<storage, read_write> image: array<u32>;
// [captured total, max captured, tied total, lost total]
@group(0) @binding(3) var<storage, read_write> totals: array<atomic<u32>>;

// Pixel `px`'s part of the totals, from its state `s`.
fn add_totals(px: u32, s: PixelState) {
    let c = s.captured;
    if (c > 0u) {
        atomicAdd(&totals[0], c);
        atomicMax(&totals[1], c);
    }
    let lost = atomicLoad(&acct[3u * px]);
    if (lost > 0u) {
        atomicAdd(&totals[3], lost);
    }
    let tied = state_tied(s);
    if (tied > 0u) {
        atomicAdd(&totals[2], tied);
    }
}

@compute @workgroup_size(64)
fn totals_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    add_totals(px, load_state(px));
}

@compute @workgroup_size(64)
fn finish_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    image[px] = srgb_pixel(finish_color(px, atomicLoad(&totals[1])));
}

// `totals_main` and `finish_main` in one kernel, each pixel's state read once, for a frame whose
// pixels do not need a frame-wide total first: every effect but the heat map (whose scale is the
// deepest pixel's count). Half the state's reads of the two kernels, and one dispatch and barrier
// fewer, a frame.
@compute @workgroup_size(64)
fn totals_finish_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    let s = load_state(px);
    add_totals(px, s);
    image[px] = srgb_pixel(finish_color_of(px, s, 0u));
}
