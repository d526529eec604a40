// The opaque pass (oit-gpu's `technique::opaque_pass`; oit-cpu's `opaque::draw`): a frame's
// opaque and masked geometry drawn into its opaque image (prelude.wgsl's `opaque_keys` and
// `opaque_rgb`) before the technique runs. Pass 0: each pixel keeps the smallest
// `depth bits << 32 | primitive id` by a 64-bit atomic MIN, so ties between coplanar triangles
// resolve by id whatever order the fragments arrive in; a fragment a mask discards (alpha under its
// cutoff, `Fragment::cutoff`) is counted and goes no further. Pass 1: the one fragment whose key won writes its linear RGB.

fn capture(f: Fragment) {
    let key = (u64(depth_bits(f.depth)) << 32u) | u64(f.prim);
    if (fu.pass_index == 0u) {
        if (f.color.w < f.cutoff) {
            atomicAdd(&opaque_rgb[3u * fu.pixel_count], 1u);
            return;
        }
        atomicMin(&opaque_keys[f.pixel], key);
    } else if (atomicLoad(&opaque_keys[f.pixel]) == key) {
        atomicStore(&opaque_rgb[3u * f.pixel], bitcast<u32>(f.color.x));
        atomicStore(&opaque_rgb[3u * f.pixel + 1u], bitcast<u32>(f.color.y));
        atomicStore(&opaque_rgb[3u * f.pixel + 2u], bitcast<u32>(f.color.z));
    }
}
