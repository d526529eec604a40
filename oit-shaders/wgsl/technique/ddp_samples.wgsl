// module ddp_samples (raster): technique/peel_samples.wgsl technique/ddp_samples.wgsl
// ddp per sample (several samples; oit-cpu's `ddp::render_samples`, docs/msaa.md): each geometry
// pass keeps, per pixel, the smallest and the largest (depth bits, primitive id, lowest sample: `peel_key`) key strictly
// inside the open range the pass before left (u64 atomicMin / atomicMax), so every fragment is
// one layer, ties in the reference's order; the fragments whose keys are the layers peeled write
// their payloads and coverage masks, which the resolve composites into the covered samples' front
// and back accumulators (peel_samples.wgsl). The pass that peels nothing fetches the last ones;
// in the last pass the plan allows (one past the peel limit) nothing is peeled and what lies
// between is lost.
@group(0) @binding(2) var<storage, read_write> ddps_near: array<atomic<u64>>;
@group(0) @binding(3) var<storage, read_write> ddps_far: array<atomic<u64>>;
// per pixel (lo, hi): key k lies inside where k + 1 > lo and k < hi; the near layer the last pass
// peeled is lo − 1, the far one hi (where it peeled two; one where hi + 1 = lo). Kept as (lo,
// !hi), so zeroed words are the first pass's (0, all ones); done (all ones, all ones).
@group(0) @binding(4) var<storage, read_write> ddps_range: array<u64>;
// the peeled layers' payloads and masks, near then far: four words a pixel
@group(0) @binding(6) var<storage, read_write> layers: array<u32>;
// [pixels that peeled a layer this pass]
@group(0) @binding(7) var<storage, read_write> peeled: array<atomic<u32>>;

const DDPS_EMPTY_MIN: u64 = 0xfffffffffffffffflu;
const DDPS_ALL: u64 = 0xfffffffffffffffflu;

fn capture(f: Fragment) {
    let px = f.pixel;
    let k = peel_key(f);
    let lo = ddps_range[2u * px];
    let hi = ~ddps_range[2u * px + 1u];
    var slot = 0u;
    if (k + 1lu > lo && k < hi) {
        if (last_pass()) {
            // between the last layers the limit allows
            lose(px);
        } else {
            atomicMin(&ddps_near[px], k);
            atomicMax(&ddps_far[px], k);
        }
        return;
    } else if (k + 1lu == lo) {
        slot = 0u;
    } else if (k == hi) {
        slot = 2u;
    } else {
        return;
    }
    layers[4u * px + slot] = payload(f, fu.effect);
    layers[4u * px + slot + 1u] = f.mask;
}

@compute @workgroup_size(64)
fn resolve_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    let lo = ddps_range[2u * px];
    let hi = ~ddps_range[2u * px + 1u];
    if (lo == DDPS_ALL && hi == DDPS_ALL) {
        return;
    }
    if (lo == 0lu && hi == DDPS_ALL) {
        // before the first layer
        accumulators_init(px, 2u);
    } else {
        accumulate(px, 2u, layers[4u * px], layers[4u * px + 1u], 0u);
        if (hi + 1lu != lo) {
            accumulate(px, 2u, layers[4u * px + 2u], layers[4u * px + 3u], 1u);
        }
    }
    let n = atomicExchange(&ddps_near[px], DDPS_EMPTY_MIN);
    let f = atomicExchange(&ddps_far[px], 0lu);
    if (n == DDPS_EMPTY_MIN) {
        ddps_range[2u * px] = DDPS_ALL;
        ddps_range[2u * px + 1u] = ~DDPS_ALL;
        accumulated(px, 2u);
        return;
    }
    ddps_range[2u * px] = n + 1lu;
    ddps_range[2u * px + 1u] = ~f;
    atomicAdd(&peeled[0], 1u);
}
