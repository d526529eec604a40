// Group 0 of every technique module: the frame uniform and the per-pixel resolve state, then the
// technique's own buffers from binding 2 on.
@group(0) @binding(0) var<uniform> fu: FrameUniform;
@group(0) @binding(1) var<storage, read_write> state: array<PixelState>;

// Loss accounting, 3 words a pixel (oit-wgpu's `GpuCtx::acct`): [lost, seen, taken]. `lost`
// counts fragments where each is lost; `seen` the fragments of a peel pass at the depths the pass
// before peeled (the peeled ones and the ties the strict comparison skips), or left behind in the
// last pass the plan allows; `taken` how many the pass before captured at those depths.
@group(0) @binding(15) var<storage, read_write> acct: array<atomic<u32>>;

// The opaque pass's image (oit-gpu's `OPAQUE_KEYS_BINDING`, `OPAQUE_RGB_BINDING`; opaque.wgsl
// draws it): per pixel the nearest opaque `depth bits << 32 | primitive id` (all ones where none
// fell) and that fragment's linear RGB (3 words, f32 bits); after the colours, two counters:
// [masked, occluded].
@group(0) @binding(16) var<storage, read_write> opaque_keys: array<atomic<u64>>;
@group(0) @binding(17) var<storage, read_write> opaque_rgb: array<atomic<u32>>;

const OPAQUE_NONE: u64 = 0xfffffffffffffffflu;

// Whether the opaque pass holds `f` back (oit-cpu's `Rasterizer::cut_at`): where the frame has an
// opaque part, a transparent fragment goes on only strictly in front of its pixel's opaque depth.
// The frame's first scene pass counts those it holds back.
fn opaque_cut(f: Fragment) -> bool {
    if (fu.opaque.x == 0u) {
        return false;
    }
    let nearest = u32(atomicLoad(&opaque_keys[f.pixel]) >> 32u);
    if (depth_bits(f.depth) < nearest) {
        return false;
    }
    if (fu.opaque.y != 0u) {
        atomicAdd(&opaque_rgb[3u * fu.pixel_count + 1u], 1u);
    }
    return true;
}

// What pixel `px` composites over: its opaque colour where an opaque fragment fell, else the
// background (oit-cpu's `Resolve::background_at`).
fn background_at(px: u32) -> vec3<f32> {
    if (fu.opaque.z != 0u) {
        if (atomicLoad(&opaque_keys[px]) != OPAQUE_NONE) {
            let r = bitcast<f32>(atomicLoad(&opaque_rgb[3u * px]));
            let g = bitcast<f32>(atomicLoad(&opaque_rgb[3u * px + 1u]));
            let b = bitcast<f32>(atomicLoad(&opaque_rgb[3u * px + 2u]));
            return vec3<f32>(r, g, b);
        }
    }
    return fu.background.xyz;
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
