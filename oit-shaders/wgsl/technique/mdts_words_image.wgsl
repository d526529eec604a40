// mdts:K's two arrays of 32-bit words as R32_UINT storage images (`--atomic-storage image`),
// the paper's capture (Liu et al. 2009 ran it on image atomics): word `slot` of pixel px is
// layer `slot` of its texel. The same functions as oit-wgpu's technique/mdts_words.wgsl; a load
// is an atomicMin with all ones (it changes nothing and returns the word).
@group(0) @binding(8) var mdts_high_image: texture_storage_2d_array<r32uint, atomic>;
@group(0) @binding(9) var mdts_low_image: texture_storage_2d_array<r32uint, atomic>;

fn mdts_min_high(px: u32, slot: u32, v: u32) -> u32 {
    textureAtomicMin(mdts_high_image, vk_texel(px), slot, v);
    return vk_atomic_result();
}

fn mdts_min_low(px: u32, slot: u32, v: u32) -> u32 {
    textureAtomicMin(mdts_low_image, vk_texel(px), slot, v);
    return vk_atomic_result();
}

fn mdts_load_high(px: u32, slot: u32) -> u32 {
    return mdts_min_high(px, slot, 0xffffffffu);
}

fn mdts_load_low(px: u32, slot: u32) -> u32 {
    return mdts_min_low(px, slot, 0xffffffffu);
}
