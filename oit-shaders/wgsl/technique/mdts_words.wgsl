// mdts:K's two arrays of 32-bit words in storage buffers (mdts.wgsl's accessors): word `slot` of
// pixel `px` is element slot · pixels + px, slot-major as fabs's slots, so the neighbouring pixels
// of a workgroup touch neighbouring words. oit-vulkan's `shaders/mdts_words_image.wgsl` defines
// the same functions over storage images.
@group(0) @binding(2) var<storage, read_write> mdts_high: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read_write> mdts_low: array<atomic<u32>>;

// atomicMin of word `slot` of pixel `px` with `v`: the word before
fn mdts_min_high(px: u32, slot: u32, v: u32) -> u32 {
    return atomicMin(&mdts_high[slot * fu.pixel_count + px], v);
}

fn mdts_min_low(px: u32, slot: u32, v: u32) -> u32 {
    return atomicMin(&mdts_low[slot * fu.pixel_count + px], v);
}

fn mdts_load_high(px: u32, slot: u32) -> u32 {
    return atomicLoad(&mdts_high[slot * fu.pixel_count + px]);
}

fn mdts_load_low(px: u32, slot: u32) -> u32 {
    return atomicLoad(&mdts_low[slot * fu.pixel_count + px]);
}
