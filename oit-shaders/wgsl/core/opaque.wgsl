// the opaque pass's two geometry passes (oit-gpu's `technique::opaque_pass`)
// module opaque (raster): core/opaque.wgsl
// The opaque pass (oit-gpu's `technique::opaque_pass`; oit-cpu's `opaque::draw`): a frame's
// opaque and masked geometry drawn into its opaque image (prelude.wgsl's `opaque_keys` and
// `opaque_rgb`) before the technique runs. Pass 0: each pixel keeps the smallest
// `depth bits << 32 | primitive id` by a 64-bit atomic MIN, so ties between coplanar triangles
// resolve by id whatever order the fragments arrive in; a fragment a mask discards (alpha under its
// cutoff, `Fragment::cutoff`) is counted and goes no further. Pass 1: the one fragment whose key won writes its linear RGB.
// Above one sample the image is kept a sample: a fragment writes only the samples its coverage mask
// holds (`f.mask`; 1 at one sample), each sample keeping its own nearest key and colour.

fn capture(f: Fragment) {
    let key = (u64(depth_bits(f.depth)) << 32u) | u64(f.prim);
    let n = opaque_samples();
    if (fu.pass_index == 0u) {
        if (f.color.w < f.cutoff) {
            atomicAdd(&opaque_rgb[opaque_counter(0u)], 1u);
            return;
        }
        for (var i = 0u; i < n; i++) {
            if (((f.mask >> i) & 1u) != 0u) {
                atomicMin(&opaque_keys[f.pixel * n + i], key);
            }
        }
    } else {
        for (var i = 0u; i < n; i++) {
            let s = f.pixel * n + i;
            if (((f.mask >> i) & 1u) != 0u && atomicLoad(&opaque_keys[s]) == key) {
                atomicStore(&opaque_rgb[3u * s], bitcast<u32>(f.color.x));
                atomicStore(&opaque_rgb[3u * s + 1u], bitcast<u32>(f.color.y));
                atomicStore(&opaque_rgb[3u * s + 2u], bitcast<u32>(f.color.z));
            }
        }
    }
}

// After the opaque pass: each 8×8 tile of the compute rasterizer (raster_compute.wgsl's `TILE`)
// keeps the farthest opaque depth of its samples (the high word of their keys: all ones where a
// sample has none, which skips nothing), complemented, so that a pass may skip a work item whose
// triangle lies wholly behind it.
@compute @workgroup_size(64)
fn opaque_tiles_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let t = kernel_pixel(gid, groups);
    let tiles_x = (fu.width + 7u) / 8u;
    if (t >= tiles_x * ((fu.height + 7u) / 8u)) {
        return;
    }
    let x0 = (t % tiles_x) * 8u;
    let y0 = (t / tiles_x) * 8u;
    let n = opaque_samples();
    var far = 0u;
    for (var y = y0; y < min(y0 + 8u, fu.height); y++) {
        for (var x = x0; x < min(x0 + 8u, fu.width); x++) {
            for (var i = 0u; i < n; i++) {
                far = max(far, u32(atomicLoad(&opaque_keys[(y * fu.width + x) * n + i]) >> 32u));
            }
        }
    }
    atomicStore(&opaque_rgb[opaque_tile_word(t)], ~far);
}
