//! Linear to 8-bit sRGB (`oit_core::composite::linear_to_srgb8`), the last step of every pixel of
//! every CPU frame, three conversions a pixel: over values spread at random (neighbouring pixels'
//! composites of unrelated fragments), where a table walk that stops at a data-dependent step
//! mispredicts, and over a smooth ramp (a lit surface, where neighbours take the same steps).
//!
//! Each value is checked against the formula before it is timed.
//!
//! `cargo bench -p oit-cpu --bench srgb` (`cargo test` runs it once, in criterion's test mode)

use criterion::{Criterion, criterion_group, criterion_main};
use oit_core::composite::{linear_to_srgb8, linear_to_srgb8_formula};
use std::hint::black_box;

/// `n` linear values spread over [0, 1] by a xorshift generator (the same every run).
fn values(n: usize) -> Vec<f32> {
    let mut state = 0x9e37_79b9_u32;
    (0..n)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            (state >> 8) as f32 / (1u32 << 24) as f32
        })
        .collect()
}

fn srgb(c: &mut Criterion) {
    const N: usize = 3 * 65_536;
    let ramp: Vec<f32> = (0..N).map(|i| 0.2 + 0.3 * i as f32 / N as f32).collect();
    for (name, xs) in [("spread", values(N)), ("ramp", ramp)] {
        for &x in &xs {
            assert_eq!(linear_to_srgb8(x), linear_to_srgb8_formula(x), "{x}");
        }
        c.bench_function(&format!("linear_to_srgb8, {N} values, {name}"), |b| {
            b.iter(|| black_box(&xs).iter().fold(0u32, |sum, &x| sum + u32::from(linear_to_srgb8(x))))
        });
    }
}

criterion_group!(benches, srgb);
criterion_main!(benches);
