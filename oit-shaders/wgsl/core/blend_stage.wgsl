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
