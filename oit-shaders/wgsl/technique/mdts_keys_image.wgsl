// mdts64:K's 64-bit keys as an R64_UINT storage image (`--atomic-storage image`, on devices with
// VK_EXT_shader_image_atomic_int64): key `slot` of pixel px is layer `slot` of its texel. The
// same functions as oit-wgpu's technique/mdts_keys.wgsl; a load is an atomicMin with all ones.
@group(0) @binding(8) var mdts_keys_image: texture_storage_2d_array<r64uint, atomic>;

fn mdts_min64(px: u32, slot: u32, v: u64) -> u64 {
    textureAtomicMin(mdts_keys_image, vk_texel(px), slot, v);
    return vk_atomic_result64();
}

fn mdts_load64(px: u32, slot: u32) -> u64 {
    return mdts_min64(px, slot, 0xfffffffffffffffflu);
}
