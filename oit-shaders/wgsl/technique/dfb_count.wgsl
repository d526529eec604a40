// module dfb_count (raster): technique/dfb_count.wgsl
// dfb's counting pass: fragments per pixel (dfb.rs scans them into offsets).
@group(0) @binding(2) var<storage, read_write> counts: array<atomic<u32>>;

fn capture(f: Fragment) {
    atomicAdd(&counts[f.pixel], 1u);
}
