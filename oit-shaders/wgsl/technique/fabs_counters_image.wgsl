// fabs:K's per-pixel counters as an R32_UINT storage image of one layer (`--atomic-storage
// image`): the counter by imageAtomicAdd, as Huang et al. 2011's OpenGL port of the CUDA
// rasterizer's atomicInc. The same functions as oit-wgpu's technique/fabs_counters.wgsl; a load
// is an add of 0.
@group(0) @binding(9) var fabs_counter_image: texture_storage_2d_array<r32uint, atomic>;

fn fabs_count_add(px: u32, v: u32) -> u32 {
    textureAtomicAdd(fabs_counter_image, vk_texel(px), 0u, v);
    return vk_atomic_result();
}

fn fabs_count(px: u32) -> u32 {
    return fabs_count_add(px, 0u);
}
