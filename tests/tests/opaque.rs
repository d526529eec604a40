//! Opaque first (issue 38) on the GPU backends: scenes with an opaque wall (`wall:F:SCENE`) drawn
//! by the opaque pass before the technique, on wgpu and Vulkan, compute and hardware paths.
//!
//! The compute paths follow oit-cpu's rules, so every technique's frame equals oit-cpu's: the same
//! fragments, captured, lost and tied, the same occluded, opaque and masked counts, the same
//! geometry passes and storage (but `plain`'s, which counts first on a GPU), and the images within
//! 1 in 8 bits; an exact technique that loses nothing on the CPU gives the CPU reference's image. The hardware paths rasterize
//! with the GPU's own rules: each exact technique equals its own backend's hardware reference,
//! the accounting holds, wgpu's and Vulkan's hardware paths agree on every count, and their
//! opaque counts are the CPU's (the occluded within a hundredth of the fragments: pixels on an
//! edge may fall otherwise). Without a device each test prints that it was skipped;
//! `OIT_REQUIRE_GPU=1` makes that a failure.
#![cfg(all(feature = "wgpu", feature = "vulkan"))]

use oit_core::{Backend, Frame, RasterPath, Settings, Technique, View};
use oit_tests::*;

const SCENES: [&str; 3] = ["wall:0.5:planes:16", "wall:0.5:default", "wall:0:planes:8"];

fn techniques() -> Vec<Technique> {
    let mut t = vec![Technique::Reference];
    t.extend(Technique::all());
    t.extend([Technique::Bdp { passes: 3 }, Technique::Mdts64 { k: Some(3) }, Technique::Mlp { m: 1 }]);
    t
}

/// The opaque pass's counts of `a` and `b` are equal.
fn same_opaque(a: &Frame, b: &Frame) -> Result<(), String> {
    let (x, y) = (&a.stats, &b.stats);
    for (what, p, q) in [
        ("occluded", x.occluded, y.occluded),
        ("opaque_fragments", x.opaque_fragments, y.opaque_fragments),
        ("masked", x.masked, y.masked),
    ] {
        if p != q {
            return Err(format!("{what}: {p} vs {q}"));
        }
    }
    Ok(())
}

fn gpu_backends(test: &str) -> Option<[(&'static str, Box<dyn Backend>); 2]> {
    let wgpu = oit_wgpu::backend_or_skip(test)?;
    let vk = oit_vulkan::backend_or_skip(test)?;
    Some([("wgpu", Box::new(wgpu)), ("vulkan", Box::new(vk))])
}

#[test]
fn opaque_first_compute_paths_equal_cpu() {
    let Some(gpus) = gpu_backends("opaque_first_compute_paths_equal_cpu") else { return };
    let cpu = oit_cpu::CpuBackend::default();
    for name in SCENES {
        let scene = scene(name);
        assert!(scene.has_opaque(), "{name} has an opaque wall");
        let base = Settings { raster: Some(RasterPath::Compute), ..settings(64, "reference") };
        let cam = camera(&scene, &base, View::default());
        let reference = render(&cpu, &scene, &cam, &base);
        assert!(
            reference.stats.occluded > 0 && reference.stats.opaque_fragments > 0,
            "{name}: the wall hides some"
        );
        if name.starts_with("wall:0:") {
            assert_eq!(reference.stats.captured, 0, "{name}: everything lies behind the wall");
        }
        for t in techniques() {
            let s = Settings { technique: t, ..base.clone() };
            let c = render(&cpu, &scene, &cam, &s);
            for (label, gpu) in &gpus {
                let g = render(gpu.as_ref(), &scene, &cam, &s);
                let what = format!("{t} on {name}, {label} compute");
                checks::accounting(&g).unwrap_or_else(|e| panic!("{what}: {e}"));
                checks::same_fragments_as_cpu(&g, &c, t).unwrap_or_else(|e| panic!("{what}: {e}"));
                same_opaque(&g, &c).unwrap_or_else(|e| panic!("{what}: {e}"));
                assert_eq!(g.stats.captured, c.stats.captured, "{what}: captured");
                if t != Technique::Plain {
                    checks::same_storage_as_cpu(label, &g, &c, &scene, &s)
                        .unwrap_or_else(|e| panic!("{what}: {e}"));
                }
                if t.is_exact() && c.stats.lost == 0 && reference.stats.captured > 0 {
                    checks::exact(&reference, &g)
                        .unwrap_or_else(|e| panic!("{what} against the CPU's reference: {e}"));
                }
            }
        }
    }
}

#[test]
fn opaque_first_hardware_paths_agree() {
    let Some(gpus) = gpu_backends("opaque_first_hardware_paths_agree") else { return };
    let cpu = oit_cpu::CpuBackend::default();
    for name in SCENES {
        let scene = scene(name);
        let base = Settings { raster: Some(RasterPath::Hardware), ..settings(64, "reference") };
        let cam = camera(&scene, &base, View::default());
        let c = render(&cpu, &scene, &cam, &Settings { raster: None, ..base.clone() });
        let references: Vec<Frame> =
            gpus.iter().map(|(_, g)| render(g.as_ref(), &scene, &cam, &base)).collect();
        for t in techniques() {
            let s = Settings { technique: t, ..base.clone() };
            let frames: Vec<Frame> = gpus.iter().map(|(_, g)| render(g.as_ref(), &scene, &cam, &s)).collect();
            for (((label, _), g), reference) in gpus.iter().zip(&frames).zip(&references) {
                let what = format!("{t} on {name}, {label} hardware");
                checks::accounting(g).unwrap_or_else(|e| panic!("{what}: {e}"));
                assert_eq!(g.stats.opaque_fragments, c.stats.opaque_fragments, "{what}: opaque fragments");
                assert_eq!(g.stats.masked, c.stats.masked, "{what}: masked");
                let slack = c.stats.fragments / 100;
                assert!(
                    g.stats.occluded.abs_diff(c.stats.occluded) <= slack,
                    "{what}: occluded {} vs the CPU's {}",
                    g.stats.occluded,
                    c.stats.occluded
                );
                if t.is_exact() && g.stats.lost == 0 && reference.stats.captured > 0 {
                    checks::exact(reference, g)
                        .unwrap_or_else(|e| panic!("{what} against its reference: {e}"));
                }
            }
            let what = format!("{t} on {name}, wgpu against vulkan hardware");
            checks::same_fragments(&frames[0], &frames[1]).unwrap_or_else(|e| panic!("{what}: {e}"));
            same_opaque(&frames[0], &frames[1]).unwrap_or_else(|e| panic!("{what}: {e}"));
        }
    }
}
