// The per-pixel resolve of oit-cpu (crates/oit-cpu/src/resolve.rs) in WGSL: captured fragments
// are pushed nearest first (and, for dual depth peeling, farthest first from the back); `finish`
// turns the state into an sRGB8 pixel. Needs `fu: FrameUniform` and `state` bound by the includer.
//
// Ties (`fu.ties` = the plan's `count_ties`): as oit-cpu's `Run`, each sequence keeps the run of
// equal depth bits it ends in (last depth bits, last payload, and the run's length in bits 0..=30
// with bit 31 set once it holds two payloads); every fragment of a run with two payloads or more
// is counted in `tied`, and `state_tied` joins the front's and the back's last runs where they
// meet at one depth.

// All zeros is the state a pixel starts in (nothing captured, transmittance 1, Fresnel product
// 1), so a frame starts from a cleared buffer: the transmittance and the Fresnel product are kept
// as their bits XORed with 1.0's (`state_t`, `one_xor`), which gives back every value bit for bit.
// (A kernel that wrote this 92-byte struct a pixel took about 0.4 ms of a 1024² frame on an H100,
// a buffer clear of the same bytes a tenth of that.)
struct PixelState {
    fr: f32,
    fg: f32,
    fb: f32,
    transmittance_x: u32,
    br: f32,
    bg: f32,
    bb: f32,
    has_back: u32,
    captured: u32,
    fresnel_x: u32,
    or: f32,
    og: f32,
    ob: f32,
    entry_dist: f32,
    entry_rgba: u32,
    has_entry: u32,
    front_depth: u32,
    front_payload: u32,
    front_run: u32,
    back_depth: u32,
    back_payload: u32,
    back_run: u32,
    tied: u32,
}

// The state is kept field by field in `state` (prelude.wgsl): a plane of `fu.pixel_count` words a
// field, in the struct's order (`oit_gpu::STATE_WORDS` planes), so that a kernel's neighbouring
// invocations, neighbouring pixels, read and write neighbouring words. Kept a struct a pixel (92
// bytes apart), each field's load or store by a group of invocations touched as many memory
// sectors as invocations: on an H100 the planes took wavg's walled 1024² frame from 1.65 to 1.32
// ms of GPU time and every compute-path frame measured down by 0.1-0.3 ms
// (bench/results/h100/count-draw-soa-1024); on lavapipe, whose invocations are CPU lanes, they
// cost about a tenth of a hardware-path frame at 512² (bench/results/cpu-lavapipe/count-draw-soa-512).
fn load_state(px: u32) -> PixelState {
    let n = fu.pixel_count;
    var s: PixelState;
    s.fr = bitcast<f32>(state[px]);
    s.fg = bitcast<f32>(state[1u * n + px]);
    s.fb = bitcast<f32>(state[2u * n + px]);
    s.transmittance_x = state[3u * n + px];
    s.br = bitcast<f32>(state[4u * n + px]);
    s.bg = bitcast<f32>(state[5u * n + px]);
    s.bb = bitcast<f32>(state[6u * n + px]);
    s.has_back = state[7u * n + px];
    s.captured = state[8u * n + px];
    s.fresnel_x = state[9u * n + px];
    s.or = bitcast<f32>(state[10u * n + px]);
    s.og = bitcast<f32>(state[11u * n + px]);
    s.ob = bitcast<f32>(state[12u * n + px]);
    s.entry_dist = bitcast<f32>(state[13u * n + px]);
    s.entry_rgba = state[14u * n + px];
    s.has_entry = state[15u * n + px];
    s.front_depth = state[16u * n + px];
    s.front_payload = state[17u * n + px];
    s.front_run = state[18u * n + px];
    s.back_depth = state[19u * n + px];
    s.back_payload = state[20u * n + px];
    s.back_run = state[21u * n + px];
    s.tied = state[22u * n + px];
    return s;
}

// Writes pixel `px`'s state (`load_state`'s planes).
fn store_state(px: u32, s: PixelState) {
    let n = fu.pixel_count;
    state[px] = bitcast<u32>(s.fr);
    state[1u * n + px] = bitcast<u32>(s.fg);
    state[2u * n + px] = bitcast<u32>(s.fb);
    state[3u * n + px] = s.transmittance_x;
    state[4u * n + px] = bitcast<u32>(s.br);
    state[5u * n + px] = bitcast<u32>(s.bg);
    state[6u * n + px] = bitcast<u32>(s.bb);
    state[7u * n + px] = s.has_back;
    state[8u * n + px] = s.captured;
    state[9u * n + px] = s.fresnel_x;
    state[10u * n + px] = bitcast<u32>(s.or);
    state[11u * n + px] = bitcast<u32>(s.og);
    state[12u * n + px] = bitcast<u32>(s.ob);
    state[13u * n + px] = bitcast<u32>(s.entry_dist);
    state[14u * n + px] = s.entry_rgba;
    state[15u * n + px] = s.has_entry;
    state[16u * n + px] = s.front_depth;
    state[17u * n + px] = s.front_payload;
    state[18u * n + px] = s.front_run;
    state[19u * n + px] = s.back_depth;
    state[20u * n + px] = s.back_payload;
    state[21u * n + px] = s.back_run;
    state[22u * n + px] = s.tied;
}

const RUN_MIXED: u32 = 0x80000000u;
const RUN_LEN: u32 = 0x7fffffffu;

// Extends a run (depth bits, payload, length | mixed) with a fragment; returns the fragments that
// makes tied (oit-cpu's `Run::push`).
fn run_push(depth: ptr<function, u32>, payload: ptr<function, u32>, run: ptr<function, u32>, d: u32, p: u32) -> u32 {
    var tied = 0u;
    if (((*run) & RUN_LEN) > 0u && *depth == d) {
        *run += 1u;
        if (((*run) & RUN_MIXED) != 0u) {
            tied = 1u;
        } else if (*payload != p) {
            *run |= RUN_MIXED;
            tied = (*run) & RUN_LEN;
        }
    } else {
        *run = 1u;
    }
    *depth = d;
    *payload = p;
    return tied;
}

fn run_counted(run: u32) -> u32 {
    if ((run & RUN_MIXED) != 0u) {
        return run & RUN_LEN;
    }
    return 0u;
}

// Fragments counted tied, the join of the front and back sequences included (oit-cpu's
// `PixelState::tied`).
fn state_tied(s: PixelState) -> u32 {
    if ((s.front_run & RUN_LEN) == 0u || (s.back_run & RUN_LEN) == 0u || s.front_depth != s.back_depth) {
        return s.tied;
    }
    var joined = 0u;
    if (((s.front_run | s.back_run) & RUN_MIXED) != 0u || s.front_payload != s.back_payload) {
        joined = (s.front_run & RUN_LEN) + (s.back_run & RUN_LEN);
    }
    return s.tied - run_counted(s.front_run) - run_counted(s.back_run) + joined;
}

// `has_back` of a state whose pixel was composited by its technique's resolve (the multisampled
// resolve, coverage.wgsl): its colour is (br, bg, bb), which `finish_color` returns as it is.
const STATE_RESOLVED: u32 = 2u;

// Sets a state's colour to `c`, composited (`STATE_RESOLVED`).
fn state_resolved(s: ptr<function, PixelState>, c: vec3<f32>) {
    (*s).br = c.x;
    (*s).bg = c.y;
    (*s).bb = c.z;
    (*s).has_back = STATE_RESOLVED;
}

const ONE_BITS: u32 = 0x3f800000u;

// A state's transmittance and Fresnel product, and what stores them (`PixelState`).
fn state_t(s: PixelState) -> f32 {
    return bitcast<f32>(s.transmittance_x ^ ONE_BITS);
}

fn state_fresnel(s: PixelState) -> f32 {
    return bitcast<f32>(s.fresnel_x ^ ONE_BITS);
}

fn one_xor(v: f32) -> u32 {
    return bitcast<u32>(v) ^ ONE_BITS;
}

// Sets a pixel's state to a colour composited in one go (the weighted techniques: wavg, wsum,
// wboit, mboit): its front colour, nothing behind it, `count` fragments captured.
fn state_composited(px: u32, c: vec3<f32>, count: u32) {
    // the five planes it sets (`store_state`'s), the others left as they are
    let n = fu.pixel_count;
    state[px] = bitcast<u32>(c.x);
    state[1u * n + px] = bitcast<u32>(c.y);
    state[2u * n + px] = bitcast<u32>(c.z);
    state[3u * n + px] = one_xor(0.0);
    state[8u * n + px] = count;
}

// oit_core::Camera::linear_depth: n·f / (f − d(f − n)) without the product n·f, which is 0 or
// infinite in f32 for a scene at 1e-20 or 1e20.
fn linear_depth(d: f32) -> f32 {
    let n = fu.lens.x;
    let f = fu.lens.y;
    return n / (1.0 - d * (1.0 - n / f));
}

// Pushes one layer into the state a caller keeps in a local (one load and one store for a whole
// list: `fabs`'s resolve).
fn push_local(s: ptr<function, PixelState>, depth: f32, payload: u32) {
    (*s).captured += 1u;
    if (fu.ties != 0u) {
        var d = (*s).front_depth;
        var p = (*s).front_payload;
        var r = (*s).front_run;
        (*s).tied += run_push(&d, &p, &r, bitcast<u32>(depth), payload);
        (*s).front_depth = d;
        (*s).front_payload = p;
        (*s).front_run = r;
    }
    if (fu.effect == EFFECT_TRANSPARENCY) {
        let c = unpack_rgba8(payload);
        let add = state_t(*s) * c.w * c.xyz;
        (*s).fr += add.x;
        (*s).fg += add.y;
        (*s).fb += add.z;
        (*s).transmittance_x = one_xor(state_t(*s) * (1.0 - c.w));
    } else if (fu.effect == EFFECT_FRESNEL) {
        let n = unpack_normal(payload);
        (*s).fresnel_x = one_xor(state_fresnel(*s) * schlick_transmittance(dot(n, fu.forward.xyz)));
    } else if (fu.effect == EFFECT_TRANSLUCENCY) {
        let dist = linear_depth(depth);
        if ((*s).has_entry == 0u) {
            (*s).has_entry = 1u;
            (*s).entry_dist = dist;
            (*s).entry_rgba = payload;
        } else {
            (*s).has_entry = 0u;
            let c = unpack_rgba8((*s).entry_rgba);
            let absorb = (vec3<f32>(1.0) - c.xyz) * fu.lens.z;
            let o = absorb * max(dist - (*s).entry_dist, 0.0);
            (*s).or += o.x;
            (*s).og += o.y;
            (*s).ob += o.z;
        }
    }
}

fn push(px: u32, depth: f32, payload: u32) {
    var s = load_state(px);
    push_local(&s, depth, payload);
    store_state(px, s);
}

// Dual depth peeling's back half (transparency only): over-blend in front of what is behind.
fn push_back(px: u32, depth: f32, payload: u32) {
    var s = load_state(px);
    s.captured += 1u;
    if (fu.ties != 0u) {
        var d = s.back_depth;
        var p = s.back_payload;
        var r = s.back_run;
        s.tied += run_push(&d, &p, &r, bitcast<u32>(depth), payload);
        s.back_depth = d;
        s.back_payload = p;
        s.back_run = r;
    }
    let c = unpack_rgba8(payload);
    var back = background_at(px);
    if (s.has_back != 0u) {
        back = vec3<f32>(s.br, s.bg, s.bb);
    }
    back = c.w * c.xyz + (1.0 - c.w) * back;
    s.br = back.x;
    s.bg = back.y;
    s.bb = back.z;
    s.has_back = 1u;
    store_state(px, s);
}

fn heat(t_in: f32) -> vec3<f32> {
    var stops = array<vec3<f32>, 5>(
        vec3<f32>(0.0, 0.0, 0.0),
        vec3<f32>(0.05, 0.1, 0.6),
        vec3<f32>(0.6, 0.05, 0.5),
        vec3<f32>(1.0, 0.5, 0.05),
        vec3<f32>(1.0, 1.0, 1.0),
    );
    var t = t_in;
    if (!(t >= 0.0)) {
        t = 0.0;
    }
    t = min(t, 1.0) * 4.0;
    let i = min(u32(floor(t)), 3u);
    return mix(stops[i], stops[i + 1u], t - f32(i));
}

// A state's final linear colour over `bg` (the pixel's `background_at`) under the effects that
// composite (oit-cpu's `Resolve::finish_over`); `bg` under the complexity effect.
fn finish_over(s: PixelState, bg: vec3<f32>) -> vec3<f32> {
    if (fu.effect == EFFECT_TRANSPARENCY) {
        var back = bg;
        if (s.has_back != 0u) {
            back = vec3<f32>(s.br, s.bg, s.bb);
        }
        return vec3<f32>(s.fr, s.fg, s.fb) + state_t(s) * back;
    } else if (fu.effect == EFFECT_FRESNEL) {
        return bg * state_fresnel(s);
    } else if (fu.effect == EFFECT_TRANSLUCENCY) {
        return bg * exp(-vec3<f32>(s.or, s.og, s.ob));
    }
    return bg;
}

// The final linear colour; `max_captured` scales the heat map.
fn finish_color(px: u32, max_captured: u32) -> vec3<f32> {
    return finish_color_of(px, load_state(px), max_captured);
}

// `finish_color` of pixel `px` whose state `s` is at hand.
fn finish_color_of(px: u32, s: PixelState, max_captured: u32) -> vec3<f32> {
    if (s.has_back == STATE_RESOLVED) {
        return vec3<f32>(s.br, s.bg, s.bb);
    }
    let bg = background_at(px);
    if (fu.effect != EFFECT_COMPLEXITY) {
        return finish_over(s, bg);
    }
    if (s.captured == 0u) {
        return bg;
    }
    return heat(f32(s.captured) / f32(max(max_captured, 1u)));
}

fn srgb_pixel(c: vec3<f32>) -> u32 {
    return linear_to_srgb8(c.x) | (linear_to_srgb8(c.y) << 8u) | (linear_to_srgb8(c.z) << 16u) | (255u << 24u);
}
