// f32 arithmetic on bit patterns (u32), exactly as an x86_64 host computes it: round to nearest
// even, subnormals kept, infinities, and NaNs as SSE gives them (a NaN operand comes back quieted,
// the first one when both are; an invalid operation gives the default NaN 0xffc00000). A port of
// Berkeley SoftFloat 3e's f32_add, f32_sub, f32_mul, f32_div and ui64_to_f32 (8086-SSE
// specialization), line for line.
//
// Why: the compute path's setup (setup.wgsl) must give oit-core's setup bit for bit, and a
// shader's float hardware does not promise that. Vulkan's add, sub and mul are correctly rounded,
// but the driver may contract a*b+c into a fused multiply-add (naga emits no NoContraction),
// division is only within 2.5 ULP, and f32 subnormals may be flushed to zero by any of them. One
// ULP in a clip coordinate moves a snapped coordinate often, so the setup does every float
// operation here, in integers, and its float hardware is never asked.

const SF_DEFAULT_NAN: u32 = 0xffc00000u;
const SF_ONE: u32 = 0x3f800000u;
const SF_HALF: u32 = 0x3f000000u;

struct SfNorm {
    exp: i32,
    sig: u32,
}

fn sf_is_nan(a: u32) -> bool {
    return (a & 0x7fffffffu) > 0x7f800000u;
}

fn sf_is_finite(a: u32) -> bool {
    return (a & 0x7f800000u) != 0x7f800000u;
}

// a >= 0.0 as Rust evaluates it (−0 is ≥ 0; NaN is not).
fn sf_ge0(a: u32) -> bool {
    return !sf_is_nan(a) && ((a >> 31u) == 0u || (a & 0x7fffffffu) == 0u);
}

// a < 0.0 as Rust evaluates it.
fn sf_lt0(a: u32) -> bool {
    return !sf_is_nan(a) && (a >> 31u) != 0u && (a & 0x7fffffffu) != 0u;
}

fn sf_propagate_nan(a: u32, b: u32) -> u32 {
    return select(b, a, sf_is_nan(a)) | 0x00400000u;
}

// SoftFloat's packToF32UI: an add, so that a significand carrying into bit 23 raises the exponent.
fn sf_pack(sign: u32, exp: i32, sig: u32) -> u32 {
    return (sign << 31u) + (u32(exp) << 23u) + sig;
}

fn sf_shift_right_jam32(a: u32, dist: u32) -> u32 {
    if (dist < 31u) {
        return (a >> dist) | select(0u, 1u, (a << ((32u - dist) & 31u)) != 0u);
    }
    return select(0u, 1u, a != 0u);
}

fn sf_norm_subnormal(sig: u32) -> SfNorm {
    let shift = i32(countLeadingZeros(sig)) - 8;
    return SfNorm(1 - shift, sig << u32(shift));
}

// softfloat_roundPackToF32, round to nearest even: `sig` has its leading bit at bit 30 (or below
// for a subnormal result) and 7 bits below the result's last.
fn sf_round_pack(sign: u32, exp_in: i32, sig_in: u32) -> u32 {
    var exp = exp_in;
    var sig = sig_in;
    var round_bits = sig & 0x7fu;
    if (u32(exp) >= 0xfdu) {
        if (exp < 0) {
            sig = sf_shift_right_jam32(sig, u32(-exp));
            exp = 0;
            round_bits = sig & 0x7fu;
        } else if (exp > 0xfd || sig + 0x40u >= 0x80000000u) {
            return sf_pack(sign, 0xff, 0u);
        }
    }
    sig = (sig + 0x40u) >> 7u;
    if (round_bits == 0x40u) {
        sig = sig & ~1u;
    }
    if (sig == 0u) {
        exp = 0;
    }
    return sf_pack(sign, exp, sig);
}

fn sf_norm_round_pack(sign: u32, exp: i32, sig: u32) -> u32 {
    let shift = i32(countLeadingZeros(sig)) - 1;
    let e = exp - shift;
    if (shift >= 7 && u32(e) < 0xfdu) {
        return sf_pack(sign, select(0, e, sig != 0u), sig << u32(shift - 7));
    }
    return sf_round_pack(sign, e, sig << u32(shift));
}

fn sf_add_mags(a: u32, b: u32) -> u32 {
    let ea = i32((a >> 23u) & 0xffu);
    var ma = a & 0x7fffffu;
    let eb = i32((b >> 23u) & 0xffu);
    var mb = b & 0x7fffffu;
    let diff = ea - eb;
    let sign = a >> 31u;
    var ez: i32;
    var sz: u32;
    if (diff == 0) {
        if (ea == 0) {
            return a + mb;
        }
        if (ea == 0xff) {
            if ((ma | mb) != 0u) {
                return sf_propagate_nan(a, b);
            }
            return a;
        }
        ez = ea;
        sz = 0x01000000u + ma + mb;
        if ((sz & 1u) == 0u && ez < 0xfe) {
            return sf_pack(sign, ez, sz >> 1u);
        }
        sz = sz << 6u;
    } else {
        ma = ma << 6u;
        mb = mb << 6u;
        if (diff < 0) {
            if (eb == 0xff) {
                if (mb != 0u) {
                    return sf_propagate_nan(a, b);
                }
                return sf_pack(sign, 0xff, 0u);
            }
            ez = eb;
            ma = ma + select(ma, 0x20000000u, ea != 0);
            ma = sf_shift_right_jam32(ma, u32(-diff));
        } else {
            if (ea == 0xff) {
                if (ma != 0u) {
                    return sf_propagate_nan(a, b);
                }
                return a;
            }
            ez = ea;
            mb = mb + select(mb, 0x20000000u, eb != 0);
            mb = sf_shift_right_jam32(mb, u32(diff));
        }
        sz = 0x20000000u + ma + mb;
        if (sz < 0x40000000u) {
            ez = ez - 1;
            sz = sz << 1u;
        }
    }
    return sf_round_pack(sign, ez, sz);
}

fn sf_sub_mags(a: u32, b: u32) -> u32 {
    var ea = i32((a >> 23u) & 0xffu);
    var ma = a & 0x7fffffu;
    let eb = i32((b >> 23u) & 0xffu);
    var mb = b & 0x7fffffu;
    let diff = ea - eb;
    var sign = a >> 31u;
    if (diff == 0) {
        if (ea == 0xff) {
            if ((ma | mb) != 0u) {
                return sf_propagate_nan(a, b);
            }
            return SF_DEFAULT_NAN;
        }
        var sd = i32(ma) - i32(mb);
        if (sd == 0) {
            return 0u;
        }
        if (ea != 0) {
            ea = ea - 1;
        }
        if (sd < 0) {
            sign = sign ^ 1u;
            sd = -sd;
        }
        var shift = i32(countLeadingZeros(u32(sd))) - 8;
        var ez = ea - shift;
        if (ez < 0) {
            shift = ea;
            ez = 0;
        }
        return sf_pack(sign, ez, u32(sd) << u32(shift));
    }
    ma = ma << 7u;
    mb = mb << 7u;
    var ez: i32;
    var sx: u32;
    var sy: u32;
    var d = diff;
    if (diff < 0) {
        sign = sign ^ 1u;
        if (eb == 0xff) {
            if (mb != 0u) {
                return sf_propagate_nan(a, b);
            }
            return sf_pack(sign, 0xff, 0u);
        }
        ez = eb - 1;
        sx = mb | 0x40000000u;
        sy = ma + select(ma, 0x40000000u, ea != 0);
        d = -diff;
    } else {
        if (ea == 0xff) {
            if (ma != 0u) {
                return sf_propagate_nan(a, b);
            }
            return a;
        }
        ez = ea - 1;
        sx = ma | 0x40000000u;
        sy = mb + select(mb, 0x40000000u, eb != 0);
    }
    return sf_norm_round_pack(sign, ez, sx - sf_shift_right_jam32(sy, u32(d)));
}

// a + b
fn sf_add(a: u32, b: u32) -> u32 {
    if (((a ^ b) >> 31u) != 0u) {
        return sf_sub_mags(a, b);
    }
    return sf_add_mags(a, b);
}

// a - b
fn sf_sub(a: u32, b: u32) -> u32 {
    if (((a ^ b) >> 31u) != 0u) {
        return sf_add_mags(a, b);
    }
    return sf_sub_mags(a, b);
}

// a * b
fn sf_mul(a: u32, b: u32) -> u32 {
    let sign = (a ^ b) >> 31u;
    var ea = i32((a >> 23u) & 0xffu);
    var ma = a & 0x7fffffu;
    var eb = i32((b >> 23u) & 0xffu);
    var mb = b & 0x7fffffu;
    if (ea == 0xff) {
        if (ma != 0u || (eb == 0xff && mb != 0u)) {
            return sf_propagate_nan(a, b);
        }
        if ((u32(eb) | mb) == 0u) {
            return SF_DEFAULT_NAN;
        }
        return sf_pack(sign, 0xff, 0u);
    }
    if (eb == 0xff) {
        if (mb != 0u) {
            return sf_propagate_nan(a, b);
        }
        if ((u32(ea) | ma) == 0u) {
            return SF_DEFAULT_NAN;
        }
        return sf_pack(sign, 0xff, 0u);
    }
    if (ea == 0) {
        if (ma == 0u) {
            return sign << 31u;
        }
        let n = sf_norm_subnormal(ma);
        ea = n.exp;
        ma = n.sig;
    }
    if (eb == 0) {
        if (mb == 0u) {
            return sign << 31u;
        }
        let n = sf_norm_subnormal(mb);
        eb = n.exp;
        mb = n.sig;
    }
    var ez = ea + eb - 0x7f;
    let sa = (ma | 0x00800000u) << 7u;
    let sb = (mb | 0x00800000u) << 8u;
    let prod = u64(sa) * u64(sb);
    var sz = u32(prod >> 32u) | select(0u, 1u, (prod & 0xfffffffflu) != 0lu);
    if (sz < 0x40000000u) {
        ez = ez - 1;
        sz = sz << 1u;
    }
    return sf_round_pack(sign, ez, sz);
}

// a / b
fn sf_div(a: u32, b: u32) -> u32 {
    let sign = (a ^ b) >> 31u;
    var ea = i32((a >> 23u) & 0xffu);
    var ma = a & 0x7fffffu;
    var eb = i32((b >> 23u) & 0xffu);
    var mb = b & 0x7fffffu;
    if (ea == 0xff) {
        if (ma != 0u) {
            return sf_propagate_nan(a, b);
        }
        if (eb == 0xff) {
            if (mb != 0u) {
                return sf_propagate_nan(a, b);
            }
            return SF_DEFAULT_NAN;
        }
        return sf_pack(sign, 0xff, 0u);
    }
    if (eb == 0xff) {
        if (mb != 0u) {
            return sf_propagate_nan(a, b);
        }
        return sign << 31u;
    }
    if (eb == 0) {
        if (mb == 0u) {
            if ((u32(ea) | ma) == 0u) {
                return SF_DEFAULT_NAN;
            }
            return sf_pack(sign, 0xff, 0u);
        }
        let n = sf_norm_subnormal(mb);
        eb = n.exp;
        mb = n.sig;
    }
    if (ea == 0) {
        if (ma == 0u) {
            return sign << 31u;
        }
        let n = sf_norm_subnormal(ma);
        ea = n.exp;
        ma = n.sig;
    }
    var ez = ea - eb + 0x7e;
    let sa = ma | 0x00800000u;
    let sb = mb | 0x00800000u;
    var wide: u64;
    if (sa < sb) {
        ez = ez - 1;
        wide = u64(sa) << 31u;
    } else {
        wide = u64(sa) << 30u;
    }
    var sz = u32(wide / u64(sb));
    if ((sz & 0x3fu) == 0u) {
        sz = sz | select(0u, 1u, u64(sb) * u64(sz) != wide);
    }
    return sf_round_pack(sign, ez, sz);
}

// `a as f32` for a u64, rounded to nearest even (ui64_to_f32).
fn sf_from_u64(a: u64) -> u32 {
    if (a == 0lu) {
        return 0u;
    }
    let hi = u32(a >> 32u);
    let lz = select(32u + countLeadingZeros(u32(a & 0xfffffffflu)), countLeadingZeros(hi), hi != 0u);
    var shift = i32(lz) - 40;
    if (shift >= 0) {
        return sf_pack(0u, 0x95 - shift, u32(a << u32(shift)));
    }
    shift = shift + 7;
    var sig: u32;
    if (shift < 0) {
        let d = u32(-shift);
        sig = u32(a >> d) | select(0u, 1u, (a & ((1lu << d) - 1lu)) != 0lu);
    } else {
        sig = u32(a << u32(shift));
    }
    return sf_round_pack(0u, 0x9c - shift, sig);
}

// f32::floor.
fn sf_floor(a: u32) -> u32 {
    let e = i32((a >> 23u) & 0xffu);
    if (e >= 150) {
        return a;
    }
    if (e < 127) {
        if ((a & 0x7fffffffu) == 0u) {
            return a;
        }
        // −1 below zero, +0 above, as a product: lavapipe turned both a `select` and an `if` of
        // the two constants into −0 for positive `a`
        return (a >> 31u) * 0xbf800000u;
    }
    let mask = (1u << u32(150 - e)) - 1u;
    if ((a & mask) == 0u) {
        return a;
    }
    if ((a >> 31u) != 0u) {
        return (a | mask) + 1u;
    }
    return a & ~mask;
}

// `a as i32` for an integral a with |a| ≤ 2^30.
fn sf_to_i32(a: u32) -> i32 {
    let e = i32((a >> 23u) & 0xffu);
    if (e < 127) {
        return 0;
    }
    let m = (a & 0x7fffffu) | 0x800000u;
    var v: u32;
    if (e >= 150) {
        v = m << u32(e - 150);
    } else {
        v = m >> u32(150 - e);
    }
    return select(i32(v), -i32(v), (a >> 31u) != 0u);
}
