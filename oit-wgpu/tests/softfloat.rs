//! oit-shaders' `wgsl/core/softfloat.wgsl`, the compute path setup's f32 arithmetic in integers, against the
//! host's f32 bit for bit: add, sub, mul, div, u64 → f32, floor and the sign tests, on every pair
//! of edge values (zeros, subnormals, the normal range's ends, infinities, quiet, signalling and
//! negative NaNs, halfway cases) and on random operands, both uniformly random bits and operands of
//! nearby exponents (where adds cancel and products round at the subnormal boundary).

use std::hint::black_box;

mod kernel;

const SOFTFLOAT: &str = oit_shaders::text("core/softfloat.wgsl");

const KERNEL: &str = r#"
@group(0) @binding(0) var<storage, read_write> cases: array<vec4<u32>>;
@group(0) @binding(1) var<storage, read_write> results: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.x + gid.y * groups.x * 64u;
    if (i >= arrayLength(&cases)) {
        return;
    }
    let c = cases[i];
    var r = 0u;
    switch c.x {
        case 0u: { r = sf_add(c.y, c.z); }
        case 1u: { r = sf_sub(c.y, c.z); }
        case 2u: { r = sf_mul(c.y, c.z); }
        case 3u: { r = sf_div(c.y, c.z); }
        case 4u: { r = sf_from_u64((u64(c.z) << 32u) | u64(c.y)); }
        case 5u: { r = sf_floor(c.y); }
        case 6u: { r = u32(sf_to_i32(c.y)); }
        case 7u: { r = select(0u, 1u, sf_ge0(c.y)) | select(0u, 2u, sf_lt0(c.y)) | select(0u, 4u, sf_is_finite(c.y)); }
        default: {}
    }
    results[i] = r;
}
"#;

/// Runs `KERNEL` over `cases` ([op, a, b, 0]) and returns one word per case.
fn run(gpu: &oit_wgpu::Gpu, cases: &[[u32; 4]]) -> Vec<u32> {
    use wgpu::util::DeviceExt;
    let device = &gpu.device;
    let input = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("cases"),
        contents: bytemuck::cast_slice(cases),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let output = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("results"),
        size: (cases.len() * 4) as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let entry = |binding| kernel::storage_entry(binding, false);
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: None,
        entries: &[entry(0), entry(1)],
    });
    let pipeline =
        gpu.compute_pipeline(&format!("{SOFTFLOAT}\n{KERNEL}"), "main", &[&layout]).expect("kernel builds");
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &layout,
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: input.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 1, resource: output.as_entire_binding() },
        ],
    });
    kernel::dispatch(gpu, &pipeline, &group, cases.len() as u64);
    gpu.read_u32(&output).expect("results read back")
}

/// What the host computes for a case (operands through `black_box`, so nothing is folded at
/// compile time: the host's float unit gives the answer).
fn host(case: [u32; 4]) -> u32 {
    let (a, b) = (black_box(f32::from_bits(case[1])), black_box(f32::from_bits(case[2])));
    match case[0] {
        0 => (a + b).to_bits(),
        1 => (a - b).to_bits(),
        2 => (a * b).to_bits(),
        3 => (a / b).to_bits(),
        4 => (black_box(u64::from(case[2]) << 32 | u64::from(case[1])) as f32).to_bits(),
        5 => a.floor().to_bits(),
        6 => (a as i32) as u32,
        7 => u32::from(a >= 0.0) | u32::from(a < 0.0) << 1 | u32::from(a.is_finite()) << 2,
        _ => unreachable!("no such op"),
    }
}

fn edge_values() -> Vec<u32> {
    let mut v = vec![
        0x0000_0000, // +0
        0x8000_0000, // −0
        0x0000_0001, // smallest subnormal
        0x0000_0002,
        0x0040_0000,
        0x007f_ffff, // largest subnormal
        0x0080_0000, // smallest normal
        0x0080_0001,
        0x00ff_ffff,
        0x3f80_0000, // 1
        0x3f80_0001,
        0x3f7f_ffff,
        0x3f00_0000, // 0.5
        0x3fc0_0000, // 1.5
        0x4040_0000, // 3
        0x3eaa_aaab, // 1/3
        0x4b00_0000, // 2^23
        0x4b80_0000, // 2^24
        0x4880_0000, // 2^18
        0x4880_0001,
        0x4e00_0000, // 2^29
        0x4280_0000, // 64 (the guard band)
        0x7f7f_ffff, // largest finite
        0x7f00_0000,
        0x0100_0000,
        0x7f80_0000, // +inf
        0x7fc0_0000, // quiet NaN
        0x7fc1_2345, // NaN with a payload
        0x7f80_0001, // signalling NaN
        0xffc0_0001, // negative NaN
    ];
    let negatives: Vec<u32> = v.iter().map(|x| x ^ 0x8000_0000).collect();
    v.extend(negatives);
    v.sort_unstable();
    v.dedup();
    v
}

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u32 {
        // splitmix64
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        (z ^ (z >> 31)) as u32
    }
    /// A float of sign and mantissa at random and an exponent within 4 of `exp`.
    fn near(&mut self, exp: u32) -> u32 {
        let r = self.next();
        let e = (exp + (r >> 28) % 9).saturating_sub(4).min(254);
        (r & 0x8000_0000) | e << 23 | (self.next() & 0x7f_ffff)
    }
}

fn check(gpu: &oit_wgpu::Gpu, cases: &[[u32; 4]]) {
    let got = run(gpu, cases);
    let mut bad = 0;
    for (case, have) in cases.iter().zip(&got) {
        let want = host(*case);
        if *have != want {
            if bad < 10 {
                eprintln!(
                    "op {} of {:#010x} ({:e}) and {:#010x} ({:e}): wgsl {:#010x} ({:e}), host {:#010x} ({:e})",
                    case[0],
                    case[1],
                    f32::from_bits(case[1]),
                    case[2],
                    f32::from_bits(case[2]),
                    have,
                    f32::from_bits(*have),
                    want,
                    f32::from_bits(want)
                );
            }
            bad += 1;
        }
    }
    assert_eq!(bad, 0, "{bad} of {} cases differ from the host's f32", cases.len());
}

#[test]
fn softfloat_equals_host_f32_on_edge_values() {
    let Some(backend) = oit_wgpu::backend_or_skip("softfloat_equals_host_f32_on_edge_values") else { return };
    let gpu = backend.gpu().expect("opened by backend_or_skip");
    let edges = edge_values();
    let mut cases = Vec::new();
    for op in 0..4 {
        for &a in &edges {
            for &b in &edges {
                cases.push([op, a, b, 0]);
            }
        }
    }
    for &a in &edges {
        for op in [5, 7] {
            cases.push([op, a, 0, 0]);
        }
    }
    // floor at and around integers and halves, both signs
    for x in [0.5f32, 1.0, 1.5, 2.5, 0.999_999_9, 255.5, 8_388_607.5, 16_777_215.0, 1e-40, 3e38] {
        for s in [1.0f32, -1.0] {
            cases.push([5, (x * s).to_bits(), 0, 0]);
        }
    }
    // integral values to i32, up to ±2^29 (what the setup converts)
    for x in [0i32, 1, -1, 255, -256, 1 << 23, (1 << 24) + 2, -(1 << 24), 1 << 29, -(1 << 29), 123_456_789] {
        cases.push([6, (x as f32).to_bits(), 0, 0]);
    }
    // u64 → f32: exact, halfway (ties to even) and around 2^60, the largest area
    for v in
        [0u64, 1, 3, (1 << 24) - 1, 1 << 24, (1 << 24) + 1, (1 << 24) + 3, (1 << 25) + 2, u64::MAX, 1 << 60]
    {
        for d in [0u64, 1, 2] {
            let v = v.wrapping_add(d);
            cases.push([4, v as u32, (v >> 32) as u32, 0]);
        }
    }
    check(gpu, &cases);
}

#[test]
fn softfloat_equals_host_f32_on_random_operands() {
    let Some(backend) = oit_wgpu::backend_or_skip("softfloat_equals_host_f32_on_random_operands") else {
        return;
    };
    let gpu = backend.gpu().expect("opened by backend_or_skip");
    let mut rng = Rng(0x5eed);
    let mut cases = Vec::new();
    for op in 0..4u32 {
        for _ in 0..40_000 {
            cases.push([op, rng.next(), rng.next(), 0]);
        }
        // nearby exponents: cancellation in adds, rounding in every op
        for exp in [1u32, 20, 60, 127, 150, 200, 250] {
            for _ in 0..4_000 {
                let e2 = if op >= 2 { 254 - exp.min(253) } else { exp };
                cases.push([op, rng.near(exp), rng.near(e2), 0]);
            }
        }
        // subnormal products and quotients
        for _ in 0..10_000 {
            cases.push([op, rng.near(40), rng.near(if op == 3 { 200 } else { 60 }), 0]);
        }
    }
    for _ in 0..20_000 {
        let (lo, hi) = (rng.next(), rng.next() >> (rng.next() % 33).min(31));
        cases.push([4, lo, hi, 0]);
        cases.push([5, rng.next(), 0, 0]);
        cases.push([5, rng.near(140), 0, 0]);
    }
    check(gpu, &cases);
}
