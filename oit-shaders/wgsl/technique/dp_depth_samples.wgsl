// dp's depth peel at several samples: a depth a sample, each sample's layer into its own accumulator
// module dp_depth_samples (stage): technique/peel_samples.wgsl technique/dp_depth_samples.wgsl
// dp through the graphics pipeline at several samples a pixel (`--hardware-capture blend`,
// `--samples 4|8`; docs/msaa.md, "Depth peeling per sample on the blender"): dp_depth.wgsl's
// depth peel with its depth kept a sample, and its ties peeled in primitive order. Each peel
// renders the scene into a fresh multisampled Depth32Float attachment (LESS, cleared to 1), a
// multisampled Rg32Uint layer and a multisampled R32Uint primitive target; the fragment stage
// writes its one depth (the pixel centre's, as `frag_depth` halved, so every sample it covers
// tests the depth oit's other captures key it by) to the samples it keeps (`hw_kept`: those it covers in
// front of their opaque depths) whose key (depth, primitive id) lies strictly behind the key the
// previous peel left at that sample (its depth and its primitive id + 1, read a sample from the
// other of two ping-ponged depth and primitive targets). The LESS test keeps, of equal depths,
// the first drawn, which is the smallest primitive id (the hardware path draws triangle t as
// primitive t, and the depth test runs in primitive order), so each sample peels its fragments
// in (depth, primitive id) order, one a peel, as the per-sample reference composites them and
// the atomics capture's per-sample peel (dp_samples.wgsl) keys them: a tie at a sample is two
// layers, none lost. The layer holds (payload, kept mask): a compute step composites each
// sample's layer into that sample's accumulator (peel_samples.wgsl), counting a fragment once, at
// the lowest sample it keeps (where it is peeled once); after the last peel every pixel's samples
// are finished over their own opaque colours (`accumulated`).
//
// The attachment holds half the depth (`frag_depth` d/2, exact for every depth above 2^-125, so
// the order and the ties of depths stay as they were), so that a fragment at depth 1 exactly
// passes LESS against the attachment's clear value of 1. Above one sample a fragment's depth is
// its plane's at the pixel centre, which may lie outside the triangle and clamp to 1: an edge
// fragment of the bunny at 8 samples did, on an NVIDIA H100 and H200, and was never peeled
// while the depth itself was kept.
//
// Module: COMMON_WGSL, TECHNIQUE_PRELUDE (group 0: fu, state), peel_samples.wgsl (group 0 binding
// 5: the accumulators), this, then the hardware raster's vertex stage (group 1 bindings 0..4) and
// blend_stage.wgsl (`hw_kept`).

// The previous peel's depth and primitive id + 1 (0: none peeled), a sample (render pipeline,
// group 2; unused on the first peel).
@group(2) @binding(0) var dps_previous: texture_depth_multisampled_2d;
@group(2) @binding(1) var dps_previous_prim: texture_multisampled_2d<u32>;

// This peel's layer and depth, a sample (compute pipeline, group 1, after the vertex stage's).
@group(1) @binding(3) var dps_layer: texture_multisampled_2d<u32>;
@group(1) @binding(4) var dps_layer_depth: texture_depth_multisampled_2d;

struct DpPeelMsOut {
    @location(0) layer: vec2<u32>,
    @location(1) prim: u32,
    @builtin(frag_depth) depth: f32,
    @builtin(sample_mask) written: u32,
}

@fragment
fn dp_peel_ms_fs(in: HwOut, @builtin(front_facing) front: bool, @builtin(sample_mask) covered: u32) -> DpPeelMsOut {
    let kept = hw_kept(in, front, covered);
    let xy = vec2<u32>(max(floor(in.position.xy), vec2<f32>(0.0)));
    let depth = clamp(in.position.z, 0.0, 1.0);
    // what the attachment holds: half the depth, exactly
    let half_depth = depth * 0.5;
    var behind = kept;
    if (fu.pass_index > 0u) {
        for (var i = 0u; i < fu.msaa.x; i++) {
            if (((behind >> i) & 1u) != 0u) {
                let previous = textureLoad(dps_previous, vec2<i32>(xy), i32(i));
                let previous_prim = textureLoad(dps_previous_prim, vec2<i32>(xy), i32(i)).x;
                // strictly behind by (depth, primitive id): at the previous depth, a later primitive
                if (half_depth < previous || (half_depth == previous && in.prim + 1u <= previous_prim)) {
                    behind &= ~(1u << i);
                }
            }
        }
    }
    if (behind == 0u) {
        discard;
    }
    var f: Fragment;
    f.pixel = xy.y * fu.width + xy.x;
    f.depth = depth;
    f.prim = in.prim;
    f.color = clamp(hw_color(in), vec4<f32>(0.0), vec4<f32>(1.0));
    f.normal = normalize_or_zero(in.normal);
    return DpPeelMsOut(vec2<u32>(payload(f, fu.effect), kept), in.prim + 1u, half_depth, behind);
}

// Composites this peel's layer, each sample's into that sample's accumulator (one invocation a
// pixel); the first peel sets the accumulators first.
@compute @workgroup_size(64)
fn dp_composite_ms_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    if (fu.pass_index == 0u) {
        accumulators_init(px, 1u);
    }
    let xy = vec2<i32>(i32(px % fu.width), i32(px / fu.width));
    var counted = 0u;
    for (var i = 0u; i < fu.msaa.x; i++) {
        let layer = textureLoad(dps_layer, xy, i32(i)).xy;
        if (layer.y == 0u) {
            continue;
        }
        // a fragment once, at the lowest sample it keeps
        if ((layer.y & (0u - layer.y)) == (1u << i)) {
            counted += 1u;
        }
        accumulate_samples(px, 1u, layer.x, 1u << i, 0u);
    }
    if (counted != 0u) {
        var s = load_state(px);
        s.captured += counted;
        store_state(px, s);
    }
}

// After the last peel: every pixel's samples finished over what lies behind them.
@compute @workgroup_size(64)
fn dp_finish_ms_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    accumulated(px, 1u);
}
