// module ll_size (raster): technique/ll_size.wgsl
// ll's sizing pass: stores nothing. The geometry pass counts the fragments it generates (the
// compute rasterizer's `generated`, the hardware path's count target), which is the node pool's
// size.
fn capture(f: Fragment) {}
