// module count_sum (kernels): vulkan/count_sum.wgsl
// Sums a hardware-raster geometry pass's fragment counts into one word: oit-wgpu's count_sum.wgsl
// over the count target copied into a buffer (one f32 per pixel, row by row), so the kernel binds
// buffers only. Group 0 as every module's: bindings 2 and 3 are the counts and the total.
@group(0) @binding(2) var<storage, read> pass_counts: array<f32>;
@group(0) @binding(3) var<storage, read_write> pass_total: array<atomic<u32>>;

var<workgroup> pass_wg: atomic<u32>;

@compute @workgroup_size(64)
fn count_sum_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    if (lid == 0u) {
        atomicStore(&pass_wg, 0u);
    }
    workgroupBarrier();
    let i = kernel_pixel(gid, groups);
    if (i < fu.pixel_count) {
        let n = u32(pass_counts[i] + 0.5);
        if (n > 0u) {
            atomicAdd(&pass_wg, n);
        }
    }
    workgroupBarrier();
    if (lid == 0u) {
        atomicAdd(&pass_total[0], atomicLoad(&pass_wg));
    }
}
