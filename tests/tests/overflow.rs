//! Fixed-size techniques that overflow give the same output from run to run (issue 13.7): `fabs:2`
//! on the default scene keeps each pixel's 2 nearest fragments by (depth, primitive id), whatever
//! order they arrive in, on every backend × path and with any number of CPU threads.

use oit_core::{Frame, Stats, View};
use oit_tests::*;

/// The stats that must repeat: all but the times.
fn counts(s: &Stats) -> Stats {
    Stats { wall_ms: 0.0, gpu_ms: None, gpu_pass_ms: Vec::new(), ..s.clone() }
}

fn same(a: &Frame, b: &Frame, what: &str) {
    assert_eq!(counts(&a.stats), counts(&b.stats), "{what}: stats");
    let differ = a.image.pixels.iter().zip(&b.image.pixels).filter(|(x, y)| x != y).count();
    assert_eq!(differ, 0, "{what}: {differ} pixels differ");
}

#[test]
fn fabs_overflow_is_deterministic() {
    let scene = scene("default");
    let s = settings(64, "fabs:2");
    let cam = camera(&scene, &s, View::default());
    let mut runs: Vec<(String, Box<dyn oit_core::Backend>)> =
        backends_for("fabs_overflow_is_deterministic").into_iter().map(|b| (label(b.as_ref()), b)).collect();
    runs.push(("cpu, 1 thread".into(), cpu_with_threads(1)));
    runs.push(("cpu, 4 threads".into(), cpu_with_threads(4)));
    let mut cpu_first: Option<Frame> = None;
    for (name, backend) in &runs {
        let first = render(backend.as_ref(), &scene, &cam, &s);
        assert!(first.stats.lost > 0, "{name}: the test needs overflow");
        assert_eq!(first.stats.captured + first.stats.lost, first.stats.fragments, "{name}");
        for run in 1..4 {
            let again = render(backend.as_ref(), &scene, &cam, &s);
            same(&first, &again, &format!("{name} run {run}"));
        }
        if name.starts_with("cpu") {
            // the CPU rasterizer is the same whatever the threads: so is the picture
            match &cpu_first {
                Some(f) => same(f, &first, &format!("{name} against the first cpu run")),
                None => cpu_first = Some(first),
            }
        }
    }
}
