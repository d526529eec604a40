// module setup (alone): core/softfloat.wgsl core/setup.wgsl
// The compute path's triangle setup on the GPU: oit-core's `setup` (crates' oit-core/src/setup.rs)
// rule for rule, every float operation in softfloat.wgsl's integer f32 (so in the host's order and
// rounding, bit for bit, whatever the driver does with float math), writing the 44-word triangles
// of `TriangleSetup::triangle_words` and the (triangle, 8×8 tile) work list the raster kernel
// (raster_compute.wgsl) reads.
//
// `setup_main`: one invocation per (instance, triangle): vertex transform (`mvp · (p, 1)` as
// ((c0·x + c1·y) + c2·z) + c3·1), normal matrix, clipping against near, far and the guard band
// (Sutherland–Hodgman, cut from the inside end), fan triangulation, perspective divide, viewport,
// snapping by floor(v·256 + 0.5), the area, orientation and pixel box; each piece kept takes a
// slot by atomic increment and appends its tiles to the work list the same way. Pieces land in
// an order of the GPU's choosing: no result depends on the triangle order (the raster kernel runs
// its work items concurrently and every capture is an atomic update; exact techniques sort by
// (depth, primitive id)), so only the set of pieces must be the host's. Speed does depend on it:
// each piece's tiles lie together, in row-major order (see `setup_items_main`).
// `setup_count_main`, `setup_items_main`: a workgroup per large piece, counting then writing its
// work items in order (`SPREAD_PIECES`).
// `setup_finish_main`: one invocation; the raster kernel's indirect dispatch arguments and item
// count from the counters.
//
// `vertex_main` first, where the vertex cache is on (`su.use_verts`): one invocation per
// (instance, vertex) transforms the vertex once, and keeps its clip position, normal, clip
// outcode and snapped projection (`VERT_WORDS` words), as oit-core's setup does per vertex:
// each is a function of the vertex alone, so `setup_main` reads the same bits a per-triangle
// transform gives, at a sixth of the transforms on a closed mesh (a vertex is shared by about six
// triangles). Only clipped pieces project in `setup_main`.

struct SetupUniform {
    // the frame's (or the window's, `Settings::region`) width and height: pixel boxes clamp to it
    width: u32,
    height: u32,
    // the full frame's width and height as f32 bits: the viewport every vertex is snapped in
    width_f: u32,
    height_f: u32,
    instance_count: u32,
    task_count: u32,
    tri_capacity: u32,
    item_capacity: u32,
    // the window's origin in the full frame, in 1/256 pixel: subtracted from the snapped
    // coordinates (an exact integer shift, as oit-core's setup does); 0 for a whole frame
    origin_x: i32,
    origin_y: i32,
    // vertices of all instances (the vertex cache's records), and 1 when the cache is used
    vertex_total: u32,
    use_verts: u32,
    // the smallest and largest offset of a pixel's samples from its top-left corner, in 1/256
    // pixel (oit-core's `setup::reach`): 128 and 128, the centre, with one sample
    reach_near: i32,
    reach_far: i32,
    pad0: u32,
    pad1: u32,
}

// Per instance, INSTANCE_WORDS words: mvp (16, columns), normal matrix (9, columns), base colour
// (4), then the fields below.
const INSTANCE_WORDS: u32 = 40u;
const I_VERTEX_BASE: u32 = 29u;   // first vertex (in vertices) of the instance's mesh
const I_VERTEX_COUNT: u32 = 30u;
const I_COLOR_BASE: u32 = 31u;    // first colour word, 0xffffffff without vertex colours
const I_INDEX_BASE: u32 = 32u;    // first index word of the mesh's triangles
const I_TRI_COUNT: u32 = 33u;
const I_PRIM_BASE: u32 = 34u;
const I_FIRST_TASK: u32 = 35u;    // tasks (triangles) of the instances before this one
const I_FLAGS: u32 = 36u;         // bit 0: normals are used as given (no normal matrix); bits 1,
                                  // 2: drop back faces, of positive / negative snapped area
const I_POSITIONS: u32 = 37u;     // first position word of the geometry
const I_NORMALS: u32 = 38u;       // first normal word of the geometry
const I_FIRST_VERT: u32 = 39u;    // vertex-cache records of the instances before this one

const TRI_WORDS: u32 = 44u;
const SETUP_TILE: u32 = 8u;
// A piece of more than SPREAD_ITEMS tiles in its box (one of the first SPREAD_PIECES such) leaves
// them to `setup_count_main` and `setup_items_main`, a workgroup a piece (oit-core's
// `gpu_setup::SPREAD_PIECES`, `SPREAD_ITEMS`): one invocation writing a large triangle's thousands of tiles, while a frame of a few such
// triangles keeps a few invocations of the whole GPU busy, took 0.26 ms of an H100's frame for the
// two triangles of a wall behind `particles:256` at 1024².
const SPREAD_PIECES: u32 = 2048u;
const SPREAD_ITEMS: u32 = 16u;
const SPREAD_FIRST: u32 = 4u;
const GUARD_BAND_BITS: u32 = 0x42800000u; // 64.0
const SUBPIXEL_F: u32 = 0x43800000u;      // 256.0
const COORD_LIMIT_BITS: u32 = 0x4e000000u; // 2^29

@group(0) @binding(0) var<uniform> su: SetupUniform;
@group(0) @binding(1) var<storage, read> instances: array<u32>;
@group(0) @binding(2) var<storage, read> geometry: array<u32>;
@group(0) @binding(3) var<storage, read_write> out_tris: array<u32>;
@group(0) @binding(4) var<storage, read_write> out_items: array<vec2<u32>>;
// 0: pieces, 1: work items (both counted past the capacities, so the host sees what is needed),
// 2: pieces spread (`SPREAD_PIECES`), 3: their tiles kept (`setup_count_main`); from 4, two
// words a spread piece: its slot, and the tiles it keeps
@group(0) @binding(5) var<storage, read_write> counters: array<atomic<u32>>;
// 0..3: per-pixel raster dispatch, 4..7: per-item raster dispatch, 8: work items in the list
@group(0) @binding(6) var<storage, read_write> args: array<u32>;
// the vertex cache: VERT_WORDS words per (instance, vertex)
@group(0) @binding(7) var<storage, read_write> verts: array<u32>;

// clip position (4), normal (3), flags (bit 0: position finite; bits 1..6: outside clip plane
// 0..5; bit 7: projected), projected x, y (i32 bits), z, 1/w
const VERT_WORDS: u32 = 12u;
const V_FINITE: u32 = 1u;
const V_PROJECTED: u32 = 128u;

struct ClipVertex {
    pos: vec4<u32>,
    n: vec3<u32>,
    c: vec3<u32>,
}

fn inst(i: u32, word: u32) -> u32 {
    return instances[i * INSTANCE_WORDS + word];
}

// glam's Mat4 · Vec4 on x86_64: ((c0·x + c1·y) + c2·z) + c3·w, each product rounded.
fn transform_point(i: u32, x: u32, y: u32, z: u32) -> vec4<u32> {
    var r: vec4<u32>;
    for (var row = 0u; row < 4u; row++) {
        let s0 = sf_mul(inst(i, row), x);
        let s1 = sf_mul(inst(i, 4u + row), y);
        let s2 = sf_mul(inst(i, 8u + row), z);
        let s3 = sf_mul(inst(i, 12u + row), SF_ONE);
        r[row] = sf_add(sf_add(sf_add(s0, s1), s2), s3);
    }
    return r;
}

// glam's Mat3 · Vec3: (c0·x + c1·y) + c2·z.
fn transform_normal(i: u32, x: u32, y: u32, z: u32) -> vec3<u32> {
    var r: vec3<u32>;
    for (var row = 0u; row < 3u; row++) {
        let s0 = sf_mul(inst(i, 16u + row), x);
        let s1 = sf_mul(inst(i, 19u + row), y);
        let s2 = sf_mul(inst(i, 22u + row), z);
        r[row] = sf_add(sf_add(s0, s1), s2);
    }
    return r;
}

fn load_vertex(i: u32, v: u32) -> ClipVertex {
    var out: ClipVertex;
    let p = inst(i, I_POSITIONS) + 3u * (inst(i, I_VERTEX_BASE) + v);
    out.pos = transform_point(i, geometry[p], geometry[p + 1u], geometry[p + 2u]);
    let n = inst(i, I_NORMALS) + 3u * (inst(i, I_VERTEX_BASE) + v);
    if ((inst(i, I_FLAGS) & 1u) != 0u) {
        out.n = vec3<u32>(geometry[n], geometry[n + 1u], geometry[n + 2u]);
    } else {
        out.n = transform_normal(i, geometry[n], geometry[n + 1u], geometry[n + 2u]);
    }
    out.c = load_color(i, v);
    return out;
}

// Vertex `v`'s colour (zero where the mesh has none).
fn load_color(i: u32, v: u32) -> vec3<u32> {
    let cb = inst(i, I_COLOR_BASE);
    if (cb == 0xffffffffu) {
        return vec3<u32>(0u);
    }
    let c = cb + 3u * v;
    return vec3<u32>(geometry[c], geometry[c + 1u], geometry[c + 2u]);
}

// self + (other − self)·t, per component.
fn toward(a: ClipVertex, b: ClipVertex, t: u32) -> ClipVertex {
    var r: ClipVertex;
    for (var k = 0u; k < 4u; k++) {
        r.pos[k] = sf_add(a.pos[k], sf_mul(sf_sub(b.pos[k], a.pos[k]), t));
    }
    for (var k = 0u; k < 3u; k++) {
        r.n[k] = sf_add(a.n[k], sf_mul(sf_sub(b.n[k], a.n[k]), t));
        r.c[k] = sf_add(a.c[k], sf_mul(sf_sub(b.c[k], a.c[k]), t));
    }
    return r;
}

// Signed distance to clip plane `plane` (inside when ≥ 0): near, far, then the guard band.
fn plane_distance(p: vec4<u32>, plane: u32) -> u32 {
    switch plane {
        case 0u: { return p.z; }
        case 1u: { return sf_sub(p.w, p.z); }
        case 2u: { return sf_sub(sf_mul(GUARD_BAND_BITS, p.w), p.x); }
        case 3u: { return sf_add(sf_mul(GUARD_BAND_BITS, p.w), p.x); }
        case 4u: { return sf_sub(sf_mul(GUARD_BAND_BITS, p.w), p.y); }
        default: { return sf_add(sf_mul(GUARD_BAND_BITS, p.w), p.y); }
    }
}

const MAX_POLYGON: u32 = 9u;

var<private> poly: array<ClipVertex, 9>;
var<private> poly_n: u32;
var<private> next_poly: array<ClipVertex, 9>;
var<private> next_n: u32;

fn push_next(v: ClipVertex) {
    if (next_n < MAX_POLYGON) {
        next_poly[next_n] = v;
        next_n += 1u;
    }
}

// Sutherland–Hodgman against the planes in `planes` (a bit mask), on `poly`.
fn clip_poly(planes: u32) {
    for (var plane = 0u; plane < 6u; plane++) {
        if ((planes & (1u << plane)) == 0u) {
            continue;
        }
        next_n = 0u;
        for (var i = 0u; i < poly_n; i++) {
            let a = poly[i];
            let b = poly[(i + 1u) % poly_n];
            let da = plane_distance(a.pos, plane);
            let db = plane_distance(b.pos, plane);
            let a_in = sf_ge0(da);
            let b_in = sf_ge0(db);
            if (a_in) {
                push_next(a);
            }
            if (a_in != b_in) {
                // cut from the inside end (no crack where two triangles share an edge)
                if (a_in) {
                    push_next(toward(a, b, sf_div(da, sf_sub(da, db))));
                } else {
                    push_next(toward(b, a, sf_div(db, sf_sub(db, da))));
                }
            }
        }
        for (var i = 0u; i < next_n; i++) {
            poly[i] = next_poly[i];
        }
        poly_n = next_n;
        if (poly_n < 3u) {
            return;
        }
    }
}

struct Projected {
    ok: bool,
    x: i32,
    y: i32,
    z: u32,
    inv_w: u32,
}

// Perspective divide, viewport, snap.
fn project(p: vec4<u32>) -> Projected {
    var r: Projected;
    r.ok = false;
    // w.is_nan() || w <= 0.0
    if (sf_is_nan(p.w) || sf_lt0(p.w) || (p.w & 0x7fffffffu) == 0u) {
        return r;
    }
    let inv_w = sf_div(SF_ONE, p.w);
    let nx = sf_mul(p.x, inv_w);
    let ny = sf_mul(p.y, inv_w);
    let nz = sf_mul(p.z, inv_w);
    let fx = sf_mul(sf_add(sf_mul(nx, SF_HALF), SF_HALF), su.width_f);
    let fy = sf_mul(sf_sub(SF_ONE, sf_add(sf_mul(ny, SF_HALF), SF_HALF)), su.height_f);
    let sx = sf_floor(sf_add(sf_mul(fx, SUBPIXEL_F), SF_HALF));
    let sy = sf_floor(sf_add(sf_mul(fy, SUBPIXEL_F), SF_HALF));
    let in_range = (sx & 0x7fffffffu) <= COORD_LIMIT_BITS && (sy & 0x7fffffffu) <= COORD_LIMIT_BITS;
    if (!(in_range && sf_is_finite(nz) && sf_is_finite(inv_w))) {
        return r;
    }
    r.ok = true;
    r.x = sf_to_i32(sx) - su.origin_x;
    r.y = sf_to_i32(sy) - su.origin_y;
    r.z = nz;
    r.inv_w = inv_w;
    return r;
}

struct Range {
    ok: bool,
    first: u32,
    last: u32,
}

// Pixel k's centre is at 256k + 128: the first centre at or after `lo`, the last at or before `hi`.
// With several samples a pixel, the first pixel whose last sample is at or after `lo`, the last
// whose first is at or before `hi` (oit-core's `TriangleSetup` sizes boxes the same way).
fn pixel_range(lo: i32, hi: i32, size: u32) -> Range {
    let first = max((lo - su.reach_far + 255) >> 8u, 0);
    let last = min((hi - su.reach_near) >> 8u, i32(size) - 1);
    return Range(first <= last, u32(max(first, 0)), u32(max(last, 0)));
}

// Projects and snaps one (clipped) triangle; keeps it if it has area and touches the viewport.
fn piece(i: u32, v: array<ClipVertex, 3>, prim: u32) {
    var p: array<Projected, 3>;
    for (var k = 0u; k < 3u; k++) {
        p[k] = project(v[k].pos);
        if (!p[k].ok) {
            return;
        }
    }
    piece_projected(i, v, p, prim);
}

// A triangle whose vertices are projected (`p`, all ok): kept if it has area and touches the
// viewport.
fn piece_projected(i: u32, v_in: array<ClipVertex, 3>, p_in: array<Projected, 3>, prim: u32) {
    var v = v_in;
    var p = p_in;
    let x0 = i64(p[0].x);
    let y0 = i64(p[0].y);
    var area = (i64(p[1].x) - x0) * (i64(p[2].y) - y0) - (i64(p[1].y) - y0) * (i64(p[2].x) - x0);
    if (area == 0li) {
        return;
    }
    // a single-sided object's back face, by the sign of the snapped area (oit-core's
    // `back_face_sign`)
    let flags = inst(i, I_FLAGS);
    if (((flags & 2u) != 0u && area > 0li) || ((flags & 4u) != 0u && area < 0li)) {
        return;
    }
    if (area < 0li) {
        let tp = p[1];
        p[1] = p[2];
        p[2] = tp;
        let tv = v[1];
        v[1] = v[2];
        v[2] = tv;
        area = -area;
    }
    let rx = pixel_range(min(min(p[0].x, p[1].x), p[2].x), max(max(p[0].x, p[1].x), p[2].x), su.width);
    let ry = pixel_range(min(min(p[0].y, p[1].y), p[2].y), max(max(p[0].y, p[1].y), p[2].y), su.height);
    if (!rx.ok || !ry.ok) {
        return;
    }
    // binning: the piece's 8×8 tiles that it may cover (`row_run`), row by row
    let tx0 = rx.first / SETUP_TILE;
    let tx1 = rx.last / SETUP_TILE;
    let ty0 = ry.first / SETUP_TILE;
    let ty1 = ry.last / SETUP_TILE;
    let n = (tx1 - tx0 + 1u) * (ty1 - ty0 + 1u);
    let slot = atomicAdd(&counters[0], 1u);
    if (slot >= su.tri_capacity) {
        // counted, as every tile of its box (more than it needs), so that the host grows the
        // buffers for it and sets up again
        atomicAdd(&counters[1], n);
        return;
    }
    let o = slot * TRI_WORDS;
    for (var k = 0u; k < 3u; k++) {
        out_tris[o + k] = u32(p[k].x);
        out_tris[o + 3u + k] = u32(p[k].y);
        out_tris[o + 6u + k] = p[k].z;
        out_tris[o + 9u + k] = p[k].inv_w;
        for (var c = 0u; c < 3u; c++) {
            out_tris[o + 12u + 3u * k + c] = v[k].n[c];
            out_tris[o + 21u + 3u * k + c] = v[k].c[c];
        }
    }
    out_tris[o + 30u] = sf_div(SF_ONE, sf_from_u64(u64(area)));
    for (var c = 0u; c < 4u; c++) {
        out_tris[o + 31u + c] = inst(i, 25u + c);
    }
    out_tris[o + 35u] = select(0u, 1u, inst(i, I_COLOR_BASE) != 0xffffffffu);
    out_tris[o + 36u] = prim;
    out_tris[o + 37u] = rx.first;
    out_tris[o + 38u] = ry.first;
    out_tris[o + 39u] = rx.last;
    out_tris[o + 40u] = ry.last;
    out_tris[o + 41u] = 0u;
    out_tris[o + 42u] = 0u;
    out_tris[o + 43u] = 0u;
    if (n > SPREAD_ITEMS) {
        let j = atomicAdd(&counters[2], 1u);
        if (j < SPREAD_PIECES) {
            atomicStore(&counters[SPREAD_FIRST + 2u * j], slot);
            return;
        }
    }
    // counted, then written, row by row
    var m = 0u;
    for (var ty = ty0; ty <= ty1; ty++) {
        let run = row_run(o, ty, tx0, tx1);
        m += run.y - run.x;
    }
    let base = atomicAdd(&counters[1], m);
    if (base >= su.item_capacity || su.item_capacity - base < m) {
        return;
    }
    var at = base;
    for (var ty = ty0; ty <= ty1; ty++) {
        let run = row_run(o, ty, tx0, tx1);
        for (var tx = run.x; tx < run.y; tx++) {
            out_items[at] = vec2<u32>(slot, (ty << 16u) | tx);
            at += 1u;
        }
    }
}

// floor(a / b) for b > 0 (WGSL's `/` truncates toward zero), oit-core's `div_euclid`. Where
// `row_run` solves for a turn its numerators are not negative (the tiles' corners lie at x ≥ 0),
// so truncation would agree; the floor keeps the host's rule as written.
fn floor_div(a: i64, b: i64) -> i64 {
    let q = a / b;
    return select(q, q - 1li, q * b > a);
}

// The tiles of row `ty` of the piece at word `o` (its box's columns tx0 to tx1) that oit-core's
// `Triangle::may_cover` keeps, as the columns [x, y), empty where y is x: oit-core's
// `RowEdges::run` rule for rule. An edge keeps a tile where its largest value over the tile's part
// of the box (from the first pixel's corner to the last's, in 1/256 pixel) exceeds its bound, and
// an affine function's largest value over a rectangle lies at a corner. Along a row the tile only
// moves right, so each edge keeps a prefix or a suffix of the row (or all of it, or none), which
// its two ends tell; where they differ, the column where the verdict turns is the solution of a
// linear inequality in the column, exact in 64 bits.
fn row_run(o: u32, ty: u32, tx0: u32, tx1: u32) -> vec2<u32> {
    let bx0 = out_tris[o + 37u];
    let by0 = out_tris[o + 38u];
    let bx1 = out_tris[o + 39u];
    let by1 = out_tris[o + 40u];
    let top = i64(max(ty * SETUP_TILE, by0)) * 256li;
    let bottom = i64(min(ty * SETUP_TILE + SETUP_TILE - 1u, by1)) * 256li + 255li;
    // the first and the last tile's left and right sides
    let first = vec2<i64>(i64(max(tx0 * SETUP_TILE, bx0)) * 256li, i64(min(tx0 * SETUP_TILE + SETUP_TILE - 1u, bx1)) * 256li + 255li);
    let last = vec2<i64>(i64(max(tx1 * SETUP_TILE, bx0)) * 256li, i64(min(tx1 * SETUP_TILE + SETUP_TILE - 1u, bx1)) * 256li + 255li);
    let width = i64(SETUP_TILE) * 256li;
    var lo = tx0;
    var end = tx1 + 1u;
    for (var k = 0u; k < 3u; k++) {
        let a = (k + 1u) % 3u;
        let b = (k + 2u) % 3u;
        let ax = i64(bitcast<i32>(out_tris[o + a]));
        let ay = i64(bitcast<i32>(out_tris[o + 3u + a]));
        let dx = i64(bitcast<i32>(out_tris[o + b])) - ax;
        let dy = i64(bitcast<i32>(out_tris[o + 3u + b])) - ay;
        let above = select(0li, -1li, dy < 0li || (dy == 0li && dx > 0li));
        // value(x, y) = dx·y − dy·x + value(0, 0), at the row's best y: c − dy·x
        let c = dx * select(top, bottom, dx > 0li) + dy * ax - dx * ay;
        let keeps_first = c - dy * select(first.x, first.y, dy < 0li) > above;
        let keeps_last = c - dy * select(last.x, last.y, dy < 0li) > above;
        if (!keeps_first && !keeps_last) {
            return vec2<u32>(tx0, tx0);
        }
        if (keeps_first == keeps_last) {
            continue;
        }
        // dy ≠ 0 here: with dy = 0 the verdict is the same along the row
        var turn: i64;
        if (dy < 0li) {
            // kept from the turn on: −dy·x̂ > above − c, x̂ = (column + 1)·width − 1
            let least = floor_div(above - c, -dy) + 1li;
            turn = floor_div(least + width, width) - 1li;
        } else {
            // kept until the turn: dy·x̂ < c − above, x̂ = column·width
            turn = floor_div(floor_div(c - above - 1li, dy), width) + 1li;
        }
        let column = u32(clamp(turn, i64(tx0) + 1li, i64(tx1)));
        if (keeps_first) {
            end = min(end, column);
        } else {
            lo = max(lo, column);
        }
    }
    return vec2<u32>(lo, max(lo, end));
}

// The instance whose tasks include `task`: the last with first task ≤ `task`.
fn find_instance(task: u32) -> u32 {
    var lo = 0u;
    var hi = su.instance_count;
    while (hi - lo > 1u) {
        let mid = (lo + hi) / 2u;
        if (inst(mid, I_FIRST_TASK) <= task) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}

// A vertex's clip flags (V_FINITE, the planes it is outside of, V_PROJECTED) and its snapped
// projection: what `vertex_main` keeps per vertex and the uncached path computes per corner.
struct VertexTest {
    flags: u32,
    p: Projected,
}

fn vertex_test(pos: vec4<u32>) -> VertexTest {
    var r: VertexTest;
    r.flags = 0u;
    if (!(sf_is_finite(pos.x) && sf_is_finite(pos.y) && sf_is_finite(pos.z) && sf_is_finite(pos.w))) {
        return r;
    }
    r.flags = V_FINITE;
    for (var plane = 0u; plane < 6u; plane++) {
        if (sf_lt0(plane_distance(pos, plane))) {
            r.flags |= 2u << plane;
        }
    }
    r.p = project(pos);
    if (r.p.ok) {
        r.flags |= V_PROJECTED;
    }
    return r;
}

@compute @workgroup_size(64)
fn setup_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let task = gid.x + gid.y * groups.x * 64u;
    if (task >= su.task_count) {
        return;
    }
    let i = find_instance(task);
    let t = task - inst(i, I_FIRST_TASK);
    if (t >= inst(i, I_TRI_COUNT)) {
        return;
    }
    let ib = inst(i, I_INDEX_BASE) + 3u * t;
    let count = inst(i, I_VERTEX_COUNT);
    // each corner's transform, flags and projection: from the vertex cache, or computed here
    var v: array<ClipVertex, 3>;
    var tests: array<VertexTest, 3>;
    for (var k = 0u; k < 3u; k++) {
        let index = geometry[ib + k];
        if (index >= count) {
            return;
        }
        if (su.use_verts != 0u) {
            let o = (inst(i, I_FIRST_VERT) + index) * VERT_WORDS;
            v[k].pos = vec4<u32>(verts[o], verts[o + 1u], verts[o + 2u], verts[o + 3u]);
            v[k].n = vec3<u32>(verts[o + 4u], verts[o + 5u], verts[o + 6u]);
            v[k].c = load_color(i, index);
            tests[k].flags = verts[o + 7u];
            tests[k].p = Projected(
                (tests[k].flags & V_PROJECTED) != 0u,
                bitcast<i32>(verts[o + 8u]),
                bitcast<i32>(verts[o + 9u]),
                verts[o + 10u],
                verts[o + 11u],
            );
        } else {
            v[k] = load_vertex(i, index);
            tests[k] = vertex_test(v[k].pos);
        }
    }
    let pb = inst(i, I_PRIM_BASE);
    let prim = select(pb + t, 0xffffffffu, pb + t < pb);
    let f0 = tests[0].flags;
    let f1 = tests[1].flags;
    let f2 = tests[2].flags;
    if ((f0 & f1 & f2 & V_FINITE) == 0u) {
        return;
    }
    // a plane all three corners are outside of culls the triangle; one any is outside of clips it
    if ((f0 & f1 & f2 & 0x7eu) != 0u) {
        return;
    }
    let outside_any = ((f0 | f1 | f2) & 0x7eu) >> 1u;
    if (outside_any == 0u) {
        if ((f0 & f1 & f2 & V_PROJECTED) == 0u) {
            return;
        }
        piece_projected(i, v, array<Projected, 3>(tests[0].p, tests[1].p, tests[2].p), prim);
        return;
    }
    poly[0] = v[0];
    poly[1] = v[1];
    poly[2] = v[2];
    poly_n = 3u;
    clip_poly(outside_any);
    for (var k = 1u; k + 1u < poly_n; k++) {
        piece(i, array<ClipVertex, 3>(poly[0], poly[k], poly[k + 1u]), prim);
    }
}

// The instance whose vertex-cache records include `v`: the last with first record ≤ `v`.
fn find_vertex_instance(v: u32) -> u32 {
    var lo = 0u;
    var hi = su.instance_count;
    while (hi - lo > 1u) {
        let mid = (lo + hi) / 2u;
        if (inst(mid, I_FIRST_VERT) <= v) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}

@compute @workgroup_size(64)
fn vertex_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let g = gid.x + gid.y * groups.x * 64u;
    if (g >= su.vertex_total) {
        return;
    }
    let i = find_vertex_instance(g);
    let v = g - inst(i, I_FIRST_VERT);
    if (v >= inst(i, I_VERTEX_COUNT)) {
        return;
    }
    let cv = load_vertex(i, v);
    let test = vertex_test(cv.pos);
    let o = g * VERT_WORDS;
    for (var c = 0u; c < 4u; c++) {
        verts[o + c] = cv.pos[c];
    }
    for (var c = 0u; c < 3u; c++) {
        verts[o + 4u + c] = cv.n[c];
    }
    verts[o + 7u] = test.flags;
    verts[o + 8u] = bitcast<u32>(test.p.x);
    verts[o + 9u] = bitcast<u32>(test.p.y);
    verts[o + 10u] = test.p.z;
    verts[o + 11u] = test.p.inv_w;
}

// The spread pieces (`SPREAD_PIECES`), a workgroup each, in two kernels after `setup_main`:
// `setup_count_main` counts the tiles of piece j's box that it may cover (`row_run`), and
// `setup_items_main` writes them, row-major, behind the small pieces' items and the spread pieces
// before j, so the list holds the spread pieces in the order they were spread (near the triangles'
// own) and each one's tiles in order. The raster kernel takes items in list order, so a pixel's
// fragments arrive near their primitive order, which the resolves' sorts are fast on: placed by
// an atomic each, in the order workgroups got to it, they came in a shuffled order, and the
// resolve of `nowall:0.4:planes:64` (64 layers a pixel) took two to three times as long on an H100. Both
// dispatch a workgroup for each piece that may be spread, at most SPREAD_PIECES (oit-core's
// `SetupGeometry::spread_groups`); those past the pieces spread end at once.
var<workgroup> spread_rows: u32;
var<workgroup> spread_sum: atomic<u32>;
var<workgroup> spread_counts: array<u32, 64>;

// Spread piece j: its slot, its first tile row and its rows of tiles (x, y, z; w unused); no rows
// past the pieces spread.
fn spread_piece(j: u32) -> vec4<u32> {
    if (j >= min(atomicLoad(&counters[2]), SPREAD_PIECES)) {
        return vec4<u32>(0u, 0u, 0u, 0u);
    }
    let slot = atomicLoad(&counters[SPREAD_FIRST + 2u * j]);
    let o = slot * TRI_WORDS;
    let ty0 = out_tris[o + 38u] / SETUP_TILE;
    return vec4<u32>(slot, ty0, out_tris[o + 40u] / SETUP_TILE - ty0 + 1u, 0u);
}

// The kept tiles of rows [r0, r1) of the piece at word o, from tile row ty0.
fn rows_kept(o: u32, ty0: u32, r0: u32, r1: u32) -> u32 {
    let tx0 = out_tris[o + 37u] / SETUP_TILE;
    let tx1 = out_tris[o + 39u] / SETUP_TILE;
    var kept = 0u;
    for (var row = r0; row < r1; row++) {
        let run = row_run(o, ty0 + row, tx0, tx1);
        kept += run.y - run.x;
    }
    return kept;
}

// Spread piece j for its workgroup (`spread_piece`): invocation 0 keeps its rows in
// `spread_rows` (which the caller reads with `workgroupUniformLoad`) and clears `spread_sum`.
fn spread_begin(j: u32, lid: u32) -> vec4<u32> {
    let piece = spread_piece(j);
    if (lid == 0u) {
        spread_rows = piece.z;
        atomicStore(&spread_sum, 0u);
    }
    return piece;
}

@compute @workgroup_size(64)
fn setup_count_main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let piece = spread_begin(wid.x, lid);
    let rows = workgroupUniformLoad(&spread_rows);
    if (rows == 0u) {
        return;
    }
    let o = piece.x * TRI_WORDS;
    var mine = 0u;
    for (var row = lid; row < rows; row += 64u) {
        mine += rows_kept(o, piece.y, row, row + 1u);
    }
    atomicAdd(&spread_sum, mine);
    workgroupBarrier();
    if (lid == 0u) {
        let kept = atomicLoad(&spread_sum);
        atomicStore(&counters[SPREAD_FIRST + 2u * wid.x + 1u], kept);
        atomicAdd(&counters[3], kept);
    }
}

@compute @workgroup_size(64)
fn setup_items_main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let j = wid.x;
    let piece = spread_begin(j, lid);
    let rows = workgroupUniformLoad(&spread_rows);
    if (rows == 0u) {
        return;
    }
    // where piece j starts: the small pieces' items (setup_main's count, final by now), then
    // those of the spread pieces before it
    var before = 0u;
    for (var i = lid; i < j; i += 64u) {
        before += atomicLoad(&counters[SPREAD_FIRST + 2u * i + 1u]);
    }
    atomicAdd(&spread_sum, before);
    // invocation lid takes a block of consecutive rows; the blocks' counts, scanned, place them
    let block = (rows + 63u) / 64u;
    let r0 = min(lid * block, rows);
    let r1 = min(r0 + block, rows);
    let o = piece.x * TRI_WORDS;
    spread_counts[lid] = rows_kept(o, piece.y, r0, r1);
    workgroupBarrier();
    var at = atomicLoad(&counters[1]) + atomicLoad(&spread_sum);
    for (var k = 0u; k < lid; k++) {
        at += spread_counts[k];
    }
    let tx0 = out_tris[o + 37u] / SETUP_TILE;
    let tx1 = out_tris[o + 39u] / SETUP_TILE;
    for (var row = r0; row < r1; row++) {
        let ty = piece.y + row;
        let run = row_run(o, ty, tx0, tx1);
        for (var tx = run.x; tx < run.y; tx++) {
            if (at < su.item_capacity) {
                out_items[at] = vec2<u32>(piece.x, (ty << 16u) | tx);
            }
            at += 1u;
        }
    }
}

// Workgroups of 64 for `invocations` as (x, y) with x ≤ 65535 (oit-gpu's `dispatch_size`; its
// `raster_args` writes these arguments for a frame set up on the host).
fn write_dispatch(at: u32, groups: u32) {
    if (groups <= 65535u) {
        args[at] = groups;
        args[at + 1u] = 1u;
    } else {
        args[at] = 65535u;
        args[at + 1u] = (groups + 65534u) / 65535u;
    }
    args[at + 2u] = 1u;
    args[at + 3u] = 0u;
}

@compute @workgroup_size(1)
fn setup_finish_main() {
    // the spread pieces' items join the count (past the capacity too: the host reads it); a
    // loop over each spread piece's count here, one invocation's 2048 loads one after another,
    // took 0.3 ms of an H100's frame on `cad`
    let spread = atomicLoad(&counters[3]);
    let items = min(atomicAdd(&counters[1], spread) + spread, su.item_capacity);
    // raster_main: a workgroup per item; raster_loop_main: an invocation per item
    write_dispatch(0u, items);
    write_dispatch(4u, (items + 63u) / 64u);
    args[8u] = items;
}
