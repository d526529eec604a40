// Group 0 of every technique module: the frame uniform and the per-pixel resolve state, then the
// technique's own buffers from binding 2 on.
@group(0) @binding(0) var<uniform> fu: FrameUniform;
@group(0) @binding(1) var<storage, read_write> state: array<PixelState>;

// Loss accounting, 3 words a pixel (oit-wgpu's `GpuCtx::acct`): [lost, seen, taken]. `lost`
// counts fragments where each is lost; `seen` the fragments of a peel pass at the depths the pass
// before peeled (the peeled ones and the ties the strict comparison skips), or left behind in the
// last pass the plan allows; `taken` how many the pass before captured at those depths.
@group(0) @binding(15) var<storage, read_write> acct: array<atomic<u32>>;

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
