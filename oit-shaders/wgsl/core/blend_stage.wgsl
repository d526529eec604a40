// What follows the hardware raster's vertex stage in a blend capture's module (oit-shaders'
// `Tail::Stage`: blend.wgsl, bdp_blend.wgsl, ddp_blend.wgsl, dp_depth.wgsl, adp_logic.wgsl): the
// one test every one of their fragment stages makes first, so that they draw the fragments the
// atomic captures capture and no other.

// Whether the fragment `in` is dropped before it writes anything: a single-sided object's back
// face (`hw_culled`), or a fragment the opaque pass holds back, at or behind its pixel's opaque
// depth (prelude.wgsl's `opaque_cut`, on the pixel and clamped depth `oit_capture_cut` gives the
// atomic captures). A blend pass is never the frame's first scene pass (the count-only draw or the
// bounds pass before it counts what the cut holds back, `occluded`), so this counts nothing.
fn hw_dropped(in: HwOut, front: bool) -> bool {
    if (hw_culled(in, front)) {
        return true;
    }
    let xy = vec2<u32>(max(floor(in.position.xy), vec2<f32>(0.0)));
    if (xy.x >= fu.width || xy.y >= fu.height) {
        return false;
    }
    var f: Fragment;
    f.pixel = xy.y * fu.width + xy.x;
    f.depth = clamp(in.position.z, 0.0, 1.0);
    return opaque_cut(f);
}

// The samples of `covered` (the sample mask a multisampled pass's fragment comes with: bit i the
// device's sample i, the standard positions as oit-core's) a blend capture's fragment keeps, as
// raster_hardware_masked.wgsl's `hw_fs_masked` hands the atomics captures theirs: none for a
// culled back face or outside the image, else those in front of their samples' opaque depths
// (prelude.wgsl's `opaque_kept`, which counts nothing in a blend pass).
fn hw_kept(in: HwOut, front: bool, covered: u32) -> u32 {
    if (hw_culled(in, front)) {
        return 0u;
    }
    let xy = vec2<u32>(max(floor(in.position.xy), vec2<f32>(0.0)));
    if (xy.x >= fu.width || xy.y >= fu.height) {
        return 0u;
    }
    var f: Fragment;
    f.pixel = xy.y * fu.width + xy.x;
    f.depth = clamp(in.position.z, 0.0, 1.0);
    f.mask = covered;
    return opaque_kept(f);
}

// The fragment's straight-alpha colour, clamped, its alpha weighted by the coverage of `kept`
// where the frame takes the coverage fraction (fragment.wgsl's `coverage_weighted`, as the atomics
// captures' fragments come), packed to 8 bits a channel as every capture's payload is.
fn hw_blend_packed(in: HwOut, kept: u32) -> u32 {
    var f: Fragment;
    f.color = clamp(hw_color(in), vec4<f32>(0.0), vec4<f32>(1.0));
    f.mask = kept;
    return pack_rgba8(coverage_weighted(f, fu.msaa, fu.opaque).color);
}

// `hw_blend_packed` unpacked: the 8-bit colour the blender adds.
fn hw_blend_color(in: HwOut, kept: u32) -> vec4<f32> {
    return unpack_rgba8(hw_blend_packed(in, kept));
}

// The lowest sample of `mask`: where a fragment of a multisampled blend pass writes a target whose
// samples its resolve combines by the blend's own operator (a sum, a MAX), so that each fragment
// is combined once, whatever it covers.
fn first_sample(mask: u32) -> u32 {
    return mask & (0u - mask);
}
