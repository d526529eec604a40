// module bounds (raster): technique/bounds.wgsl
// Per-pixel depth range [zNear, zFar] for bdp and adp (oit-cpu's `Ctx::depth_bounds`): one
// geometry pass over the scene or its bounding boxes, u32 atomicMin/atomicMax of `depth_bits`.
// bounds[2·px] = zNear, bounds[2·px + 1] = zFar (depth bits); pixels nothing reached get [0, 1].
@group(0) @binding(2) var<storage, read_write> bounds: array<atomic<u32>>;

fn capture(f: Fragment) {
    let b = depth_bits(f.depth);
    atomicMin(&bounds[2u * f.pixel], b);
    atomicMax(&bounds[2u * f.pixel + 1u], b);
}

@compute @workgroup_size(64)
fn bounds_init_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    atomicStore(&bounds[2u * px], 0xffffffffu);
    atomicStore(&bounds[2u * px + 1u], 0u);
}

@compute @workgroup_size(64)
fn bounds_finish_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    if (atomicLoad(&bounds[2u * px]) > atomicLoad(&bounds[2u * px + 1u])) {
        atomicStore(&bounds[2u * px], 0u);
        atomicStore(&bounds[2u * px + 1u], 0x3f800000u);
    }
}
