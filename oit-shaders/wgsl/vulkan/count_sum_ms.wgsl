// the same over a multisampled count image (several samples a pixel)
// module count_sum_ms (kernels): vulkan/count_sum_ms.wgsl
// Sums a multisampled hardware-raster geometry pass's count image into one word (oit-vulkan at
// several samples a pixel; count_sum.wgsl at one): a multisampled pass's fragment adds 1 at one
// sample, the first it covers (raster_hardware.wgsl's `hw_fs_masked`), so every sample of every
// pixel is summed. The image is read where it lies (group 1, a sampled image); group 0 as every
// module's: binding 2 is the total.
@group(0) @binding(2) var<storage, read_write> pass_total: array<atomic<u32>>;
@group(1) @binding(0) var pass_counts: texture_multisampled_2d<f32>;

var<workgroup> pass_wg: atomic<u32>;

@compute @workgroup_size(64)
fn count_sum_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    if (lid == 0u) {
        atomicStore(&pass_wg, 0u);
    }
    workgroupBarrier();
    let size = textureDimensions(pass_counts);
    let i = kernel_pixel(gid, groups);
    if (i < size.x * size.y) {
        var n = 0u;
        for (var k = 0u; k < textureNumSamples(pass_counts); k++) {
            n += u32(textureLoad(pass_counts, vec2<i32>(i32(i % size.x), i32(i / size.x)), i32(k)).x + 0.5);
        }
        if (n > 0u) {
            atomicAdd(&pass_wg, n);
        }
    }
    workgroupBarrier();
    if (lid == 0u) {
        atomicAdd(&pass_total[0], atomicLoad(&pass_wg));
    }
}
