// the supersampled reference's end of each frame, instead of finish's `finish_main`
// module supersample (kernels): core/supersample.wgsl
// The supersampled reference (`--supersample`, docs/msaa.md): one single-sample reference frame a
// sample position, each frame's linear colours added up on the device across the frames, the
// last frame's image the mean. This kernel replaces `finish_main` (finish.wgsl) at the end of
// sample `fu.param`'s frame of `fu.pass_index` frames.
//
// `sums` holds two running sums of 3 words a pixel (f32 linear RGB): frame i reads half i mod 2
// (where i > 0) and writes half (i + 1) mod 2, so a frame that runs again (its speculation or
// setup found wrong at its end) adds its colour to the same sum as the first attempt did.
@group(0) @binding(2) var<storage, read_write> image: array<u32>;
// [captured total, max captured, tied total, lost total]
@group(0) @binding(3) var<storage, read_write> totals: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read_write> sums: array<f32>;

@compute @workgroup_size(64)
fn supersample_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    let i = fu.param;
    let frames = fu.pass_index;
    let half = 3u * fu.pixel_count;
    let c = finish_color(px, atomicLoad(&totals[1]));
    var sum = c;
    if (i > 0u) {
        let src = (i % 2u) * half + 3u * px;
        sum = vec3<f32>(sums[src], sums[src + 1u], sums[src + 2u]) + c;
    }
    let dst = ((i + 1u) % 2u) * half + 3u * px;
    sums[dst] = sum.x;
    sums[dst + 1u] = sum.y;
    sums[dst + 2u] = sum.z;
    if (i + 1u == frames) {
        // 4 or 8 frames: the division exact, as oit-cpu's
        image[px] = srgb_pixel(sum * (1.0 / f32(frames)));
    } else {
        // this sample's frame alone
        image[px] = srgb_pixel(c);
    }
}
