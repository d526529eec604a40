// `--atomic-storage image` (oit-vulkan only): what an image atomic returned, and a pixel's texel.
//
// WGSL's textureAtomic* are statements that return nothing, while GLSL's imageAtomic* (and the
// SPIR-V OpAtomic* naga emits for them) return the texel's value before the operation, which
// every capture here needs (mdts carries it on; fabs's counter is the slot index). So
// `textureAtomicMin(t, c, l, v); let old = vk_atomic_result();` is written, and build.rs
// (`atomic_results`) rewrites each call of these two functions into a copy of the result of the
// image atomic just before it in the same block: GLSL's `old = imageAtomicMin(t, ivec3(c, l), v)`.
// A call with no image atomic before it in its block fails the build.
fn vk_atomic_result() -> u32 {
    return 0u;
}

fn vk_atomic_result64() -> u64 {
    return 0lu;
}

// Pixel px of the frame (row-major, fu.width a row) as image coordinates.
fn vk_texel(px: u32) -> vec2<u32> {
    return vec2<u32>(px % fu.width, px / fu.width);
}
