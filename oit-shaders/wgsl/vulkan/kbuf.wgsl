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
// The words are read and written by atomic loads and stores: plain in effect (no other invocation
// touches the pixel inside the section) but coherent at device scope, so the pixel's next
// fragment sees what the last one wrote.
@group(0) @binding(2) var<storage, read_write> kbuf_slots: array<atomic<u64>>;
@group(0) @binding(3) var<storage, read_write> kbuf_payloads: array<atomic<u32>>;

const KBUF_EMPTY: u64 = 0xfffffffffffffffflu;

fn capture(f: Fragment) {
    let stride = fu.pixel_count;
    var key = (u64(depth_bits(f.depth)) << 32u) | u64(f.prim);
    var pay = payload(f, fu.effect);
    for (var i = 0u; i < fu.param; i++) {
        let at = i * stride + f.pixel;
        let old = atomicLoad(&kbuf_slots[at]);
        if (old == KBUF_EMPTY) {
            atomicStore(&kbuf_slots[at], key);
            atomicStore(&kbuf_payloads[at], pay);
            return;
        }
        if (key < old) {
            let old_pay = atomicLoad(&kbuf_payloads[at]);
            atomicStore(&kbuf_slots[at], key);
            atomicStore(&kbuf_payloads[at], pay);
            key = old;
            pay = old_pay;
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
    var s = state[px];
    for (var i = 0u; i < fu.param; i++) {
        let at = i * fu.pixel_count + px;
        let key = atomicLoad(&kbuf_slots[at]);
        if (key == KBUF_EMPTY) {
            break;
        }
        push_local(&s, bitcast<f32>(u32(key >> 32u)), atomicLoad(&kbuf_payloads[at]));
    }
    state[px] = s;
}
