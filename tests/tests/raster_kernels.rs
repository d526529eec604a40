//! The compute rasterizer's GPU kernel on a CPU device. GPUs run `raster_main` (a workgroup a
//! (triangle, tile) work item, an invocation a pixel) and CPU devices such as lavapipe
//! `raster_loop_main` (an invocation a work item walking its tile), so without this file no test
//! on a machine without a GPU would run the kernel every GPU runs. Here the test runs itself again
//! with `OIT_RASTER_PER_PIXEL=1` (`oit_gpu::raster_per_pixel`), which puts `raster_main` on any
//! device, and holds wgpu's and Vulkan's compute paths to oit-cpu's frames: the same fragments,
//! captured and occluded counts, and an exact technique that loses nothing equal to the CPU's
//! reference; over opaque walls (the tile skip: items behind their tile's opaque depth skipped
//! after the frame's first scene pass), through the bunny, and at four samples a pixel.
//! Mutations caught (each tried): `raster_main` never reaching a tile's last row (the fragments
//! short on the first scene), and its tile skip applied in the frame's first scene pass too (the
//! fragments and occluded count short). Not caught, as it should not be: x and y swapped within a
//! tile (the same pixels in another order).
#![cfg(all(feature = "wgpu", feature = "vulkan"))]

use oit_core::{Backend, RasterPath, Settings, View};
use oit_tests::*;

const FORCE: &str = "OIT_RASTER_PER_PIXEL";

#[test]
fn the_gpus_raster_kernel_equals_the_cpu() {
    if std::env::var(FORCE).as_deref() != Ok("1") {
        // run this test again in a process of its own with the GPUs' kernel forced (setting the
        // variable here would race the harness's other threads)
        let exe = std::env::current_exe().expect("the test binary's path");
        let status = std::process::Command::new(exe)
            .env(FORCE, "1")
            .args(["--exact", "the_gpus_raster_kernel_equals_the_cpu", "--nocapture", "--test-threads", "1"])
            .status()
            .expect("the test binary runs again");
        assert!(status.success(), "with {FORCE}=1: {status}");
        return;
    }
    let Some(wgpu) = oit_wgpu::backend_or_skip("the_gpus_raster_kernel_equals_the_cpu") else { return };
    let Some(vk) = oit_vulkan::backend_or_skip("the_gpus_raster_kernel_equals_the_cpu") else { return };
    let gpus: [(&str, Box<dyn Backend>); 2] = [("wgpu", Box::new(wgpu)), ("vulkan", Box::new(vk))];
    let cpu = oit_cpu::CpuBackend::default();
    let mut compared = 0;
    for (name, size, samples) in
        [("wall:0.5:planes:16", 64, 1), ("wall:0:planes:8", 48, 1), ("bunny", 48, 1), ("bunny", 40, 4)]
    {
        let scene = scene(name);
        let base = Settings { raster: Some(RasterPath::Compute), samples, ..settings(size, "reference") };
        let cam = camera(&scene, &base, View::default());
        let reference = render(&cpu, &scene, &cam, &base);
        for t in ["reference", "dp", "ddp", "ll", "dfb", "fabs:4", "wavg", "bdp"] {
            let s = Settings { technique: t.parse().unwrap(), ..base.clone() };
            let c = render(&cpu, &scene, &cam, &s);
            for (label, gpu) in &gpus {
                let g = render(gpu.as_ref(), &scene, &cam, &s);
                let what = format!("{t} on {name} at {samples}×, {label} compute with raster_main");
                checks::accounting(&g).unwrap_or_else(|e| panic!("{what}: {e}"));
                checks::same_fragments_as_cpu(&g, &c, s.technique).unwrap_or_else(|e| panic!("{what}: {e}"));
                assert_eq!(
                    (g.stats.captured, g.stats.occluded, g.stats.opaque_fragments),
                    (c.stats.captured, c.stats.occluded, c.stats.opaque_fragments),
                    "{what}: captured, occluded, opaque fragments"
                );
                if s.technique.is_exact() && c.stats.lost == 0 && reference.stats.captured > 0 {
                    checks::exact(&reference, &g)
                        .unwrap_or_else(|e| panic!("{what} against the CPU's reference: {e}"));
                }
                compared += 1;
            }
        }
        if scene.has_opaque() {
            assert!(reference.stats.occluded > 0, "{name}: the wall holds nothing back");
        }
        if name.starts_with("wall:0:") {
            assert_eq!(reference.stats.captured, 0, "{name}: everything lies behind the wall");
        }
    }
    assert_eq!(compared, 4 * 8 * 2);
}
