// Group 0 of every technique module: the frame uniform and the per-pixel resolve state, then the
// technique's own buffers from binding 2 on.
@group(0) @binding(0) var<uniform> fu: FrameUniform;
@group(0) @binding(1) var<storage, read_write> state: array<PixelState>;

// The pixel a pixel kernel invocation owns (dispatched in 2D when there are many).
fn kernel_pixel(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * groups.x * 64u;
}
