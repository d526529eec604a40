// The multisampled hardware raster's fragment entry point, after raster_hardware.wgsl and the
// capture contract (capture_render.wgsl's `oit_capture_masked`): appended only where a technique's
// capture is (oit-shaders' `Module::hardware_text`, oit-wgpu's hardware path), not to the vertex
// stage an embedding user or the opaque draw compiles alone.
struct HwMaskedOut {
    @location(0) count: vec4<f32>,
    @builtin(sample_mask) written: u32,
}

// The fragment entry point of a multisampled pass (`fu.msaa.x` samples a pixel; docs/msaa.md):
// the fragment, shaded once at the pixel's centre, carries the samples it covers (`sample_mask`,
// bit i the device's sample i: the standard positions, as oit-core's), less those the opaque pass
// holds back (`oit_kept`), into the capture, and
// writes the count target at the first of them only, so the target's samples add up to
// fragments (core/count_sum_texture_ms.wgsl).
@fragment
fn hw_fs_masked(in: HwOut, @builtin(front_facing) front: bool, @builtin(sample_mask) covered: u32) -> HwMaskedOut {
    var out: HwMaskedOut;
    out.count = vec4<f32>(0.0);
    out.written = covered & (0u - covered);
    if (!hw_culled(in, front)) {
        out.count = vec4<f32>(1.0, 0.0, 0.0, 0.0);
        // the covered samples in front of their opaque depths (none: held back, unshaded)
        let kept = oit_kept(in.position.xy, in.position.z, covered);
        if (kept != 0u) {
            out.count = oit_capture_shaded(in.position.xy, in.position.z, hw_color(in), in.normal, in.prim, in.cutoff, kept);
        }
    }
    return out;
}
