// fabs:K's per-pixel counters in a storage buffer (fabs.wgsl's accessors). oit-vulkan's
// `shaders/fabs_counters_image.wgsl` defines the same functions over a storage image.
@group(0) @binding(2) var<storage, read_write> counters: array<atomic<u32>>;

// atomicAdd of pixel px's counter: the count before
fn fabs_count_add(px: u32, v: u32) -> u32 {
    return atomicAdd(&counters[px], v);
}

fn fabs_count(px: u32) -> u32 {
    return atomicLoad(&counters[px]);
}
