// kbuf (oit-vulkan): its hardware twin's fragment stage runs in an ordered interlock (the build script's rewrite); the compute twin is only its resolve (the compute path refuses kbuf)
// module kbuf (raster): vulkan/kbuf.wgsl technique/coverage.wgsl
// kbuf:K, the ordered k-buffer (oit-vulkan only). The k-buffer (Bavoil et al. 2007) keeps K
// fragments a pixel sorted by a read-modify-write in the fragment shader; without ordering, two
// fragments of one pixel in flight at once read the same array and one write is lost (the
// read-modify-write hazards the HPG 2009 bucket paper measured it by). Here the whole fragment
// stage of the hardware raster (`hw_fs`) runs inside VK_EXT_fragment_shader_interlock's ordered
// per-pixel critical section, which build.rs adds to the SPIR-V (`interlock`; WGSL cannot say
// it): the fragments of a pixel update its array one at a time, in primitive order.
//
// K slots a pixel (param = K), slot-major as fabs's (slot i of pixel px at i · pixels + px): a
// 64-bit key, depth bits << 32 | primitive id, all ones when empty, and a 32-bit payload beside
// it. A fragment is carried in from the front: each slot keeps the smaller of its key and the
// carried one, the larger carried on; a key carried off the end of a full array is one fragment
// lost (counted). So the slots hold the pixel's K smallest keys in order, whatever the arrival
// order: the same K nearest fragments as fabs:K keeps, sorted by (depth, primitive id) as the
// reference sorts them, and the resolve walks them without sorting.
//
// Multisampled (`fu.msaa.x` samples above 1; docs/msaa.md): each slot's coverage mask, a byte
// (coverage.wgsl, appended), slot-major as the slots, carried with its key, so the slots keep
// fabs:K's K nearest fragments with their masks; the resolve composites them per sample. The
// multisampled capture `hw_fs_masked` runs inside the same interlock (build.rs wraps both entry
// points). A placeholder at one sample.
//
// The words are read and written by atomic loads and stores: plain in effect (no other invocation
// touches the pixel inside the section) but coherent at device scope, so the pixel's next
// fragment sees what the last one wrote.
@group(0) @binding(2) var<storage, read_write> kbuf_slots: array<atomic<u64>>;
@group(0) @binding(3) var<storage, read_write> kbuf_payloads: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read_write> masks: array<atomic<u32>>;

const KBUF_EMPTY: u64 = 0xfffffffffffffffflu;

fn capture(f: Fragment) {
    let stride = fu.pixel_count;
    var key = (u64(depth_bits(f.depth)) << 32u) | u64(f.prim);
    var pay = payload(f, fu.effect);
    let masked = fu.msaa.x > 1u;
    var mask = kept_mask(f);
    for (var i = 0u; i < fu.param; i++) {
        let at = i * stride + f.pixel;
        let old = atomicLoad(&kbuf_slots[at]);
        if (old == KBUF_EMPTY) {
            atomicStore(&kbuf_slots[at], key);
            atomicStore(&kbuf_payloads[at], pay);
            if (masked) {
                mask_put(at, mask);
            }
            return;
        }
        if (key < old) {
            let old_pay = atomicLoad(&kbuf_payloads[at]);
            atomicStore(&kbuf_slots[at], key);
            atomicStore(&kbuf_payloads[at], pay);
            key = old;
            pay = old_pay;
            if (masked) {
                let old_mask = mask_at(at);
                mask_put(at, mask);
                mask = old_mask;
            }
        }
    }
    // the largest of K + 1 keys carried off the full array
    lose(f.pixel);
}

@compute @workgroup_size(64)
fn resolve_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    if (fu.msaa.x > 1u) {
        // the slots are sorted: the per-sample resolve over the n filled
        var n = 0u;
        while (n < fu.param && atomicLoad(&kbuf_slots[n * fu.pixel_count + px]) != KBUF_EMPTY) {
            n++;
        }
        resolve_masked(px, px, n);
        return;
    }
    var s = load_state(px);
    for (var i = 0u; i < fu.param; i++) {
        let at = i * fu.pixel_count + px;
        let key = atomicLoad(&kbuf_slots[at]);
        if (key == KBUF_EMPTY) {
            break;
        }
        push_local(&s, bitcast<f32>(u32(key >> 32u)), atomicLoad(&kbuf_payloads[at]));
    }
    store_state(px, s);
}

// coverage.wgsl's view of the slots: slot i of pixel px at i · pixels + px
fn entry_key(e: u32) -> u64 {
    return atomicLoad(&kbuf_slots[e]);
}

fn entry_payload(e: u32) -> u32 {
    return atomicLoad(&kbuf_payloads[e]);
}

fn entry_next(e: u32) -> u32 {
    return e + fu.pixel_count;
}
