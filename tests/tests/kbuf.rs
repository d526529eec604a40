//! `kbuf[:K]`, the ordered k-buffer, on every backend × raster path compiled in. Where it runs
//! (oit-vulkan's hardware path on a device with `fragmentShaderPixelInterlock`: the H200, not
//! lavapipe) a frame is `fabs:K`'s to the bit: both keep each pixel's K smallest (depth bits,
//! primitive id) keys and lose the rest, so image, fragments, captured, lost, ties and passes are
//! the same, with pixels past K (lost > 0) and with equal depths (`ties:5`); sized from the scene it
//! equals the reference (EPR 0). Everywhere else the frame is refused, naming the interlock, and no
//! frame is drawn.

use oit_core::metrics::accuracy;
use oit_core::{Backend, RasterPath, Settings, Technique, TechniqueKind, View};
use oit_tests::*;

/// Whether `backend` on its path runs kbuf: its capabilities list it, on a hardware raster path.
fn runs_kbuf(backend: &dyn Backend) -> bool {
    backend.capabilities().techniques.contains(&TechniqueKind::Kbuf)
        && backend.raster_path(&Settings::default()) == RasterPath::Hardware
}

#[test]
fn kbuf_equals_fabs_where_it_runs_and_is_refused_elsewhere() {
    let mut ran = Vec::new();
    for b in backends() {
        let b = &*b;
        let runs = runs_kbuf(b);
        for name in ["planes:8", "knot", "ties:5", "cluster:200"] {
            let scene = scene(name);
            let base = settings(64, "reference");
            let cam = camera(&scene, &base, View::default());
            for k in [Some(3), None] {
                let technique = Technique::Kbuf { k };
                let what = format!("{technique} on {name}, {}", label(b));
                let s = Settings { technique, ..base.clone() };
                let result = b.render(&scene, &cam, &s);
                if !runs {
                    let e = result.err().unwrap_or_else(|| panic!("{what}: ran without an interlock"));
                    let e = e.to_string();
                    assert!(e.contains("VK_EXT_fragment_shader_interlock") && e.contains("fabs:K"), "{what}: {e}");
                    continue;
                }
                let kbuf = result.unwrap_or_else(|e| panic!("{what}: {e}"));
                let fabs = render(b, &scene, &cam, &Settings { technique: Technique::Fabs { k }, ..s.clone() });
                let key = |f: &oit_core::Frame| {
                    let s = &f.stats;
                    (s.fragments, s.captured, s.lost, s.merged, s.tied, s.geometry_passes)
                };
                assert_eq!(key(&kbuf), key(&fabs), "{what}: (fragments, captured, lost, merged, tied, passes) vs fabs");
                let differ = kbuf.image.pixels.iter().zip(&fabs.image.pixels).filter(|(a, b)| a != b).count();
                assert_eq!(differ, 0, "{what}: {differ} pixels differ from fabs's");
                if name == "planes:8" && k.is_some() {
                    assert!(kbuf.stats.lost > 0, "{what}: 8 layers into 3 slots lose fragments");
                }
                if k.is_none() {
                    let reference =
                        render(b, &scene, &cam, &Settings { technique: Technique::Reference, ..s.clone() });
                    let a = accuracy(&reference, &kbuf.image).expect("same size");
                    assert_eq!((kbuf.stats.lost, a.epr), (0, 0.0), "{what}: against the reference");
                }
            }
        }
        if runs {
            ran.push(label(b));
        }
    }
    if ran.is_empty() {
        eprintln!(
            "kbuf: refused on every backend here, as expected (no device with \
             VK_EXT_fragment_shader_interlock); it ran against fabs and the reference on none"
        );
    } else {
        eprintln!("kbuf: ran against fabs and the reference on {}", ran.join(", "));
    }
}
