// The fragment side of a geometry pass on a render pipeline: oit's hardware rasterizer
// (raster_hardware.wgsl) and a user's own pipeline embedding oit (embed.rs) both call these from
// their fragment shader. Comes after the technique's source, which defines `capture`.
//
// The value returned is what the fragment writes to oit's one-channel count target, which adds it
// up (additive blending): fragments per pixel, summed after the pass into the generated count.
// Blending counts without atomics, so counting costs a pass next to nothing and needs no binding
// in the user's layout.

// One fragment of a triangle: `pixel_xy` from `@builtin(position)` (pixel centres at .5), depth
// its `position.z` (NDC z in [0, 1]), colour straight-alpha linear RGBA, the world normal (zero
// when there is none; used by the Fresnel effect), `prim` the primitive id (ties between equal
// depths are broken by it).
fn oit_capture_full(pixel_xy: vec2<f32>, depth: f32, color: vec4<f32>, normal: vec3<f32>, prim: u32) -> vec4<f32> {
    return oit_capture_cut(pixel_xy, depth, color, normal, prim, 0.5);
}

// `oit_capture_full` with the opaque pass's cutoff (`Fragment::cutoff`): oit's hardware raster,
// whose textured masked objects are decided fragment by fragment. A fragment of any other alpha
// mode comes with alpha 1 or 0 (`Scene::layers`), which the half `oit_capture_full` takes splits.
fn oit_capture_cut(pixel_xy: vec2<f32>, depth: f32, color: vec4<f32>, normal: vec3<f32>, prim: u32, cutoff: f32) -> vec4<f32> {
    return oit_capture_masked(pixel_xy, depth, color, normal, prim, cutoff, 1u);
}

// `oit_capture_cut` of a fragment covering the samples `mask` of its pixel (a multisampled pass:
// `sample_mask`; 1 at one sample).
fn oit_capture_masked(pixel_xy: vec2<f32>, depth: f32, color: vec4<f32>, normal: vec3<f32>, prim: u32, cutoff: f32, mask: u32) -> vec4<f32> {
    let kept = oit_kept(pixel_xy, depth, mask);
    if (kept != 0u) {
        return oit_capture_shaded(pixel_xy, depth, color, normal, prim, cutoff, kept);
    }
    return vec4<f32>(1.0, 0.0, 0.0, 0.0);
}

// The samples of `mask` (a multisampled pass's coverage; 1 at one sample) the opaque pass leaves to
// a fragment at `pixel_xy` and `depth` (prelude.wgsl's `opaque_kept`, counted where the pass
// counts): 0 where it holds the fragment back at all of them.
fn oit_kept(pixel_xy: vec2<f32>, depth: f32, mask: u32) -> u32 {
    return oit_opaque_front(pixel_xy, depth, mask, true);
}

// `oit_kept`, counted only where `count` (`opaque_kept`), else not (`opaque_front`); a fragment
// outside the target keeps its mask.
fn oit_opaque_front(pixel_xy: vec2<f32>, depth: f32, mask: u32, count: bool) -> u32 {
    let xy = vec2<u32>(max(floor(pixel_xy), vec2<f32>(0.0)));
    if (xy.x >= fu.width || xy.y >= fu.height) {
        return mask;
    }
    var f: Fragment;
    f.pixel = xy.y * fu.width + xy.x;
    f.depth = clamp(depth, 0.0, 1.0);
    f.mask = mask;
    if (count) {
        return opaque_kept(f);
    }
    return opaque_front(f);
}

// What a fragment of a multisampled pass writes (an embedding user's pipeline at
// `CaptureShader::multisample` above one sample): oit's count at the first sample the fragment
// covers only, so the count target's samples add up to fragments (core/count_sum_texture_ms.wgsl),
// as oit's own `hw_fs_masked` writes it.
struct OitSampled {
    @location(0) count: vec4<f32>,
    @builtin(sample_mask) written: u32,
}

// `oit_capture_full` in a multisampled pass: `mask` is the fragment's `@builtin(sample_mask)`
// input (the samples it covers, which the technique composites it into); the fragment stage
// returns what this returns.
fn oit_capture_samples(pixel_xy: vec2<f32>, depth: f32, color: vec4<f32>, normal: vec3<f32>, prim: u32, mask: u32) -> OitSampled {
    var out: OitSampled;
    out.written = mask & (0u - mask);
    out.count = oit_capture_masked(pixel_xy, depth, color, normal, prim, 0.5, mask);
    return out;
}

// Whether the opaque pass holds back a fragment at `pixel_xy` and `depth` (`opaque_cut`: counted
// where the pass counts): oit's hardware raster asks before it shades, so a fragment behind the
// opaque depth costs no shading (as oit-cpu's and the compute path's).
fn oit_held_back(pixel_xy: vec2<f32>, depth: f32) -> bool {
    return oit_kept(pixel_xy, depth, (1u << opaque_samples()) - 1u) == 0u;
}

// Captures a fragment `oit_held_back` did not hold back; returns what it adds to the count target.
fn oit_capture_shaded(pixel_xy: vec2<f32>, depth: f32, color: vec4<f32>, normal: vec3<f32>, prim: u32, cutoff: f32, mask: u32) -> vec4<f32> {
    let xy = vec2<u32>(max(floor(pixel_xy), vec2<f32>(0.0)));
    if (xy.x < fu.width && xy.y < fu.height) {
        var f: Fragment;
        f.pixel = xy.y * fu.width + xy.x;
        f.depth = clamp(depth, 0.0, 1.0);
        f.prim = prim;
        f.color = clamp(color, vec4<f32>(0.0), vec4<f32>(1.0));
        f.normal = normalize_or_zero(normal);
        f.cutoff = cutoff;
        f.mask = mask;
        capture(coverage_weighted(f, fu.msaa, fu.opaque));
    }
    return vec4<f32>(1.0, 0.0, 0.0, 0.0);
}

// The same without a normal.
fn oit_capture(pixel_xy: vec2<f32>, depth: f32, color: vec4<f32>, prim: u32) -> vec4<f32> {
    return oit_capture_full(pixel_xy, depth, color, vec3<f32>(0.0), prim);
}
