// mdts64:K's array of 64-bit keys in a storage buffer (mdts.wgsl's accessors): key `slot` of
// pixel `px` is element slot · pixels + px, slot-major as fabs's slots, so the neighbouring pixels
// of a workgroup touch neighbouring keys. oit-vulkan's `shaders/mdts_keys_image.wgsl` defines the
// same functions over a 64-bit storage image.
@group(0) @binding(4) var<storage, read_write> mdts_slots: array<atomic<u64>>;

// atomicMin of key `slot` of pixel `px` with `v`: the key before
fn mdts_min64(px: u32, slot: u32, v: u64) -> u64 {
    return atomicMin(&mdts_slots[slot * fu.pixel_count + px], v);
}

fn mdts_load64(px: u32, slot: u32) -> u64 {
    return atomicLoad(&mdts_slots[slot * fu.pixel_count + px]);
}
