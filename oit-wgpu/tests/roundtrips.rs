//! CPU–GPU round trips inside a frame (issue 10): a frame whose technique sizes nothing from the
//! GPU and stops on no GPU count reads back once, at its end (counters, timestamps and, when
//! asked, the image and per-pixel losses together), plus the compute path's setup check where the
//! setup runs on the GPU. Before, every geometry pass read its fragment count back and every
//! timed pass its timestamps.

use oit_core::{Backend, Camera, RasterPath, Settings, Technique, View, load_scene};

#[test]
fn a_steady_frame_reads_back_once() {
    let Some(backend) = oit_wgpu::backend_or_skip("a_steady_frame_reads_back_once") else { return };
    let gpu = backend.gpu().expect("opened above");
    let scene = load_scene("planes:6").unwrap();
    let camera = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
    for path in [RasterPath::Compute, RasterPath::Hardware] {
        // the compute path's GPU setup reads its counters back once, to check the pieces fit
        let on_gpu = u64::from(path == RasterPath::Compute && oit_wgpu::setup_on_gpu(gpu));
        for technique in ["wavg", "wsum", "bdp", "bdp:2", "mdts64:8", "fabs"] {
            // bdp's depth bounds come from the instances' boxes (the default `BoundsMode`):
            // a second rasterizer, set up on its own
            let setup = on_gpu * if technique.starts_with("bdp") { 2 } else { 1 };
            let settings = Settings {
                width: 48,
                height: 40,
                technique: technique.parse::<Technique>().unwrap(),
                raster: Some(path),
                ..Settings::default()
            };
            let mut prepared = backend.prepare(&scene).unwrap();
            let first = prepared.frame(&camera, &settings).unwrap();
            assert!(first.stats.fragments > 0, "{technique} on {path}: the scene has fragments");
            // fabs sizes K from a counting pass: one readback more, by design (the plan's sizing)
            let sizing = u64::from(technique == "fabs");
            let before = gpu.readbacks();
            let stats = prepared.frame_stats(&camera, &settings).unwrap();
            let steady = gpu.readbacks() - before;
            assert_eq!(stats.fragments, first.stats.fragments, "{technique} on {path}");
            assert_eq!(steady, 1 + setup + sizing, "{technique} on {path}: readbacks of a steady frame");
            let before = gpu.readbacks();
            let again = prepared.frame(&camera, &settings).unwrap();
            assert_eq!(gpu.readbacks() - before, 1 + setup + sizing, "{technique} on {path}: with the image");
            assert_eq!(again.image, first.image, "{technique} on {path}: the same frame twice");
            assert_eq!(again.stats.fragments, first.stats.fragments);
            assert_eq!(again.stats.captured, first.stats.captured);
            assert_eq!(again.stats.lost, first.stats.lost);
        }
    }
}
