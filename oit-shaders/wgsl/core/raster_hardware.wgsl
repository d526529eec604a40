// The hardware-raster path: the GPU's own rasterizer. The meshes' vertices are uploaded once in
// their own space; the vertex stage transforms them with the frame's per-instance matrices (the
// same `view_proj · transform` and normal matrix as oit-cpu, applied in the same order of
// operations as glam's). Vertices are pulled from storage by vertex index so each triangle's
// three vertices carry its primitive id (triangle t of the draw is primitive t: the triangles are
// laid out in primitive order). No culling in the pipeline, no depth test: a single-sided object's
// back faces are dropped by every fragment entry point first, by `front_facing` (`hw_culled`),
// before anything is counted; the fragment shades like oit-cpu's `Shading::shade`, its texture
// sampled first (`hw_color`), where the opaque pass does not hold it back (`oit_held_back`), and
// is captured (`oit_capture_shaded`, capture_render.wgsl).

struct HwVertex {
    // xyz: position in the mesh's space; w: 1 when the mesh has vertex colours
    position: vec4<f32>,
    // w: the texture coordinate u (0 without)
    normal: vec4<f32>,
    // w: the texture coordinate v
    color: vec4<f32>,
}

struct HwInstance {
    // object to clip space: view_proj · transform
    mvp: mat4x4<f32>,
    // the normal matrix's columns (normal0.w: the opaque pass's cutoff, `Fragment::cutoff`;
    // normal1.w: which faces are dropped, oit-core's `back_face_sign`: 0 none, 1 those not
    // front-facing, −1 those front-facing; normal2.w unused)
    normal0: vec4<f32>,
    normal1: vec4<f32>,
    normal2: vec4<f32>,
    base: vec4<f32>,
}

struct HwUniform {
    shading: u32,
    // 1 where the frame has textures: `hw_tex` holds them, and from word `tex_levels` on each
    // triangle's level descriptor (0: untextured)
    textured: u32,
    tex_levels: u32,
    pad2: u32,
    forward: vec4<f32>,
}

@group(1) @binding(0) var<storage, read> hw_vertices: array<HwVertex>;
// per triangle: its three vertices and its instance
@group(1) @binding(1) var<storage, read> hw_indices: array<vec4<u32>>;
@group(1) @binding(2) var<uniform> hw: HwUniform;
@group(1) @binding(3) var<storage, read> hw_instances: array<HwInstance>;
// the frame's textures (oit-gpu's `hardware_textures`): the texture region (texture.wgsl) from
// word 0, then from `hw.tex_levels` one word a triangle, the word offset of the descriptor of the
// level its fragments sample (chosen on the host as oit-core's setup chooses it); a placeholder
// where the frame has none
@group(1) @binding(4) var<storage, read> hw_tex: array<u32>;

fn tex_word(i: u32) -> u32 {
    return hw_tex[i];
}

struct HwOut {
    @builtin(position) position: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) vcolor: vec3<f32>,
    @location(2) @interpolate(flat) base: vec4<f32>,
    @location(3) @interpolate(flat) prim: u32,
    @location(4) @interpolate(flat) has_color: u32,
    @location(5) uv: vec2<f32>,
    // the level descriptor of the triangle's texture (0: untextured)
    @location(6) @interpolate(flat) tex: u32,
    @location(7) @interpolate(flat) cutoff: f32,
    // the instance's `normal1.w`: which faces `hw_culled` drops
    @location(8) @interpolate(flat) cull: f32,
}

@vertex
fn hw_vs(@builtin(vertex_index) vi: u32) -> HwOut {
    let prim = vi / 3u;
    let tri = hw_indices[prim];
    let v = hw_vertices[tri[vi % 3u]];
    let inst = hw_instances[tri.w];
    let p = v.position;
    let m = inst.mvp;
    let n = v.normal;
    var out: HwOut;
    // glam's Mat4 · Vec4 and Mat3 · Vec3, term by term (w = 1)
    out.position = m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3];
    out.normal = inst.normal0.xyz * n.x + inst.normal1.xyz * n.y + inst.normal2.xyz * n.z;
    out.vcolor = v.color.xyz;
    out.base = inst.base;
    out.prim = prim;
    out.has_color = select(0u, 1u, p.w != 0.0);
    out.uv = vec2<f32>(n.w, v.color.w);
    out.cutoff = inst.normal0.w;
    out.cull = inst.normal1.w;
    out.tex = 0u;
    if (hw.textured != 0u) {
        out.tex = hw_tex[hw.tex_levels + prim];
    }
    return out;
}

// The fragment's shaded colour (oit-core's `TriangleSetup::color_at`): where its triangle is
// textured, the sample at its texture coordinates multiplies the base colour and the vertex
// colour before shading.
fn hw_color(in: HwOut) -> vec4<f32> {
    var base = in.base;
    var vcolor = in.vcolor;
    if (in.tex != 0u) {
        let s = tex_sample(0u, in.tex, in.uv);
        base = base * s;
        vcolor = vcolor * s.xyz;
    }
    return shade(hw.shading, base, in.normal, vcolor, in.has_color != 0u, hw.forward.xyz);
}

// Whether the fragment is a single-sided object's back face, dropped before anything reads it
// (every fragment entry point taking `HwOut` discards it first). The pipelines' front face is
// counter-clockwise, as glTF's; the instance's sign turns it over where its transform mirrors.
fn hw_culled(in: HwOut, front: bool) -> bool {
    return (in.cull > 0.0 && !front) || (in.cull < 0.0 && front);
}

@fragment
fn hw_fs(in: HwOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    // a back face is dropped without `discard`, which kbuf's interlocked body may not hold
    // (oit-vulkan's build.rs): it captures nothing and adds 0 to the count target (additive);
    // this entry point writes no depth
    var counted = vec4<f32>(0.0);
    if (!hw_culled(in, front)) {
        // behind the opaque pass's depth: counted, neither shaded nor captured
        counted = vec4<f32>(1.0, 0.0, 0.0, 0.0);
        if (!oit_held_back(in.position.xy, in.position.z)) {
            counted = oit_capture_shaded(in.position.xy, in.position.z, hw_color(in), in.normal, in.prim, in.cutoff, 1u);
        }
    }
    return counted;
}
