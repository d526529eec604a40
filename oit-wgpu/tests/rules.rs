//! oit-core's rules and their WGSL twins (oit-shaders' wgsl/core/common.wgsl) on the same edge values:
//! d = 0, d = 1, −0, NaN, beyond [0, 1], zNear = zFar, alpha 0 and 255, every alpha for the bdp
//! packing; the bucket midpoint and eq. 5 at and around their boundaries. Integer results must be equal; sRGB encoding may differ by one step (pow differs).

use oit_core::composite::linear_to_srgb8;
use oit_core::rules::*;
use oit_core::technique::wboit::{WBOIT_OPTICAL_DEPTH, wboit_weight};

const KERNEL: &str = r#"
@group(0) @binding(0) var<storage, read_write> cases: array<vec4<u32>>;
@group(0) @binding(1) var<storage, read_write> results: array<vec2<u32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i >= arrayLength(&cases)) {
        return;
    }
    let c = cases[i];
    let a = bitcast<f32>(c.y);
    let b = bitcast<f32>(c.z);
    let d = bitcast<f32>(c.w);
    var r = vec2<u32>(0u, 0u);
    switch c.x {
        case 0u: { r.x = depth_bits(a); }
        case 1u: { r.x = bucket_index(a, b, d, 16u); r.y = bucket_index(a, b, d, 32u); }
        case 2u: { r.x = histogram_bin(a, b, d); }
        case 3u: { r.x = bdp_pack_color(c.y); r.y = bdp_unpack_color(bdp_pack_color(c.y)); }
        case 4u: { r = mdts_pack(a, c.z); }
        case 5u: { r.x = pack_rgba8(vec4<f32>(a, b, d, a)); }
        case 6u: { r.x = pack_normal(vec3<f32>(a, b, d)); }
        case 7u: { r.x = linear_to_srgb8(a); }
        case 8u: { r = mdts_unpack(vec2<u32>(c.y, c.z)); }
        case 9u: { r.x = bitcast<u32>(bucket_midpoint(c.y, 32u, b, d)); r.y = bitcast<u32>(bucket_midpoint(c.y, 16u, b, d)); }
        case 10u: {
            let lo = (u64(c.z) << 32u) | 0x1234lu;
            let hi = (u64(c.w) << 32u) | 0x5678lu;
            r.x = u32(bdp_eq5_next(c.y, lo, hi));
            r.y = u32(bdp_eq5_next(c.y, BDP_EMPTY_MIN, hi));
        }
        default: {}
    }
    results[i] = r;
}
"#;

/// Runs `main` of `kernel` over `invocations`: bindings 0.. are storage buffers holding `inputs`
/// (read-write, so a kernel may bind atomics), the last one `out_words` u32 results, read back.
fn run_kernel(
    gpu: &oit_wgpu::Gpu,
    kernel: &str,
    inputs: &[&[u8]],
    out_words: usize,
    invocations: u32,
) -> Vec<u32> {
    use wgpu::util::DeviceExt;
    let device = &gpu.device;
    let mut buffers: Vec<wgpu::Buffer> = inputs
        .iter()
        .map(|contents| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("input"),
                contents,
                usage: wgpu::BufferUsages::STORAGE,
            })
        })
        .collect();
    buffers.push(device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("results"),
        size: (out_words * 4) as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    }));
    let entries: Vec<wgpu::BindGroupLayoutEntry> = (0..buffers.len() as u32)
        .map(|binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: false },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        })
        .collect();
    let layout =
        device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: None, entries: &entries });
    let pipeline = gpu.compute_pipeline(kernel, "main", &[&layout]).expect("kernel builds");
    let bound: Vec<wgpu::BindGroupEntry<'_>> = buffers
        .iter()
        .enumerate()
        .map(|(i, b)| wgpu::BindGroupEntry { binding: i as u32, resource: b.as_entire_binding() })
        .collect();
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &layout,
        entries: &bound,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(invocations.div_ceil(64), 1, 1);
    }
    gpu.queue.submit([encoder.finish()]);
    gpu.read_u32(buffers.last().expect("the results buffer")).unwrap()
}

fn f(x: f32) -> u32 {
    x.to_bits()
}

#[test]
fn wgsl_rules_equal_rust_rules() {
    let Some(backend) = oit_wgpu::backend_or_skip("wgsl_rules_equal_rust_rules") else { return };
    let gpu = backend.gpu().expect("opened by backend_or_skip");
    let depths =
        [0.0f32, -0.0, 1.0, 1.000_000_1, -1.0, f32::NAN, 0.5, 1e-30, f32::INFINITY, 0.999_999_9, 0.3];
    let mut cases: Vec<[u32; 4]> = Vec::new();
    let mut expected: Vec<[u32; 2]> = Vec::new();
    // the bucket midpoint for every k at both bucket counts, on ranges that include a point range
    for k in [0u32, 1, 15, 31] {
        for (zn, zf) in [(0.0f32, 1.0f32), (0.25, 0.75), (0.5, 0.5), (0.1, 0.100_000_1)] {
            cases.push([9, k, f(zn), f(zf)]);
            expected.push([f(bucket_midpoint(k, 32, zn, zf)), f(bucket_midpoint(k, 16, zn, zf))]);
        }
    }
    // eq. 5 on either side of, and at, the previous pass's min and max depths
    for (lo, hi) in [(f(0.25), f(0.75)), (f(0.5), f(0.5)), (0, u32::MAX), (f(0.3), f(0.300_000_04))] {
        for d in [lo.wrapping_sub(1), lo, lo.wrapping_add(1), hi.wrapping_sub(1), hi, hi.wrapping_add(1)] {
            let (lo_key, hi_key) = (u64::from(lo) << 32 | 0x1234, u64::from(hi) << 32 | 0x5678);
            cases.push([10, d, lo, hi]);
            expected.push([
                u32::from(bdp_eq5_next(d, lo_key, hi_key)),
                u32::from(bdp_eq5_next(d, BDP_EMPTY_MIN, hi_key)),
            ]);
        }
    }
    for &d in &depths {
        cases.push([0, f(d), 0, 0]);
        expected.push([depth_bits(d), 0]);
        for (zn, zf) in [(0.0f32, 1.0f32), (0.25, 0.75), (0.5, 0.5), (0.6, 0.4), (0.0, 0.0), (1.0, 1.0)] {
            cases.push([1, f(d), f(zn), f(zf)]);
            expected.push([bucket_index(d, zn, zf, 16), bucket_index(d, zn, zf, 32)]);
            cases.push([2, f(d), f(zn), f(zf)]);
            expected.push([histogram_bin(d, zn, zf), 0]);
        }
        for rgba in [0u32, 0xffff_ffff, 0x7f12_3456, 0x00ff_ffff, 0xff00_0000] {
            cases.push([4, f(d), rgba, 0]);
            expected.push(mdts_pack(d, rgba));
            let words = mdts_pack(d, rgba);
            cases.push([8, words[0], words[1], 0]);
            let (dd, rgb) = mdts_unpack(words);
            expected.push([dd.to_bits(), rgb]);
        }
    }
    for a in 0..=255u32 {
        for rgb in [0u32, 0xffffff, 0x80_7f01] {
            let c = a << 24 | rgb;
            cases.push([3, c, 0, 0]);
            expected.push([bdp_pack_color(c), bdp_unpack_color(bdp_pack_color(c))]);
        }
    }
    for x in [0.0f32, 1.0, 0.5, 1.0 / 255.0, 0.5 / 255.0, 254.5 / 255.0, -0.2, 1.7] {
        for y in [0.0f32, 0.25, 1.0] {
            cases.push([5, f(x), f(y), f(1.0 - x)]);
            expected.push([pack_rgba8(glam::Vec4::new(x, y, 1.0 - x, x)), 0]);
        }
    }
    for n in [(0.0f32, 0.0f32, 1.0f32), (0.0, 0.0, -1.0), (1.0, 0.0, 0.0), (0.3, -0.5, -0.8), (0.0, 0.0, 0.0)]
    {
        cases.push([6, f(n.0), f(n.1), f(n.2)]);
        expected.push([pack_normal(glam::Vec3::new(n.0, n.1, n.2)), 0]);
    }
    let srgb_start = cases.len();
    for x in [0.0f32, 1.0, 0.5, 0.003_130_8, 0.2, -1.0, f32::NAN, 2.0] {
        cases.push([7, f(x), 0, 0]);
        expected.push([u32::from(linear_to_srgb8(x)), 0]);
    }

    let got = run_kernel(gpu, KERNEL, &[bytemuck::cast_slice(&cases)], cases.len() * 2, cases.len() as u32);
    for (i, (case, want)) in cases.iter().zip(&expected).enumerate() {
        let have = [got[2 * i], got[2 * i + 1]];
        if i >= srgb_start {
            assert!(
                have[0].abs_diff(want[0]) <= 1,
                "sRGB of {}: wgsl {} rust {}",
                f32::from_bits(case[1]),
                have[0],
                want[0]
            );
        } else {
            assert_eq!(have, *want, "case {i}: kind {} inputs {:?}", case[0], &case[1..]);
        }
    }
}

/// adp's bucket routing: `adp_rank` of `src/technique/adp.wgsl` (the text itself, cut from the
/// file) against `oit_core::rules::histogram_rank`, on histograms whose set bits sit at word
/// boundaries (bins 0, 31, 32, 1023), on the empty and the full histogram, and on a scatter.
#[test]
fn wgsl_histogram_rank_equals_rust() {
    let Some(backend) = oit_wgpu::backend_or_skip("wgsl_histogram_rank_equals_rust") else { return };
    let gpu = backend.gpu().expect("opened by backend_or_skip");
    let adp = oit_shaders::text("technique/adp.wgsl");
    let start = adp.find("fn adp_rank(").expect("adp.wgsl defines adp_rank");
    let end = start + adp[start..].find("\n}\n").expect("adp_rank ends") + 3;
    let kernel = format!(
        "@group(0) @binding(0) var<storage, read_write> hist: array<atomic<u32>>;
@group(0) @binding(1) var<storage, read_write> cases: array<vec2<u32>>;
@group(0) @binding(2) var<storage, read_write> results: array<u32>;
{}
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {{
    let i = gid.x;
    if (i >= arrayLength(&cases)) {{
        return;
    }}
    results[i] = adp_rank(cases[i].x, cases[i].y);
}}
",
        &adp[start..end]
    );
    let mut s = 0x9e37_79b9u32;
    let mut next = || {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        s
    };
    let mut hists: Vec<[u32; HISTOGRAM_WORDS]> = vec![[0; HISTOGRAM_WORDS], [u32::MAX; HISTOGRAM_WORDS]];
    let mut edges = [0u32; HISTOGRAM_WORDS];
    for bin in [0u32, 31, 32, 33, 511, 512, 1022, 1023] {
        edges[(bin / 32) as usize] |= 1 << (bin % 32);
    }
    hists.push(edges);
    hists.push(std::array::from_fn(|_| next()));
    hists.push(std::array::from_fn(|i| if i % 3 == 0 { next() & next() } else { 0 }));
    let bins = [0u32, 1, 30, 31, 32, 33, 63, 64, 511, 512, 513, 1000, 1022, 1023];
    let mut cases: Vec<[u32; 2]> = Vec::new();
    let mut expected = Vec::new();
    for (px, h) in hists.iter().enumerate() {
        for &bin in &bins {
            cases.push([px as u32, bin]);
            expected.push(histogram_rank(h, bin));
        }
    }
    let flat: Vec<u32> = hists.iter().flatten().copied().collect();
    let inputs: [&[u8]; 2] = [bytemuck::cast_slice(&flat), bytemuck::cast_slice(&cases)];
    let got = run_kernel(gpu, &kernel, &inputs, cases.len(), cases.len() as u32);
    for ((case, want), have) in cases.iter().zip(&expected).zip(&got) {
        assert_eq!(have, want, "histogram {} bin {}", case[0], case[1]);
    }
    // and the cases can tell ranks apart: the full histogram's rank is the bin itself
    assert_eq!(histogram_rank(&[u32::MAX; HISTOGRAM_WORDS], 1000), 1000);
}

/// wboit's per-fragment integers: `wboit_weight` of `wboit.wgsl` and the optical-depth table of
/// `wboit_table.wgsl` (the text itself, cut from the file) against `oit_core::technique::wboit::wboit_weight` and
/// `WBOIT_OPTICAL_DEPTH`, over every table entry and depths at and around the 10-bit steps, the
/// planes, −0, NaN and beyond [0, 1]. Fails when an entry of either table or the weight's formula
/// on either side is changed.
#[test]
fn wgsl_wboit_weight_and_table_equal_rust() {
    let Some(backend) = oit_wgpu::backend_or_skip("wgsl_wboit_weight_and_table_equal_rust") else { return };
    let gpu = backend.gpu().expect("opened by backend_or_skip");
    let wboit = oit_shaders::text("technique/wboit.wgsl");
    let table = oit_shaders::text("technique/wboit_table.wgsl");
    let cut = |text: &'static str, from: &str, to: &str| {
        let start = text.find(from).unwrap_or_else(|| panic!("wboit's WGSL has {from}"));
        let end = start + text[start..].find(to).unwrap_or_else(|| panic!("{from} ends")) + to.len();
        &text[start..end]
    };
    let kernel = format!(
        "@group(0) @binding(0) var<storage, read_write> depths: array<u32>;
@group(0) @binding(1) var<storage, read_write> results: array<u32>;
{}
{}
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {{
    let i = gid.x;
    if (i >= arrayLength(&depths)) {{
        return;
    }}
    let w = wboit_weight(bitcast<f32>(depths[i]));
    results[3u * i] = u32(w);
    results[3u * i + 1u] = u32(w >> 32u);
    results[3u * i + 2u] = WBOIT_OPTICAL_DEPTH[i & 255u];
}}
",
        cut(table, "const WBOIT_OPTICAL_DEPTH", "\n);\n"),
        cut(wboit, "fn wboit_weight(", "\n}\n")
    );
    let mut depths: Vec<f32> = (0..=1024).map(|i| i as f32 / 1024.0).collect();
    depths.extend((0..=1024).map(|i| (i as f32 / 1024.0 - 1e-7).max(0.0)));
    depths.extend([-0.0, -1.0, 2.0, f32::NAN, f32::INFINITY, 0.5, 0.999_999, 1e-30]);
    while !depths.len().is_multiple_of(256) {
        depths.push(0.25);
    }
    let bits: Vec<u32> = depths.iter().map(|d| d.to_bits()).collect();
    let got = run_kernel(gpu, &kernel, &[bytemuck::cast_slice(&bits)], bits.len() * 3, bits.len() as u32);
    for (i, d) in depths.iter().enumerate() {
        let w = u64::from(got[3 * i]) | u64::from(got[3 * i + 1]) << 32;
        assert_eq!(w, wboit_weight(*d), "weight at depth {d}");
        assert_eq!(got[3 * i + 2], WBOIT_OPTICAL_DEPTH[i & 255], "optical depth of alpha {}", i & 255);
    }
}

/// mboit's per-fragment arithmetic: `mboit_power` and `mboit_share_in_front` of `mboit.wgsl`
/// (the text itself, cut from the file) against `oit_core::technique::mboit::mboit_powers` and
/// `oit_core::technique::mboit::mboit_share_in_front`, on one- and two-atom moments and moments of
/// random depth sets, at depths across [−1, 1]. The powers must be equal; the share within 10⁻⁴
/// (a device may fuse the bound's multiply-adds, f32 rounding apart; one 16-bit transmittance
/// step is 1.5·10⁻⁵ of e⁻ˢ, so this allows a few). Fails when the bias, the overestimation, the
/// substitutions or the roots differ on one side, or the powers round differently.
#[test]
fn wgsl_mboit_bound_equals_rust() {
    use oit_core::technique::mboit::mboit_share_in_front;
    let Some(backend) = oit_wgpu::backend_or_skip("wgsl_mboit_bound_equals_rust") else { return };
    let gpu = backend.gpu().expect("opened by backend_or_skip");
    let mboit = oit_shaders::text("technique/mboit.wgsl");
    let cut = |from: &str, to: &str| {
        let start = mboit.find(from).unwrap_or_else(|| panic!("mboit.wgsl has {from}"));
        let end = start + mboit[start..].find(to).unwrap_or_else(|| panic!("{from} ends")) + to.len();
        &mboit[start..end]
    };
    let kernel = format!(
        "@group(0) @binding(0) var<storage, read_write> cases: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> depths: array<f32>;
@group(0) @binding(2) var<storage, read_write> results: array<u32>;
{}
{}
{}
{}
{}
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {{
    let i = gid.x;
    if (i >= arrayLength(&depths)) {{
        return;
    }}
    let z = depths[i];
    results[3u * i] = bitcast<u32>(mboit_share_in_front(cases[i], z));
    let p = mboit_power(z * z * z);
    results[3u * i + 1u] = u32(p & 0xffffffffli);
    results[3u * i + 2u] = u32(p >> 32u);
}}
",
        cut("const MBOIT_BIAS", ";\n"),
        cut("const MBOIT_OVERESTIMATION", ";\n"),
        cut("fn mboit_power(", "\n}\n"),
        cut("fn mboit_div(", "\n}\n"),
        cut("fn mboit_share_in_front(", "\n}\n"),
    );
    let moments = |zs: &[f32]| -> [f32; 4] {
        std::array::from_fn(|k| zs.iter().map(|z| z.powi(k as i32 + 1)).sum::<f32>() / zs.len() as f32)
    };
    let mut s = 0x2545_f491u32;
    let mut next = || {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        (s as f32 / u32::MAX as f32) * 2.0 - 1.0
    };
    let mut sets: Vec<Vec<f32>> = vec![vec![0.3], vec![-0.7], vec![-0.5, 0.5], vec![0.0, 0.0, 0.9]];
    for n in 2..10 {
        sets.push((0..n).map(|_| next()).collect());
    }
    let (mut cases, mut depths) = (Vec::new(), Vec::new());
    for set in &sets {
        for i in 0..=20 {
            cases.push(moments(set));
            depths.push(-1.0 + i as f32 / 10.0);
        }
    }
    let inputs: [&[u8]; 2] = [bytemuck::cast_slice(&cases), bytemuck::cast_slice(&depths)];
    let got = run_kernel(gpu, &kernel, &inputs, depths.len() * 3, depths.len() as u32);
    for (i, (m, z)) in cases.iter().zip(&depths).enumerate() {
        let share = f32::from_bits(got[3 * i]);
        let want = mboit_share_in_front(*m, *z);
        assert!((share - want).abs() <= 1e-4, "moments {m:?} at {z}: wgsl {share}, rust {want}");
        let p = i64::from(got[3 * i + 1]) | i64::from(got[3 * i + 2] as i32) << 32;
        assert_eq!(p, oit_core::technique::mboit::mboit_powers(*z)[2], "z³ at {z}");
    }
}

/// mboit:6's bound: `mboit6_share_in_front` and `mboit_cubic_roots` of `mboit.wgsl` (the text
/// itself) against `oit_core::technique::mboit::mboit6_share_in_front`, on one-, two- and three-atom
/// moments and moments of random depth sets (as mboit:4's above, at the same depths), and the
/// powers z⁵ and z⁶ as the capture forms them (z⁴·z, z³·z³) against `mboit_powers`. The powers
/// must be equal; the share within 10⁻³: the roots of the cubic go through `acos`, `cos` and a
/// cube root (`pow` in WGSL), each within a few ulps on a device but not the same ulps, and a
/// near-double root or a fragment near a root of the Hankel matrix's orthogonal cubic magnifies
/// an ulp (the f32 bound against itself in f64 differs by up to 1.1·10⁻³, oit-core's
/// `mboit6_f32_follows_f64`). Fails when the bias, its target, the factorization, the roots or
/// the interpolation differ on one side, or a power rounds differently.
#[test]
fn wgsl_mboit6_bound_equals_rust() {
    use oit_core::technique::mboit::mboit6_share_in_front;
    let Some(backend) = oit_wgpu::backend_or_skip("wgsl_mboit6_bound_equals_rust") else { return };
    let gpu = backend.gpu().expect("opened by backend_or_skip");
    let mboit = oit_shaders::text("technique/mboit.wgsl");
    let cut = |from: &str, to: &str| {
        let start = mboit.find(from).unwrap_or_else(|| panic!("mboit.wgsl has {from}"));
        let end = start + mboit[start..].find(to).unwrap_or_else(|| panic!("{from} ends")) + to.len();
        &mboit[start..end]
    };
    let kernel = format!(
        "@group(0) @binding(0) var<storage, read_write> cases: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> depths: array<f32>;
@group(0) @binding(2) var<storage, read_write> results: array<u32>;
{}
{}
{}
{}
{}
{}
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {{
    let i = gid.x;
    if (i >= arrayLength(&depths)) {{
        return;
    }}
    let z = depths[i];
    results[5u * i] = bitcast<u32>(mboit6_share_in_front(cases[2u * i], cases[2u * i + 1u].xy, z));
    let z2 = z * z;
    let z3 = z2 * z;
    let p5 = mboit_power((z2 * z2) * z);
    let p6 = mboit_power(z3 * z3);
    results[5u * i + 1u] = u32(p5 & 0xffffffffli);
    results[5u * i + 2u] = u32(p5 >> 32u);
    results[5u * i + 3u] = u32(p6 & 0xffffffffli);
    results[5u * i + 4u] = u32(p6 >> 32u);
}}
",
        cut("const MBOIT6_BIAS", ";\n"),
        cut("const MBOIT_OVERESTIMATION", ";\n"),
        cut("fn mboit_power(", "\n}\n"),
        cut("fn mboit_div(", "\n}\n"),
        cut("fn mboit_cubic_roots(", "\n}\n"),
        cut("fn mboit6_share_in_front(", "\n}\n"),
    );
    let moments = |zs: &[f32]| -> [f32; 6] {
        std::array::from_fn(|k| zs.iter().map(|z| z.powi(k as i32 + 1)).sum::<f32>() / zs.len() as f32)
    };
    let mut s = 0x2545_f491u32;
    let mut next = || {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        (s as f32 / u32::MAX as f32) * 2.0 - 1.0
    };
    let mut sets: Vec<Vec<f32>> =
        vec![vec![0.3], vec![-0.7], vec![-0.5, 0.5], vec![0.0, 0.0, 0.9], vec![-0.6, 0.0, 0.6]];
    for n in 2..14 {
        sets.push((0..n).map(|_| next()).collect());
    }
    let (mut cases, mut depths, mut want) = (Vec::new(), Vec::new(), Vec::new());
    for set in &sets {
        let m = moments(set);
        for i in 0..=20 {
            let z = -1.0 + i as f32 / 10.0;
            cases.extend([[m[0], m[1], m[2], m[3]], [m[4], m[5], 0.0, 0.0]]);
            depths.push(z);
            want.push((m, z));
        }
    }
    let inputs: [&[u8]; 2] = [bytemuck::cast_slice(&cases), bytemuck::cast_slice(&depths)];
    let got = run_kernel(gpu, &kernel, &inputs, depths.len() * 5, depths.len() as u32);
    let mut worst = 0.0f32;
    for (i, (m, z)) in want.iter().enumerate() {
        let share = f32::from_bits(got[5 * i]);
        let rust = mboit6_share_in_front(*m, *z);
        worst = worst.max((share - rust).abs());
        assert!((share - rust).abs() <= 1e-3, "moments {m:?} at {z}: wgsl {share}, rust {rust}");
        let word = |j: usize| i64::from(got[5 * i + j]) | i64::from(got[5 * i + j + 1] as i32) << 32;
        let powers = oit_core::technique::mboit::mboit_powers(*z);
        assert_eq!(word(1), powers[4], "z⁵ at {z}");
        assert_eq!(word(3), powers[5], "z⁶ at {z}");
    }
    eprintln!("wgsl against rust: {} cases, the share at most {worst:.2e} apart", want.len());
}

/// mboit:6's cubic: `mboit_cubic_roots` of `mboit.wgsl` (the text itself) on oit-core's
/// `mboit6_cubic_roots` cases (three real roots spread, clustered, double, symmetric, one running
/// off to infinity), each root within that test's bound: 10⁻⁴ of its size, 10⁻³ near a double
/// root. The bound above reaches the smallest of Viète's three roots only where it is the largest
/// in magnitude, and then only through the share; here each root is checked. Fails when Viète's
/// angles (the smallest root at φ/3 + 2π/3), the scaling, the Newton step, the deflation or the
/// quadratic differ from oit-core's `cubic_roots`.
#[test]
fn wgsl_mboit6_cubic_roots() {
    let Some(backend) = oit_wgpu::backend_or_skip("wgsl_mboit6_cubic_roots") else { return };
    let gpu = backend.gpu().expect("opened by backend_or_skip");
    let mboit = oit_shaders::text("technique/mboit.wgsl");
    let cut = |from: &str, to: &str| {
        let start = mboit.find(from).unwrap_or_else(|| panic!("mboit.wgsl has {from}"));
        let end = start + mboit[start..].find(to).unwrap_or_else(|| panic!("{from} ends")) + to.len();
        &mboit[start..end]
    };
    let kernel = format!(
        "@group(0) @binding(0) var<storage, read_write> cases: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> results: array<vec4<f32>>;
{}
{}
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {{
    let i = gid.x;
    if (i >= arrayLength(&cases)) {{
        return;
    }}
    results[i] = vec4<f32>(mboit_cubic_roots(cases[i]), 0.0);
}}
",
        cut("fn mboit_div(", "\n}\n"),
        cut("fn mboit_cubic_roots(", "\n}\n"),
    );
    let roots: [([f32; 3], f32); 9] = [
        ([-0.5, 0.1, 0.7], 1.0),
        ([-0.5, 0.1, 0.7], -3e4),
        ([0.2, 0.2, -0.9], 2.0),
        ([0.3, 0.30001, 0.31], 1.0),
        ([-0.4, 0.6, 1e6], 1e-6),
        ([-0.4, 0.6, -3e8], 1.0),
        ([0.0, 0.5, -0.5], 1.0),
        ([-0.7, -0.1, 0.5], 1.0),
        ([-0.5, 0.5, -10.0], -3e3),
    ];
    let cases: Vec<[f32; 4]> = roots
        .iter()
        .map(|&(r, lead)| {
            let [r1, r2, r3] = r.map(f64::from);
            let l = f64::from(lead);
            [-l * r1 * r2 * r3, l * (r1 * r2 + r1 * r3 + r2 * r3), -l * (r1 + r2 + r3), l].map(|v| v as f32)
        })
        .collect();
    let got = run_kernel(gpu, &kernel, &[bytemuck::cast_slice(&cases)], cases.len() * 4, cases.len() as u32);
    for (i, (r, _)) in roots.iter().enumerate() {
        let mut found: Vec<f32> = (0..3).map(|j| f32::from_bits(got[4 * i + j])).collect();
        found.sort_by(f32::total_cmp);
        let mut want = *r;
        want.sort_by(f32::total_cmp);
        let close = (r[0] - r[1]).abs() < 1e-3;
        for (g, w) in found.iter().zip(want) {
            let tol = if close { 1e-3 } else { 1e-4 * w.abs().max(1.0) };
            assert!((g - w).abs() <= tol, "{r:?}: wgsl {found:?}");
        }
    }
}
