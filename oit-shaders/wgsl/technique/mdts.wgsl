// module mdts (raster): technique/mdts_words.wgsl technique/mdts_keys.wgsl technique/mdts.wgsl technique/tail.wgsl
// module mdts_image (raster): core/atomic_result.wgsl technique/mdts_words_image.wgsl technique/mdts_keys.wgsl technique/mdts.wgsl technique/tail.wgsl
// module mdts64_image (raster): core/atomic_result.wgsl technique/mdts_words.wgsl technique/mdts_keys_image.wgsl technique/mdts.wgsl technique/tail.wgsl
// mdts:K and mdts64:K (Liu et al. 2009; Huang et al. 2011, section 3), as oit-cpu's
// `technique/mdts.rs`: K words per pixel start at all ones; each fragment is inserted by repeated
// atomicMin carrying the larger value on to the next word, so each array stays sorted whatever the
// arrival order and ends as the K smallest values inserted.
//
// param = K. pass_index = mode | alpha8 << 8, the mode MDTS_32 (two u32 arrays of mdts_pack's
// 20 + 12-bit words, high then low colour halves; alpha is not stored, the resolve uses alpha8,
// the scene's alpha as oit-cpu computes it) or MDTS_64 (one u64 array of depth bits << 32 |
// payload, exact). The mode's unused arrays are bound to small placeholders.
//
// `--overflow tail` (tail.wgsl, appended): with MDTS_WITH_TAIL set the capture raises
// tail_words[0] when it carries a word off a full array, and the resolve puts the pixel's tail
// behind its K; the pass MDTS_TAIL_PASS adds every fragment whose word is larger than the pixel's
// K-th into the tail (one equal to it that was carried off stays lost).
//
// The words are reached only through mdts_words.wgsl's (32-bit: mdts_min_high, mdts_min_low,
// mdts_load_high, mdts_load_low) and mdts_keys.wgsl's (64-bit: mdts_min64, mdts_load64)
// functions of (pixel, slot), over storage buffers; oit-vulkan's `--atomic-storage image` puts
// its own definitions over storage images in their place (oit-vulkan/src/shaders/).

const MDTS_EMPTY32: u32 = 0xffffffffu;
const MDTS_EMPTY64: u64 = 0xfffffffffffffffflu;
const MDTS_32: u32 = 0u;
const MDTS_64: u32 = 1u;
const MDTS_WITH_TAIL: u32 = 0x10000u;
const MDTS_TAIL_PASS: u32 = 0x20000u;

// insert_min32 into pixel px's K high words; true when a word fell off the end
fn mdts_insert_high(px: u32, key: u32) -> bool {
    var carry = key;
    for (var i = 0u; i < fu.param; i++) {
        let old = mdts_min_high(px, i, carry);
        if (old == MDTS_EMPTY32) {
            return false;
        }
        carry = max(carry, old);
    }
    return true;
}

fn mdts_insert_low(px: u32, key: u32) -> bool {
    var carry = key;
    for (var i = 0u; i < fu.param; i++) {
        let old = mdts_min_low(px, i, carry);
        if (old == MDTS_EMPTY32) {
            return false;
        }
        carry = max(carry, old);
    }
    return true;
}

fn mdts_insert64(px: u32, key: u64) -> bool {
    var carry = key;
    for (var i = 0u; i < fu.param; i++) {
        let old = mdts_min64(px, i, carry);
        if (old == MDTS_EMPTY64) {
            return false;
        }
        carry = max(carry, old);
    }
    return true;
}

// A word carried off a full array: one fragment lost (merged later where there is a tail).
fn mdts_lose(px: u32) {
    lose(px);
    // read before written: one word every overflowing fragment of the frame would hit
    if ((fu.pass_index & MDTS_WITH_TAIL) != 0u && atomicLoad(&tail_words[0]) == 0u) {
        atomicStore(&tail_words[0], 1u);
    }
}

fn capture(f: Fragment) {
    let last = fu.param - 1u;
    if ((fu.pass_index & 0xffu) == MDTS_64) {
        let key = (u64(depth_bits(f.depth)) << 32u) | u64(payload(f, fu.effect));
        if ((fu.pass_index & MDTS_TAIL_PASS) != 0u) {
            if (key > mdts_load64(f.pixel, last)) {
                tail_add(f.pixel, pack_rgba8(f.color));
            }
        } else if (mdts_insert64(f.pixel, key)) {
            // a key carried off the end of the full array
            mdts_lose(f.pixel);
        }
        return;
    }
    // All ones is the empty word: a fragment at d ≈ 1 with that colour gives up its last bit.
    let w = min(mdts_pack(f.depth, pack_rgba8(f.color)), vec2<u32>(MDTS_EMPTY32 - 1u));
    if ((fu.pass_index & MDTS_TAIL_PASS) != 0u) {
        if (w.x > mdts_load_high(f.pixel, last)) {
            // the fragment's 8-bit RGB with the plan's alpha, as the kept words get
            tail_add(f.pixel, (pack_rgba8(f.color) & 0xffffffu) | (((fu.pass_index >> 8u) & 0xffu) << 24u));
        }
        return;
    }
    // both arrays hold the same number of words: one carried off the high array is one lost
    if (mdts_insert_high(f.pixel, w.x)) {
        mdts_lose(f.pixel);
    }
    _ = mdts_insert_low(f.pixel, w.y);
}

@compute @workgroup_size(64)
fn resolve_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    var s = load_state(px);
    let mode = fu.pass_index & 0xffu;
    if (mode == MDTS_64) {
        for (var i = 0u; i < fu.param; i++) {
            let key = mdts_load64(px, i);
            if (key == MDTS_EMPTY64) {
                break;
            }
            push_local(&s, bitcast<f32>(u32(key >> 32u)), u32(key & 0xfffffffflu));
        }
        if ((fu.pass_index & MDTS_WITH_TAIL) != 0u) {
            tail_resolve(&s, px);
        }
        store_state(px, s);
        return;
    }
    let alpha8 = (fu.pass_index >> 8u) & 0xffu;
    for (var i = 0u; i < fu.param; i++) {
        let h = mdts_load_high(px, i);
        let l = mdts_load_low(px, i);
        if (h == MDTS_EMPTY32 || l == MDTS_EMPTY32) {
            break;
        }
        let u = mdts_unpack(vec2<u32>(h, l));
        push_local(&s, bitcast<f32>(u.x), u.y | (alpha8 << 24u));
    }
    if ((fu.pass_index & MDTS_WITH_TAIL) != 0u) {
        tail_resolve(&s, px);
    }
    store_state(px, s);
}
