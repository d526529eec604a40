// dp and ddp per sample (several samples): (depth, primitive id) peels into per-sample accumulators
// module dp_samples (raster): technique/peel_samples.wgsl technique/dp_samples.wgsl
// dp per sample (several samples; oit-cpu's `dp::render_samples`, docs/msaa.md): each geometry
// pass keeps, per pixel, the smallest (depth bits, primitive id, lowest sample: `peel_key`) key strictly behind the layer
// the pass before peeled (u64 atomicMin), so every fragment is one layer, ties in the reference's
// order; the one fragment whose key is the layer peeled writes its payload and coverage mask,
// which the resolve composites into the covered samples' accumulators (peel_samples.wgsl). The
// pass that peels nothing fetches the last layer; in the last pass the plan allows (one past the
// peel limit) nothing is peeled and what lies behind is lost.
@group(0) @binding(2) var<storage, read_write> nearest: array<atomic<u64>>;
// key + 1 of the layer the last pass peeled; 0 none yet, DPS_DONE nothing left
@group(0) @binding(3) var<storage, read_write> previous: array<u64>;
// the peeled layer's payload and mask, two words a pixel
@group(0) @binding(4) var<storage, read_write> layer: array<u32>;
// [pixels that peeled a layer this pass]
@group(0) @binding(6) var<storage, read_write> peeled: array<atomic<u32>>;

const DPS_EMPTY: u64 = 0xfffffffffffffffflu;
const DPS_DONE: u64 = 0xfffffffffffffffflu;

fn capture(f: Fragment) {
    let k = peel_key(f) + 1lu;
    let prev = previous[f.pixel];
    if (k > prev) {
        if (last_pass()) {
            // behind the last layer the limit allows
            lose(f.pixel);
        } else {
            atomicMin(&nearest[f.pixel], k - 1lu);
        }
    } else if (k == prev) {
        layer[2u * f.pixel] = payload(f, fu.effect);
        layer[2u * f.pixel + 1u] = f.mask;
    }
}

@compute @workgroup_size(64)
fn resolve_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    let prev = previous[px];
    if (prev == DPS_DONE) {
        return;
    }
    if (prev == 0lu) {
        accumulators_init(px, 1u);
    } else {
        accumulate(px, 1u, layer[2u * px], layer[2u * px + 1u], 0u);
    }
    let key = atomicExchange(&nearest[px], DPS_EMPTY);
    if (key == DPS_EMPTY) {
        previous[px] = DPS_DONE;
        accumulated(px, 1u);
        return;
    }
    previous[px] = key + 1lu;
    atomicAdd(&peeled[0], 1u);
}
