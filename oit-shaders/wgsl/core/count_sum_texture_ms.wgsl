// Sums a multisampled count target of a render-pipeline geometry pass into one word: a
// multisampled pass's fragment adds 1 at one sample (the first it covers: raster_hardware.wgsl's
// `hw_fs_masked`), so every sample of every pixel is summed (count_sum_texture.wgsl at one
// sample).
@group(0) @binding(0) var counts_tex: texture_multisampled_2d<f32>;
@group(0) @binding(1) var<storage, read_write> counts_total: array<atomic<u32>>;

var<workgroup> counts_wg: atomic<u32>;

@compute @workgroup_size(8, 8)
fn count_sum_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    if (lid == 0u) {
        atomicStore(&counts_wg, 0u);
    }
    workgroupBarrier();
    let size = textureDimensions(counts_tex);
    if (gid.x < size.x && gid.y < size.y) {
        var n = 0u;
        for (var i = 0u; i < textureNumSamples(counts_tex); i++) {
            n += u32(textureLoad(counts_tex, vec2<i32>(gid.xy), i32(i)).x + 0.5);
        }
        if (n > 0u) {
            atomicAdd(&counts_wg, n);
        }
    }
    workgroupBarrier();
    if (lid == 0u) {
        atomicAdd(&counts_total[0], atomicLoad(&counts_wg));
    }
}
