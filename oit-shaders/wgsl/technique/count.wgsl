// module count (raster): technique/count.wgsl
// A counting pass: fragments per pixel (sizes arrays from the scene, and the reference's lists).
@group(0) @binding(2) var<storage, read_write> counts: array<atomic<u32>>;

fn capture(f: Fragment) {
    atomicAdd(&counts[f.pixel], 1u);
}

// [max count] into binding 3
@group(0) @binding(3) var<storage, read_write> max_count: array<atomic<u32>>;

@compute @workgroup_size(64)
fn max_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px < fu.pixel_count) {
        atomicMax(&max_count[0], atomicLoad(&counts[px]));
    }
}
