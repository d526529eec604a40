// Group 0 of every technique module: the frame uniform and the per-pixel resolve state, then the
// technique's own buffers from binding 2 on.
@group(0) @binding(0) var<uniform> fu: FrameUniform;
// (resolve.wgsl's `PixelState` a pixel, a plane a field: `load_state`, `store_state`)
@group(0) @binding(1) var<storage, read_write> state: array<u32>;

// Loss accounting, 3 words a pixel (oit-wgpu's `GpuCtx::acct`): [lost, seen, taken]. `lost`
// counts fragments where each is lost; `seen` the fragments of a peel pass at the depths the pass
// before peeled (the peeled ones and the ties the strict comparison skips), or left behind in the
// last pass the plan allows; `taken` how many the pass before captured at those depths.
@group(0) @binding(15) var<storage, read_write> acct: array<atomic<u32>>;

// The opaque pass's image (oit-gpu's `OPAQUE_KEYS_BINDING`, `OPAQUE_RGB_BINDING`; opaque.wgsl
// draws it), kept a sample (`fu.msaa.x` a pixel, sample i of pixel px at px · samples + i; one a
// pixel at one sample): per sample the nearest opaque `depth bits << 32 | primitive id` covering
// it (all ones where none did) and that fragment's linear RGB (3 words, f32 bits); after the
// colours, two counters: [masked, occluded] (`opaque_counter`).
@group(0) @binding(16) var<storage, read_write> opaque_keys: array<atomic<u64>>;
@group(0) @binding(17) var<storage, read_write> opaque_rgb: array<atomic<u32>>;

const OPAQUE_NONE: u64 = 0xfffffffffffffffflu;

// Samples a pixel of the opaque image.
fn opaque_samples() -> u32 {
    return max(fu.msaa.x, 1u);
}

// The word of opaque_rgb's counter i (0 masked, 1 occluded, 2 the fragments the hardware path's
// count-only draw counted: raster_hardware_early.wgsl), after every sample's colour.
fn opaque_counter(i: u32) -> u32 {
    return 3u * fu.pixel_count * opaque_samples() + i;
}

// The word of opaque_rgb holding compute-raster tile t's farthest opaque depth bits, complemented
// (0: unknown, nothing skipped), after the counters (oit-gpu's `opaque_tiles`).
fn opaque_tile_word(t: u32) -> u32 {
    return opaque_counter(3u) + t;
}

// The samples of `f.mask` the opaque pass leaves to `f` (oit-cpu's cut in
// `Rasterizer::for_each_masked_fragment`): where the frame has an opaque part, those where `f`
// (its one depth, the pixel centre's) lies strictly in front of that sample's opaque depth.
// `f.mask` is 1 at one sample. Counts nothing (`opaque_kept` counts).
fn opaque_front(f: Fragment) -> u32 {
    if (fu.opaque.x == 0u) {
        return f.mask;
    }
    let n = opaque_samples();
    let d = depth_bits(f.depth);
    var kept = 0u;
    for (var i = 0u; i < n; i++) {
        if (((f.mask >> i) & 1u) != 0u && d < u32(atomicLoad(&opaque_keys[f.pixel * n + i]) >> 32u)) {
            kept |= 1u << i;
        }
    }
    return kept;
}

// `opaque_front`, a fragment left with no sample held back and counted by the frame's first
// scene pass.
fn opaque_kept(f: Fragment) -> u32 {
    let kept = opaque_front(f);
    if (kept == 0u && fu.opaque.y != 0u) {
        atomicAdd(&opaque_rgb[opaque_counter(1u)], 1u);
    }
    return kept;
}

// Whether the opaque pass holds `f` back at every sample of its pixel (`f.mask` not read): the
// cut of the captures that carry no mask (one sample).
fn opaque_cut(f: Fragment) -> bool {
    var g = f;
    g.mask = (1u << opaque_samples()) - 1u;
    return opaque_kept(g) == 0u;
}

// What sample i of pixel `px` composites over: its opaque colour where an opaque fragment covers
// it, else the background (oit-cpu's `Resolve::background_at_sample`).
fn background_at_sample(px: u32, i: u32) -> vec3<f32> {
    if (fu.opaque.z != 0u) {
        let s = px * opaque_samples() + i;
        if (atomicLoad(&opaque_keys[s]) != OPAQUE_NONE) {
            let r = bitcast<f32>(atomicLoad(&opaque_rgb[3u * s]));
            let g = bitcast<f32>(atomicLoad(&opaque_rgb[3u * s + 1u]));
            let b = bitcast<f32>(atomicLoad(&opaque_rgb[3u * s + 2u]));
            return vec3<f32>(r, g, b);
        }
    }
    return fu.background.xyz;
}

// Whether every sample of pixel `px` holds the same opaque key (one fragment, or none): a
// per-sample resolve may then composite the pixel once (oit-cpu's `Resolve::opaque_uniform`).
fn opaque_uniform(px: u32) -> bool {
    let n = opaque_samples();
    if (fu.opaque.z == 0u || n == 1u) {
        return true;
    }
    let first = atomicLoad(&opaque_keys[px * n]);
    for (var i = 1u; i < n; i++) {
        if (atomicLoad(&opaque_keys[px * n + i]) != first) {
            return false;
        }
    }
    return true;
}

// What pixel `px` composites over: its opaque colour where an opaque fragment fell, else the
// background (oit-cpu's `Resolve::background_at`); above one sample, with nothing captured, the
// mean of its samples' (`Resolve::background_mean`: summed in order, times 1/N).
fn background_at(px: u32) -> vec3<f32> {
    if (opaque_uniform(px)) {
        return background_at_sample(px, 0u);
    }
    let n = opaque_samples();
    var sum = vec3<f32>(0.0);
    for (var i = 0u; i < n; i++) {
        sum += background_at_sample(px, i);
    }
    return sum * (1.0 / f32(n));
}

fn lose(px: u32) {
    atomicAdd(&acct[3u * px], 1u);
}

fn seen(px: u32) {
    atomicAdd(&acct[3u * px + 1u], 1u);
}

// After a peel pass: what was seen beyond the `taken` fragments captured is lost. A mismatch
// (seen < taken) is left uncounted, so `captured + lost == fragments` catches it.
fn settle(px: u32, taken: u32) {
    let s = atomicExchange(&acct[3u * px + 1u], 0u);
    if (s > taken) {
        atomicAdd(&acct[3u * px], s - taken);
    }
}

fn last_pass() -> bool {
    return fu.last_pass == 1u;
}

// The pixel a pixel kernel invocation owns (dispatched in 2D when there are many).
fn kernel_pixel(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * groups.x * 64u;
}
