// The hardware raster's entry points over the opaque pass's depth in the fixed-function depth
// test (one sample a pixel; issue 38): appended after raster_hardware.wgsl and the capture
// contract only where the device takes `@early_depth_test` (oit-wgpu's hardware path with
// SHADER_EARLY_DEPTH_TEST; every Vulkan device), not to what an embedding user compiles.
//
// Each such pass has a depth attachment of its own, which its first draw (`depth_vs`/`depth_fs`)
// fills with each pixel's opaque depth (1.0 where no opaque fragment fell); its capture draw
// tests LESS_OR_EQUAL against it, without writing, before the fragment stage runs, so a fragment
// behind the opaque depth costs neither shading nor capture. The test keeps ties (a fragment at
// exactly the opaque depth, which the cut holds back: `opaque_cut` is strict); this stage holds
// them back itself. The frame's first scene pass counts every fragment once: the capture counts
// those its test passes, and the count-only draw (`hw_fs_count`), drawn first behind the opposite
// test (GREATER), counts those the capture's test drops. Both count by atomic adds to two words
// (the fragments, and those the cut holds back: `occluded`); neither writes the count target.
// Each also holds its fragments to the stage's own comparison with the opaque key, so a fixed-
// function test that disagreed with it would leave a fragment counted but neither captured nor
// held back, which the frame's accounting check refuses.

// The capture behind the fixed-function test: what `hw_fs` does with the fragments the test
// passed. In the frame's first scene pass (`fu.opaque.y`) it counts each of them, and the ties
// the cut holds back (`opaque_kept` counts only there). Its pipeline writes no colour: nothing
// reads a later pass's count target. `hw_fs_early_counted` is the same capture adding 1 to the
// count target, for a pass whose count is read without a count-only draw.
fn hw_early_capture(in: HwOut, front: bool) {
    if (hw_culled(in, front)) {
        return;
    }
    if (fu.opaque.y != 0u) {
        atomicAdd(&opaque_rgb[opaque_counter(2u)], 1u);
    }
    if (oit_opaque_front(in.position.xy, in.position.z, 1u, true) != 0u) {
        _ = oit_capture_shaded(in.position.xy, in.position.z, hw_color(in), in.normal, in.prim, in.cutoff, 1u);
    }
}

@fragment
@early_depth_test(force)
fn hw_fs_early(in: HwOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    hw_early_capture(in, front);
    return vec4<f32>(0.0);
}

@fragment
@early_depth_test(force)
fn hw_fs_early_counted(in: HwOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    hw_early_capture(in, front);
    return vec4<f32>(1.0, 0.0, 0.0, 0.0);
}

// The count-only draw of a frame's first scene pass over the opaque depth, behind the test
// GREATER: the fragments the capture's test drops (a back face of a single-sided object excepted,
// as `hw_fs`). Each adds 1 to opaque_rgb's counter 2 (the pass's fragments, with the capture's;
// the pass copies it to its fragment count in place of the count target's sum), and
// `oit_held_back` counts it as `occluded`. Its pipeline writes no colour: blending every fragment
// into the float count target cost an H100 about a millisecond of each 1024² hardware frame of
// `planes:64` (bench/results/h100/count-draw-soa-1024). Drawn untested, it shaded every fragment
// of the scene, those in front of the opaque depth too, in every frame with an opaque part; behind
// the test it shades only those held back (an H200 at 1024²: every walled hardware frame of
// `planes:64` faster, bench/results/h200/count-behind-1024). No shading, no capture.
@fragment
@early_depth_test(force)
fn hw_fs_count(in: HwOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    if (!hw_culled(in, front)) {
        atomicAdd(&opaque_rgb[opaque_counter(2u)], 1u);
        _ = oit_held_back(in.position.xy, in.position.z);
    }
    return vec4<f32>(0.0);
}

// The draw that fills the pass's depth attachment: one triangle over the whole target, whose
// fragment writes the pixel's opaque depth, the high word of its key (`depth bits << 32 |
// primitive id`: the bits of the depth the opaque pass kept, so the fixed-function test and
// `opaque_cut` compare the same numbers), or 1.0 where no opaque fragment fell. Drawn with the
// test ALWAYS, writing depth and no colour.
@vertex
fn depth_vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // (-1, -1), (3, -1), (-1, 3): every pixel of the viewport, whichever way it is turned
    let x = f32(i32(i & 1u) * 4 - 1);
    let y = f32(i32(i >> 1u) * 4 - 1);
    return vec4<f32>(x, y, 0.5, 1.0);
}

@fragment
fn depth_fs(@builtin(position) position: vec4<f32>) -> @builtin(frag_depth) f32 {
    let xy = vec2<u32>(max(floor(position.xy), vec2<f32>(0.0)));
    if (xy.x >= fu.width || xy.y >= fu.height) {
        return 1.0;
    }
    // one sample a pixel: a pixel's one key
    let key = atomicLoad(&opaque_keys[xy.y * fu.width + xy.x]);
    if (key == OPAQUE_NONE) {
        return 1.0;
    }
    return bitcast<f32>(u32(key >> 32u));
}
