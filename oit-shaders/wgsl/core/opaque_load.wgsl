// The caller's opaque image loaded into a frame's (oit-wgpu's `OitPass::with_opaque`): an embedding
// renderer drew its opaque geometry into its own depth buffer (and colour target) before the
// OIT pass, and this kernel copies them, texel for texel, into the buffers oit's own opaque pass
// fills (prelude.wgsl's `opaque_keys` and `opaque_rgb`), so every technique's cut and composite
// run unchanged. Per pixel: the key `depth bits << 32 | 0` (the caller's depth, NDC z in [0, 1],
// smaller nearer), and the linear RGB the composite goes over: the caller's colour as the load
// returns it (a `…Srgb` texture decoded), else the background.
//
// Later: a read-only depth attachment with the hardware depth test would cut the fragments before
// the fragment shader runs; this copy keeps one code path for every technique.

struct LoadUniform {
    // width, height, 1 where a colour texture is bound, unused
    size: vec4<u32>,
    background: vec4<f32>,
}

@group(0) @binding(0) var<uniform> lu: LoadUniform;
@group(0) @binding(1) var load_depth: texture_depth_2d;
@group(0) @binding(2) var load_color: texture_2d<f32>;
// the keys as two words a pixel (low, high) and the colours, 3 words a pixel
@group(0) @binding(3) var<storage, read_write> load_keys: array<u32>;
@group(0) @binding(4) var<storage, read_write> load_rgb: array<u32>;

@compute @workgroup_size(8, 8)
fn opaque_load_main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= lu.size.x || id.y >= lu.size.y) {
        return;
    }
    let px = id.y * lu.size.x + id.x;
    let xy = vec2<i32>(id.xy);
    let depth = textureLoad(load_depth, xy, 0);
    load_keys[2u * px] = 0u;
    load_keys[2u * px + 1u] = depth_bits(depth);
    var rgb = lu.background.xyz;
    if (lu.size.z != 0u) {
        rgb = textureLoad(load_color, xy, 0).xyz;
    }
    load_rgb[3u * px] = bitcast<u32>(rgb.x);
    load_rgb[3u * px + 1u] = bitcast<u32>(rgb.y);
    load_rgb[3u * px + 2u] = bitcast<u32>(rgb.z);
}
