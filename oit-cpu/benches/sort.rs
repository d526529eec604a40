//! Which sort should `fabs` use for a pixel's n captured fragments? Insertion sort, a bitonic
//! sorting network (padded to a power of two, as a GPU resolve would run it), the standard
//! library's stable merge sort (driftsort) and its unstable pdqsort, by n.
//!
//! Each sort's output is checked before it is timed: in order, and the input's keys as often.
//!
//! `cargo bench -p oit-cpu --bench sort` (`cargo test` runs each once, in criterion's test mode)

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use std::hint::black_box;

fn insertion(keys: &mut [u64]) {
    for i in 1..keys.len() {
        let v = keys[i];
        let mut j = i;
        while j > 0 && keys[j - 1] > v {
            keys[j] = keys[j - 1];
            j -= 1;
        }
        keys[j] = v;
    }
}

fn bitonic(keys: &mut [u64]) {
    let n = keys.len().next_power_of_two();
    let mut buf = [u64::MAX; 256];
    let buf = &mut buf[..n];
    buf[..keys.len()].copy_from_slice(keys);
    let mut k = 2;
    while k <= n {
        let mut j = k / 2;
        while j > 0 {
            for i in 0..n {
                let l = i ^ j;
                if l > i {
                    let up = i & k == 0;
                    if (buf[i] > buf[l]) == up {
                        buf.swap(i, l);
                    }
                }
            }
            j /= 2;
        }
        k *= 2;
    }
    keys.copy_from_slice(&buf[..keys.len()]);
}

/// A sort under test.
type Sort = fn(&mut [u64]);

fn lists(n: usize) -> Vec<Vec<u64>> {
    let mut s = 0x2545_f491_4f6c_dd1du64;
    (0..256)
        .map(|_| {
            (0..n)
                .map(|_| {
                    s ^= s << 13;
                    s ^= s >> 7;
                    s ^= s << 17;
                    s
                })
                .collect()
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("fabs_sort");
    g.sample_size(20)
        .warm_up_time(std::time::Duration::from_millis(300))
        .measurement_time(std::time::Duration::from_millis(800));
    for n in [4usize, 8, 16, 32, 64, 128] {
        let input = lists(n);
        let sorts: [(&str, Sort); 4] = [
            ("insertion", insertion),
            ("bitonic", bitonic),
            ("merge", |k: &mut [u64]| k.sort()),
            ("pdq", |k: &mut [u64]| k.sort_unstable()),
        ];
        for (name, sort) in sorts {
            // a sort that does not sort is not timed: each output must be in order and hold the
            // input's keys, each as often (checked without a sort, so that the standard
            // library's two are held to something other than themselves)
            for list in &input {
                let mut mine = list.clone();
                sort(&mut mine);
                assert!(mine.windows(2).all(|w| w[0] <= w[1]), "{name} leaves {n} keys out of order");
                let counts = |keys: &[u64]| {
                    keys.iter().fold(std::collections::BTreeMap::new(), |mut m, &k| {
                        *m.entry(k).or_insert(0usize) += 1;
                        m
                    })
                };
                assert_eq!(counts(&mine), counts(list), "{name} changes the keys of {n}");
            }
            g.bench_with_input(BenchmarkId::new(name, n), &input, |b, input| {
                b.iter_batched_ref(
                    || input.clone(),
                    |lists| {
                        for l in lists.iter_mut() {
                            sort(black_box(l));
                        }
                    },
                    criterion::BatchSize::LargeInput,
                )
            });
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
