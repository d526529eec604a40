// The compute-path rasterizer: oit-cpu's fixed-point rules (crates/oit-cpu/src/raster.rs) walked
// on the GPU. Triangles come set up (clipped, snapped) by the same code as oit-cpu's, so the
// covered pixels are the same by construction; this kernel tests coverage with the same integer
// edge functions and interpolates with the same f32 formula, then calls the technique's
// `capture`. Work items are (triangle, 8×8 tile of its box that it may cover: oit-core's
// `Triangle::may_cover`, setup.wgsl's `row_run`): `raster_main` runs one
// workgroup per item and one invocation per pixel (GPUs), `raster_loop_main` one invocation per
// item walking its tile (CPU devices).

struct Tri {
    x: array<i32, 3>,
    y: array<i32, 3>,
    z: array<f32, 3>,
    inv_w: array<f32, 3>,
    n: array<f32, 9>,
    c: array<f32, 9>,
    inv_area: f32,
    base: array<f32, 4>,
    has_color: u32,
    prim: u32,
    bbox: array<u32, 4>,
    // the word offset of the triangle's texture record (0: untextured): oit-gpu's `host_setup`
    tex: u32,
    pad1: u32,
    pad2: u32,
}

struct RasterUniform {
    item_count: u32,
    width: u32,
    height: u32,
    shading: u32,
    forward: vec4<f32>,
}

// TRI_WORDS words a triangle (`TriangleSetup::triangle_words`), then, in a frame with textures
// (set up on the host: oit-gpu's `host_setup`), each textured triangle's record (its vertices'
// texture coordinates, 6 f32; its level's descriptor; its cutoff, f32; the texture region's
// first word) and the texture region (texture.wgsl)
@group(1) @binding(0) var<storage, read> tris: array<u32>;
// (triangle, tile: row << 16 | column), the tile's bit 31 set by the frame's first scene pass on
// an item that captured nothing (`ITEM_SPENT`)
@group(1) @binding(1) var<storage, read_write> items: array<vec2<u32>>;
@group(1) @binding(2) var<uniform> ru: RasterUniform;
@group(1) @binding(3) var<storage, read_write> generated: array<atomic<u32>>;

const TILE: u32 = 8u;
const TRI_WORDS: u32 = 44u;
// A work item's mark, in its tile word's top bit (a tile's row takes at most 11 bits of the 16
// above its column). The frame's first scene pass (`fu.opaque.w`, oit-gpu's `MARKS_WRITE`) writes
// it on every item, set where the item captured no fragment: none of its pixels covered (the tiles
// of a triangle's box that miss the triangle), or every one behind the opaque depth. The frame's
// later passes (`MARKS_READ`) skip the items marked. Coverage and the opaque cut are the same in
// every pass of a frame, so an item with nothing to capture in the first pass has nothing in any
// other: the peels and the second passes of two-pass captures walk only the items with something
// to capture (oit-cpu skips the same fragments by testing them). The setup (or the host's upload)
// writes every item afresh each frame, so a rasterizer whose first pass of the frame was not the
// writing one (the boxes', the opaque pass's) reads no mark.
const ITEM_SPENT: u32 = 0x80000000u;
// `fu.opaque.w`: oit-gpu's `MARKS_WRITE` and `MARKS_READ`
const MARKS_WRITE: u32 = 1u;
const MARKS_READ: u32 = 2u;
// A work item's other mark, the bit below `ITEM_SPENT`: `classify_main` counted its fragments
// before the frame's first scene pass (every one held back by the opaque depth), so that pass
// skips it as the later ones skip a spent item, and marks it spent.
const ITEM_COUNTED: u32 = 0x40000000u;

// Work item `i` (its tile without the marks) and whether this pass skips it (`ITEM_SPENT` in a
// later pass, `ITEM_COUNTED` in any).
fn load_item(i: u32) -> vec3<u32> {
    let raw = items[i];
    let spent = (fu.opaque.w == MARKS_READ && (raw.y & ITEM_SPENT) != 0u) || (raw.y & ITEM_COUNTED) != 0u;
    return vec3<u32>(raw.x, raw.y & ~(ITEM_SPENT | ITEM_COUNTED), u32(spent));
}

// The frame's first scene pass (`MARKS_WRITE`): marks item `i` (`item`, unmarked) spent where it
// captured nothing, and clears a mark an earlier frame left.
fn mark_item(i: u32, item: vec2<u32>, captured: u32) {
    if (fu.opaque.w == MARKS_WRITE) {
        items[i] = vec2<u32>(item.x, item.y | select(0u, ITEM_SPENT, captured == 0u));
    }
}

fn tex_word(i: u32) -> u32 {
    return tris[i];
}

fn tri_f32(i: u32) -> f32 {
    return bitcast<f32>(tris[i]);
}

// Triangle `i` of the buffer.
fn load_tri(i: u32) -> Tri {
    let o = i * TRI_WORDS;
    var t: Tri;
    for (var k = 0u; k < 3u; k++) {
        t.x[k] = bitcast<i32>(tris[o + k]);
        t.y[k] = bitcast<i32>(tris[o + 3u + k]);
        t.z[k] = tri_f32(o + 6u + k);
        t.inv_w[k] = tri_f32(o + 9u + k);
    }
    for (var k = 0u; k < 9u; k++) {
        t.n[k] = tri_f32(o + 12u + k);
        t.c[k] = tri_f32(o + 21u + k);
    }
    t.inv_area = tri_f32(o + 30u);
    for (var k = 0u; k < 4u; k++) {
        t.base[k] = tri_f32(o + 31u + k);
        t.bbox[k] = tris[o + 37u + k];
    }
    t.has_color = tris[o + 35u];
    t.prim = tris[o + 36u];
    t.tex = tris[o + 41u];
    return t;
}
const SUBPIXEL: i64 = 256li;
const HALF_PIXEL: i64 = 128li;

// The pixels work item `item` of `t` walks: its 8×8 tile within the triangle's box, inclusive
// (x0, y0, x1, y1).
fn item_rect(t: Tri, item: vec2<u32>) -> vec4<u32> {
    let tx = (item.y & 0xffffu) * TILE;
    let ty = (item.y >> 16u) * TILE;
    return vec4<u32>(max(t.bbox[0], tx), max(t.bbox[1], ty), min(t.bbox[2], tx + TILE - 1u), min(t.bbox[3], ty + TILE - 1u));
}

// Whether every fragment of `t` in the compute-raster tile of work item `item` lies at or behind
// the opaque depth at every sample of the tile (the tile's farthest, opaque.wgsl's
// `opaque_tiles_main`), so that the opaque cut holds back each one: the triangle's nearest vertex
// depth, less more than its interpolation's rounding can take off (the barycentric weights' few
// ulps times the depths' spread, and the depths' own), is not in front of it. One sample a pixel
// only: above one a fragment's depth is extrapolated to the pixel centre, which may lie outside
// the triangle. (A floor from the triangle's depth plane at the item's corners skips more tiles of
// a sloping triangle, but its 64-bit edge arithmetic made every compute pass 1.1-1.6x slower on
// the H100 and the H200, done by each invocation or once a workgroup behind a barrier, even where
// no opaque object lets it skip anything: bench/results/h200/tile-skip-workgroup-1024. The
// frame's first scene pass has that floor, `depth_floor`, from `classify_main`, once an item.)
// It reads the triangle's three depths alone, so that an item held back loads nothing more.
fn behind_tile(item: vec2<u32>) -> bool {
    if (fu.opaque.x == 0u || fu.msaa.x > 1u) {
        return false;
    }
    let far = tile_far(item);
    let o = item.x * TRI_WORDS + 6u;
    let z = vec3<f32>(tri_f32(o), tri_f32(o + 1u), tri_f32(o + 2u));
    let lo = min(z.x, min(z.y, z.z));
    let hi = max(z.x, max(z.y, z.z));
    return depth_bits(clamp(lo - (hi - lo) * 1e-5 - 1e-6, 0.0, 1.0)) >= far;
}

// `tile_far` of a tile with a pixel that no opaque fragment covers: nothing lies behind it.
const FAR_NONE: u32 = 0xffffffffu;

// The farthest opaque depth's bits over work item `item`'s tile (`FAR_NONE` where a pixel of it
// has no opaque fragment, or the frame no opaque part).
fn tile_far(item: vec2<u32>) -> u32 {
    return ~atomicLoad(&opaque_rgb[opaque_tile_word(item_tile(item))]);
}

// A floor of the depths `raster_pixel` gives `t` at the pixel centres of rect `r` (inclusive):
// `plane_depth` at the barycentrics of the edge values, of those the rect's corners take, that
// give the least depth. An edge value is affine in the pixel, so over the rect it lies between
// its corners' values; and the depth is monotone in each of the two edge values it reads, each
// operation (the f32 conversion, the products, the sums, the clamp) being a rounding of a
// monotone function. Taking each edge's value at its own worst corner floors every pixel's.
fn depth_floor(t: Tri, r: vec4<u32>) -> f32 {
    var lo = vec2<i64>(0x7fffffffffffffffli, 0x7fffffffffffffffli);
    var hi = -lo;
    for (var c = 0u; c < 4u; c++) {
        let p = rect_corner(r, c);
        let e = vec2<i64>(edge_at(t, 1u, p.x, p.y).x, edge_at(t, 2u, p.x, p.y).x);
        lo = min(lo, e);
        hi = max(hi, e);
    }
    let z0 = bitcast<u32>(t.z[0]);
    let dz = vec2<u32>(sf_sub(bitcast<u32>(t.z[1]), z0), sf_sub(bitcast<u32>(t.z[2]), z0));
    // the depth grows with an edge's value where its weight's factor (the inverse area) and its
    // depth difference have one sign
    let area_up = (bitcast<u32>(t.inv_area) >> 31u) == 0u;
    let e1 = select(hi.x, lo.x, area_up == ((dz.x >> 31u) == 0u));
    let e2 = select(hi.y, lo.y, area_up == ((dz.y >> 31u) == 0u));
    return plane_depth(t, vec3<f32>(0.0, f32(e1) * t.inv_area, f32(e2) * t.inv_area));
}

// oit-core's `DepthPlane::depth` of `t` at barycentrics `b`, operation for operation in the
// integer f32 of softfloat.wgsl. In float hardware a driver may contract the products and sums
// into fused multiply-adds (naga emits no NoContraction), which moves a depth by an ulp now and
// then; equal depths are the ties the techniques order and count, and the depth bins' edges are
// exact, so an ulp changes counts (an NVIDIA H200 counted two ties fewer than oit-cpu on planes:6
// at 4 samples, and adp two losses more).
fn plane_depth(t: Tri, b: vec3<f32>) -> f32 {
    let z0 = bitcast<u32>(t.z[0]);
    let dz1 = sf_sub(bitcast<u32>(t.z[1]), z0);
    let dz2 = sf_sub(bitcast<u32>(t.z[2]), z0);
    let d = sf_add(sf_add(z0, sf_mul(bitcast<u32>(b.y), dz1)), sf_mul(bitcast<u32>(b.z), dz2));
    return clamp(bitcast<f32>(d), 0.0, 1.0);
}

// Edge k of `t` (from vertex k+1 to k+2) at the subpixel point (px, py): its function's value,
// its steps along x and y, and the value it must exceed to cover the point (-1 on a top or left
// edge, whose points belong to the triangle, else 0).
fn edge_at(t: Tri, k: u32, px: i64, py: i64) -> vec4<i64> {
    let a = (k + 1u) % 3u;
    let b = (k + 2u) % 3u;
    let ax = i64(t.x[a]);
    let ay = i64(t.y[a]);
    let dx = i64(t.x[b]) - ax;
    let dy = i64(t.y[b]) - ay;
    let top_left = dy < 0li || (dy == 0li && dx > 0li);
    return vec4<i64>(dx * (py - ay) - dy * (px - ax), -dy, dx, select(0li, -1li, top_left));
}

// What the fragment of `t` at pixel (x, y) is: 0 none (the pixel's centre outside; with several
// samples a pixel, each of its samples: `fu.msaa`), 2 held back by the opaque depth at every
// sample it covers (counted, neither shaded nor captured; at once where `behind`: `behind_tile`),
// 1 captured.
fn raster_pixel(t: Tri, x: u32, y: u32, behind: bool) -> u32 {
    if (x < t.bbox[0] || x > t.bbox[2] || y < t.bbox[1] || y > t.bbox[3]) {
        return 0u;
    }
    let py = i64(y) * SUBPIXEL + HALF_PIXEL;
    let px = i64(x) * SUBPIXEL + HALF_PIXEL;
    // edge k runs from vertex k+1 to k+2
    var e: array<i64, 3>;
    var step_x: array<i64, 3>;
    var step_y: array<i64, 3>;
    var above: array<i64, 3>;
    var inside = true;
    for (var k = 0u; k < 3u; k++) {
        let edge = edge_at(t, k, px, py);
        e[k] = edge.x;
        step_x[k] = edge.y;
        step_y[k] = edge.z;
        above[k] = edge.w;
        inside = inside && e[k] > above[k];
    }
    var mask = 1u;
    if (fu.msaa.x > 1u) {
        // oit-core's `setup::sample_mask`: the same edge functions and rule at each sample, the
        // centre's value plus the sample's offset from the centre along each edge's steps; the
        // fragment is shaded at the centre, covered or not (its depth extrapolated)
        mask = 0u;
        for (var i = 0u; i < fu.msaa.x; i++) {
            let byte = (select(fu.msaa.z, fu.msaa.w, i >= 4u) >> (8u * (i % 4u))) & 0xffu;
            let ox = i64(byte & 15u) * 16li - HALF_PIXEL;
            let oy = i64(byte >> 4u) * 16li - HALF_PIXEL;
            var covered = true;
            for (var k = 0u; k < 3u; k++) {
                covered = covered && e[k] + step_x[k] * ox + step_y[k] * oy > above[k];
            }
            mask |= select(0u, 1u << i, covered);
        }
        inside = mask != 0u;
    }
    if (!inside) {
        return 0u;
    }
    if (behind) {
        return 2u;
    }
    let b = vec3<f32>(f32(e[0]) * t.inv_area, f32(e[1]) * t.inv_area, f32(e[2]) * t.inv_area);
    let depth = plane_depth(t, b);
    var f: Fragment;
    f.pixel = y * ru.width + x;
    f.depth = depth;
    // the samples in front of the opaque pass's depth; behind at every one: generated (counted),
    // neither shaded nor captured (oit-cpu tests the cut before it shades too)
    f.mask = mask;
    f.mask = opaque_front(f);
    if (f.mask == 0u) {
        return 2u;
    }
    let q = vec3<f32>(b.x * t.inv_w[0], b.y * t.inv_w[1], b.z * t.inv_w[2]);
    let inv_q = 1.0 / (q.x + q.y + q.z);
    let p = q * inv_q;
    let n0 = vec3<f32>(t.n[0], t.n[1], t.n[2]);
    let n1 = vec3<f32>(t.n[3], t.n[4], t.n[5]);
    let n2 = vec3<f32>(t.n[6], t.n[7], t.n[8]);
    let normal = n0 * p.x + n1 * p.y + n2 * p.z;
    let c0 = vec3<f32>(t.c[0], t.c[1], t.c[2]);
    let c1 = vec3<f32>(t.c[3], t.c[4], t.c[5]);
    let c2 = vec3<f32>(t.c[6], t.c[7], t.c[8]);
    var vcolor = c0 * p.x + c1 * p.y + c2 * p.z;
    var base = vec4<f32>(t.base[0], t.base[1], t.base[2], t.base[3]);
    // an untextured masked object's alpha is 1 or 0 (`Scene::layers`), which one half splits
    var cutoff = 0.5;
    if (t.tex != 0u) {
        // oit-core's `TriangleSetup::color_at`: the texture coordinates interpolated as the
        // colours are, the sample multiplying the base colour and the vertex colour
        let r = t.tex;
        let uv0 = vec2<f32>(tri_f32(r), tri_f32(r + 1u));
        let uv1 = vec2<f32>(tri_f32(r + 2u), tri_f32(r + 3u));
        let uv2 = vec2<f32>(tri_f32(r + 4u), tri_f32(r + 5u));
        let uv = uv0 * p.x + uv1 * p.y + uv2 * p.z;
        let s = tex_sample(tris[r + 8u], tris[r + 6u], uv);
        base = base * s;
        vcolor = vcolor * s.xyz;
        cutoff = tri_f32(r + 7u);
    }
    let color = shade(ru.shading, base, normal, vcolor, t.has_color != 0u, ru.forward.xyz);
    f.prim = t.prim;
    f.color = color;
    f.normal = normalize_or_zero(normal);
    f.cutoff = cutoff;
    capture(coverage_weighted(f, fu.msaa, fu.opaque));
    return 1u;
}

var<workgroup> wg_count: atomic<u32>;
var<workgroup> wg_occluded: atomic<u32>;

// Clears the workgroup's counts for `count_fragments` (called first, in uniform control flow).
fn start_counts(lid: u32) {
    if (lid == 0u) {
        atomicStore(&wg_count, 0u);
        atomicStore(&wg_occluded, 0u);
    }
    workgroupBarrier();
}

// The work item of an invocation of a kernel run an invocation an item (`raster_loop_main`,
// `classify_main`: workgroups of 64 from the per-item arguments, y above x's limit).
fn item_index(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * groups.x * 64u;
}

// Adds the workgroup's fragments to `generated`, and those the opaque cut held back to the
// occluded counter where the pass counts them (the frame's first scene pass: `fu.opaque.y`), one
// atomic each a workgroup (called in uniform control flow), none where the workgroup has none: a
// pass's items are millions of workgroups on a large scene, most of them with nothing to add
// where an opaque object holds their tiles back, all adding to one word.
// Returns, to invocation 0, the workgroup's fragments in front of the cut (captured).
fn count_fragments(lid: u32, count: u32, occluded: u32) -> u32 {
    atomicAdd(&wg_count, count);
    if (occluded != 0u) {
        atomicAdd(&wg_occluded, occluded);
    }
    workgroupBarrier();
    var captured = 0u;
    if (lid == 0u) {
        let n = atomicLoad(&wg_count);
        if (n != 0u) {
            atomicAdd(&generated[0], n);
        }
        let held = atomicLoad(&wg_occluded);
        if (held != 0u && fu.opaque.y != 0u) {
            atomicAdd(&opaque_rgb[opaque_counter(1u)], held);
        }
        captured = n - held;
    }
    return captured;
}

// The compute-raster tile of work item `item` (its tile's column and row), as opaque.wgsl's
// `opaque_tiles_main` numbers them.
fn item_tile(item: vec2<u32>) -> u32 {
    return (item.y >> 16u) * ((ru.width + TILE - 1u) / TILE) + (item.y & 0xffffu);
}

// GPUs: one workgroup per work item (a triangle and one 8×8 tile of its box), one invocation per
// pixel, so a large triangle spreads over many workgroups.
@compute @workgroup_size(64)
fn raster_main(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    start_counts(lid);
    let i = wid.x + wid.y * groups.x;
    var code = 0u;
    var item = vec2<u32>();
    if (i < ru.item_count) {
        let loaded = load_item(i);
        item = loaded.xy;
        // wholly behind the opaque depth: only the frame's first scene pass counts its fragments
        if (loaded.z == 0u) {
            let behind = behind_tile(item);
            if (!behind || fu.opaque.y != 0u) {
                let t = load_tri(item.x);
                let x = (item.y & 0xffffu) * TILE + lid % TILE;
                let y = (item.y >> 16u) * TILE + lid / TILE;
                code = raster_pixel(t, x, y, behind);
            }
        }
    }
    let captured = count_fragments(lid, u32(code != 0u), u32(code == 2u));
    if (lid == 0u && i < ru.item_count) {
        mark_item(i, item, captured);
    }
}

// The subpixel centre of corner c (0 to 3) of rect `r` (inclusive pixels x0, y0, x1, y1).
fn rect_corner(r: vec4<u32>, c: u32) -> vec2<i64> {
    let x = select(r.x, r.z, (c & 1u) != 0u);
    let y = select(r.y, r.w, (c & 2u) != 0u);
    return vec2<i64>(i64(x) * SUBPIXEL + HALF_PIXEL, i64(y) * SUBPIXEL + HALF_PIXEL);
}

// The pixels of rect `r` of `t` (a work item's: `item_rect`) where every one is covered at its
// centre (one sample a pixel), else 0. An edge function is affine in the pixel and exact in 64
// bits, so a rect whose four corners an edge covers is covered by it throughout.
fn interior_pixels(t: Tri, r: vec4<u32>) -> u32 {
    if (r.x > r.z || r.y > r.w) {
        return 0u;
    }
    for (var c = 0u; c < 4u; c++) {
        let p = rect_corner(r, c);
        for (var k = 0u; k < 3u; k++) {
            let edge = edge_at(t, k, p.x, p.y);
            if (edge.x <= edge.w) {
                return 0u;
            }
        }
    }
    return (r.z - r.x + 1u) * (r.w - r.y + 1u);
}

// Before the frame's first scene pass over an opaque part, at one sample a pixel (oit-gpu's
// `classifies_items`), one invocation a work item: an item wholly behind the opaque depth
// (`behind_tile`) whose rect its triangle covers throughout has each of its pixels' fragments
// held back, so this counts them (`generated`, and `occluded` as the pass counts them) without
// the pass walking the pixels, and marks the item `ITEM_COUNTED` for every pass of the frame to
// skip. Behind a wall most items of a large triangle are such; the pass walks the rest (a
// triangle's edges, the tiles it only partly hides) as before, so the counts are the same.
@compute @workgroup_size(64)
fn classify_main(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    start_counts(lid);
    let i = item_index(gid, groups);
    var held = 0u;
    if (i < ru.item_count) {
        // the frame's first scene pass is yet to run: no item is marked
        let item = load_item(i).xy;
        let far = tile_far(item);
        if (far != FAR_NONE) {
            let t = load_tri(item.x);
            let r = item_rect(t, item);
            let n = interior_pixels(t, r);
            if (n != 0u && (behind_tile(item) || depth_bits(depth_floor(t, r)) >= far)) {
                held = n;
                items[i] = vec2<u32>(item.x, item.y | ITEM_COUNTED);
            }
        }
    }
    count_fragments(lid, held, held);
}

// CPU devices (lavapipe): one invocation per work item, walking its tile; a workgroup of 64
// pixels of one small triangle would mostly test pixels outside it.
@compute @workgroup_size(64)
fn raster_loop_main(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    start_counts(lid);
    let i = item_index(gid, groups);
    var count = 0u;
    var occluded = 0u;
    if (i < ru.item_count) {
        let loaded = load_item(i);
        let item = loaded.xy;
        let behind = loaded.z == 0u && behind_tile(item);
        // wholly behind the opaque depth: only the frame's first scene pass counts its fragments
        if (loaded.z == 0u && (!behind || fu.opaque.y != 0u)) {
            let t = load_tri(item.x);
            let r = item_rect(t, item);
            for (var y = r.y; y <= r.w; y++) {
                for (var x = r.x; x <= r.z; x++) {
                    let code = raster_pixel(t, x, y, behind);
                    count += u32(code != 0u);
                    occluded += u32(code == 2u);
                }
            }
        }
        mark_item(i, item, count - occluded);
    }
    count_fragments(lid, count, occluded);
}
