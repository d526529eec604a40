// The hardware-raster path: the GPU's own rasterizer. Vertices come transformed to clip space on
// the host (the same `view_proj · transform` as oit-cpu), pulled from storage by vertex index so
// each triangle's three vertices carry its primitive id (triangle t of the draw is primitive t:
// the triangles are laid out in primitive order). No culling, no depth test; the fragment shades
// like oit-cpu's `Shading::shade` and calls `oit_capture_full` (capture_render.wgsl).

struct HwVertex {
    clip: vec4<f32>,
    // xyz: world normal; w: 1 when the mesh has vertex colours
    normal: vec4<f32>,
    color: vec4<f32>,
    base: vec4<f32>,
}

struct HwUniform {
    shading: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
    forward: vec4<f32>,
}

@group(1) @binding(0) var<storage, read> hw_vertices: array<HwVertex>;
@group(1) @binding(1) var<storage, read> hw_indices: array<u32>;
@group(1) @binding(2) var<uniform> hw: HwUniform;

struct HwOut {
    @builtin(position) position: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) vcolor: vec3<f32>,
    @location(2) @interpolate(flat) base: vec4<f32>,
    @location(3) @interpolate(flat) prim: u32,
    @location(4) @interpolate(flat) has_color: u32,
}

@vertex
fn hw_vs(@builtin(vertex_index) vi: u32) -> HwOut {
    let v = hw_vertices[hw_indices[vi]];
    var out: HwOut;
    out.position = v.clip;
    out.normal = v.normal.xyz;
    out.vcolor = v.color.xyz;
    out.base = v.base;
    out.prim = vi / 3u;
    out.has_color = select(0u, 1u, v.normal.w != 0.0);
    return out;
}

@fragment
fn hw_fs(in: HwOut) -> @location(0) vec4<f32> {
    let color = shade(hw.shading, in.base, in.normal, in.vcolor, in.has_color != 0u, hw.forward.xyz);
    return oit_capture_full(in.position.xy, in.position.z, color, in.normal, in.prim);
}
