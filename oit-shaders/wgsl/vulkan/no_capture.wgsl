// module nothing (raster): vulkan/no_capture.wgsl
// A capture that keeps nothing: the hardware raster's count-only draw (the fragments of a pass
// whose own capture cannot count them, as oit-wgpu's `count_fragments`).
fn capture(f: Fragment) {}
