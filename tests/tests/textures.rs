//! Textured alpha (issue 38, item 3): a fragment's colour and alpha are the material's factor
//! times its texture's sample ([`oit_core::Texture::sample`]), the same on every technique; a
//! masked textured object is kept or discarded fragment by fragment, and the discarded ones are
//! counted. On the CPU backend, and on the GPU backends (wgpu and Vulkan): their compute paths
//! sample with oit-core's sampler ported to WGSL in integers (`texture.wgsl`), so their fragments'
//! colours, alphas and masks are the CPU's bit for bit; their hardware paths sample the same
//! texels at the same levels with the GPU's own interpolated coordinates.

use glam::{Vec2, Vec4};
use oit_core::setup::{TriangleSetup, barycentrics, covers};
use oit_core::{AlphaMode, Backend, Object, Settings, Texture, View, Wrap};
use oit_tests::checks;
use oit_tests::*;

fn cpu() -> oit_cpu::CpuBackend {
    oit_cpu::CpuBackend::default()
}

/// The exact techniques (those that pack colour among them: dfb, fabs, mdts64) equal the
/// reference on the textured scenes, and the texture shows: the frame differs from its
/// untextured twin.
#[test]
fn exact_techniques_equal_the_reference_on_textured_scenes() {
    let b = cpu();
    for (name, size) in [("particles:48", 96), ("fence", 96), ("grid:2x2:particles:8", 64)] {
        let scene = scene(name);
        let base = settings(size, "reference");
        let cam = camera(&scene, &base, View::default());
        let reference = render(&b, &scene, &cam, &base);
        checks::accounting(&reference).unwrap_or_else(|e| panic!("{name} reference: {e}"));
        assert!(reference.stats.captured > 0, "{name}: {:?}", reference.stats);
        for t in ["dfb", "ll", "fabs", "dp", "ddp", "adp", "mdts64", "mlp:4", "bdp2"] {
            let f = render(&b, &scene, &cam, &Settings { technique: t.parse().unwrap(), ..base.clone() });
            checks::exact(&reference, &f).unwrap_or_else(|e| panic!("{name} {t}: {e}"));
        }
        let plain = scene_untextured(name);
        let u = render(&b, &plain, &cam, &base);
        assert_eq!(u.stats.fragments, reference.stats.fragments, "{name}: the same geometry");
        assert_ne!(u.image, reference.image, "{name}: the texture must show");
    }
}

fn scene_untextured(name: &str) -> oit_core::Scene {
    scene(&format!("untextured:{name}"))
}

/// Whatever the thread count, the raster mode's kernels and the tiling: the same textured frame.
#[test]
fn textured_frames_do_not_depend_on_threads_or_tiles() {
    let scene = scene("particles:32");
    for t in ["reference", "fabs", "dp"] {
        let base = settings(64, t);
        let cam = camera(&scene, &base, View::default());
        let one = render(cpu_with_threads(1).as_ref(), &scene, &cam, &base);
        let four = render(cpu_with_threads(4).as_ref(), &scene, &cam, &base);
        assert_eq!(one.image, four.image, "{t}");
        let tiled = render(&cpu(), &scene, &cam, &Settings { memory: Some(96 << 10), ..base.clone() });
        assert!(tiled.stats.tiles > 1, "{t}: the budget must force tiles");
        assert_eq!(tiled.image, one.image, "{t}");
    }
}

/// A masked textured quad discards exactly the fragments whose alpha (the factor's times the
/// texture's sample at the fragment, by the core sampler) is under the cutoff, and counts them:
/// counted here independently, pixel by pixel over the set-up triangles of the opaque part.
#[test]
fn masked_texture_discards_exactly_what_is_under_the_cutoff() {
    let b = cpu();
    let fence = scene("fence");
    for (size, cutoff, factor) in [(96, 0.5, 1.0), (64, 0.3, 0.9), (128, 0.75, 1.0), (48, 0.0, 1.0)] {
        let mut s = fence.clone();
        let o = s.objects.iter_mut().find(|o| o.name == "fence").unwrap();
        o.alpha_mode = AlphaMode::Mask { cutoff };
        o.color.w = factor;
        let base = settings(size, "reference");
        let cam = camera(&s, &base, View::default());
        let f = render(&b, &s, &cam, &base);
        let layers = s.layers(None);
        let opaque = layers.opaque.as_ref().unwrap();
        let setup = TriangleSetup::new(opaque, &cam, &base);
        let (mut drawn, mut under) = (0u64, 0u64);
        for t in &setup.triangles {
            let [x0, y0, x1, y1] = t.bbox;
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let Some(e) = covers(t, x, y) else { continue };
                    drawn += 1;
                    let Some(texture) = setup.textures.get(t.texture as usize) else { continue };
                    // perspective-correct weights, the texture coordinates, the sample
                    let b = barycentrics(t, e);
                    let q: [f32; 3] = std::array::from_fn(|k| b[k] * t.inv_w[k]);
                    let inv = 1.0 / (q[0] + q[1] + q[2]);
                    let p = q.map(|q| q * inv);
                    let uv = t.uv[0] * p[0] + t.uv[1] * p[1] + t.uv[2] * p[2];
                    let alpha = (t.base.w * texture.sample(t.lod, uv).w).clamp(0.0, 1.0);
                    if alpha < cutoff {
                        under += 1;
                    }
                }
            }
        }
        assert_eq!(f.stats.opaque_fragments, drawn, "{size} {cutoff}");
        assert_eq!(f.stats.masked, under, "{size} {cutoff}");
        if cutoff == 0.0 {
            assert_eq!(under, 0, "a cutoff of 0 keeps everything");
        } else if size >= 96 {
            // large enough for a fine level, whose holes reach under the cutoff (a small frame's
            // coarse level averages them away)
            assert!(under > 0 && under < drawn / 2, "{size} {cutoff}: {under} of {drawn}");
        }
        checks::accounting(&f).unwrap();
        // the holes let the planes through: fewer held back than with the fence whole
        let mut whole = s.clone();
        whole.objects.iter_mut().find(|o| o.name == "fence").unwrap().alpha_mode = AlphaMode::Opaque;
        let w = render(&b, &whole, &cam, &base);
        assert!(under == 0 || f.stats.occluded < w.stats.occluded, "{size} {cutoff}");
    }
}

/// A flat texture of alpha 128 on a blended object is the same frame as no texture with the
/// factor's alpha times 128/255: the texture multiplies alpha (and white multiplies nothing).
#[test]
fn a_flat_texture_multiplies_the_factor() {
    let b = cpu();
    let mut textured = scene("particles:8");
    textured.textures[0] =
        Texture::new("flat", 4, 4, vec![[255, 255, 255, 128]; 16], [Wrap::Repeat; 2]).unwrap();
    let mut plain = scene("untextured:particles:8");
    for o in plain.objects.iter_mut().filter(|o| !o.is_opaque_pass()) {
        o.color.w *= 128.0 / 255.0;
    }
    for t in ["reference", "fabs", "wavg"] {
        let base = settings(64, t);
        let cam = camera(&textured, &base, View::default());
        let a = render(&b, &textured, &cam, &base);
        let c = render(&b, &plain, &cam, &base);
        let worst = a
            .image
            .pixels
            .iter()
            .zip(&c.image.pixels)
            .flat_map(|(p, q)| p.iter().zip(q).map(|(x, y)| x.abs_diff(*y)))
            .max()
            .unwrap();
        // 0.8 × 128/255 against 0.8 × (128/255 as f32): the last bit of an f32 at most
        assert!(worst <= 1, "{t}: {worst}");
    }
}

/// Bad textured input is refused with a message that names the object, mesh or texture.
#[test]
fn bad_textured_input_is_refused_by_name() {
    let b = cpu();
    let refused = |s: &oit_core::Scene| b.prepare(s).err().expect("refused").to_string();
    let good = scene("particles:4");
    assert!(b.prepare(&good).is_ok());
    // texture coordinates without a texture
    let mut s = good.clone();
    s.objects.iter_mut().for_each(|o| o.texture = None);
    let e = refused(&s);
    assert!(e.contains("billboard") && e.contains("texture coordinates"), "{e}");
    // a texture without coordinates
    let mut s = good.clone();
    s.meshes[0].uvs = None;
    let e = refused(&s);
    assert!(e.contains("particle 0") && e.contains("sprite") && e.contains("billboard"), "{e}");
    // non-finite coordinates, and too few
    for bad in [f32::NAN, f32::INFINITY] {
        let mut s = good.clone();
        s.meshes[0].uvs.as_mut().unwrap()[2] = Vec2::new(0.5, bad);
        let e = refused(&s);
        assert!(e.contains("billboard") && e.contains("vertex 3"), "{e}");
    }
    let mut s = good.clone();
    s.meshes[0].uvs.as_mut().unwrap().pop();
    assert!(refused(&s).contains("3 texture coordinates for 4"));
    // a missing texture
    let mut s = good.clone();
    s.objects[1].texture = Some(5);
    let e = refused(&s);
    assert!(e.contains("particle 1") && e.contains("texture 5"), "{e}");
    // images of zero or over-limit size
    for (w, h) in [(0, 16), (16, 0), (Texture::MAX_SIDE + 1, 1)] {
        let e = Texture::new("img", w, h, vec![[0; 4]; (w * h) as usize], [Wrap::Repeat; 2]).unwrap_err();
        assert!(e.to_string().contains("'img'") && e.to_string().contains("1 to 16384"), "{e}");
    }
    // a cutoff outside [0, 1] on a masked textured object
    let mut s = scene("fence");
    let o = s.objects.iter_mut().find(|o| o.name == "fence").unwrap();
    o.alpha_mode = AlphaMode::Mask { cutoff: -0.25 };
    let e = refused(&s);
    assert!(e.contains("fence") && e.contains("cutoff -0.25"), "{e}");
    // a textured object added by hand, its texture given
    let mut s = good.clone();
    s.objects.push(Object::new("extra", 0, Vec4::ONE).textured(0));
    assert!(b.prepare(&s).is_ok());
}

/// Every fragment of a textured frame carries the texture: under flat shading a white texture
/// of alpha 255 is the untextured frame, bit for bit (multiplying by 1.0 changes nothing).
#[test]
fn a_white_opaque_texture_changes_nothing() {
    let b = cpu();
    let mut textured = scene("particles:16");
    textured.textures[0] =
        Texture::new("white", 3, 5, vec![[255; 4]; 15], [Wrap::MirroredRepeat; 2]).unwrap();
    let plain = scene("untextured:particles:16");
    for t in ["reference", "dfb", "ll"] {
        let base = settings(64, t);
        let cam = camera(&textured, &base, View::default());
        assert_eq!(render(&b, &textured, &cam, &base).image, render(&b, &plain, &cam, &base).image, "{t}");
    }
}

/// One level of detail per triangle, from its texel-to-pixel area ratio: the fence's level
/// falls by one each time the frame's side doubles (the ratio falls by four).
#[test]
fn the_level_follows_the_texel_to_pixel_ratio() {
    let s = scene("fence");
    let levels: Vec<u32> = [32, 64, 128, 256]
        .iter()
        .map(|&size| {
            let base = settings(size, "reference");
            let cam = camera(&s, &base, View::default());
            let layers = s.layers(None);
            let setup = TriangleSetup::new(layers.opaque.as_ref().unwrap(), &cam, &base);
            let lods: Vec<u32> = setup.triangles.iter().filter(|t| t.texture == 0).map(|t| t.lod).collect();
            assert!(!lods.is_empty() && lods.iter().all(|&l| l == lods[0]), "{size}: {lods:?}");
            lods[0]
        })
        .collect();
    assert!(levels.windows(2).all(|w| w[0] == w[1] + 1), "{levels:?}");
}

/// The GPU backends on textured scenes (`mod gpu`).
#[cfg(all(feature = "wgpu", feature = "vulkan"))]
mod gpu {
    use oit_core::metrics::edge_mask;
    use oit_core::{Backend, Frame, RasterPath, Settings, Technique, View};
    use oit_tests::*;

    /// The textured scenes, and the frame size they are drawn at.
    const SCENES: [&str; 3] = ["particles:64", "fence", "grid:2x2:particles:8"];
    const SIZE: u32 = 128;

    /// The exact techniques compared (fabs with room for every fragment of these scenes), and
    /// two that pack colour (mdts64 in 20+12 bits, bdp's colour mode), compared by their counts.
    fn techniques() -> Vec<Technique> {
        ["reference", "ll", "fabs:64", "dp", "dfb", "mdts64:16", "bdp2"]
            .iter()
            .map(|t| t.parse().unwrap())
            .collect()
    }

    fn gpu_backends(test: &str) -> Option<[(&'static str, Box<dyn Backend>); 2]> {
        let wgpu = oit_wgpu::backend_or_skip(test)?;
        let vk = oit_vulkan::backend_or_skip(test)?;
        Some([("wgpu", Box::new(wgpu)), ("vulkan", Box::new(vk))])
    }

    /// The opaque pass's counts of `a` and `b`: equal.
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

    /// The compute paths of both GPU backends equal oit-cpu on textured scenes: the same fragments
    /// (captured, lost, tied, per pixel), the same masked, occluded and opaque counts (a masked
    /// fragment is one whose sampled alpha is under the cutoff: equal counts are the alphas'
    /// bits agreeing at every fragment near the cutoff), images within 1 in 8 bits, and every
    /// exact technique that loses nothing gives the CPU reference's image.
    #[test]
    fn textured_compute_paths_equal_cpu() {
        let Some(gpus) = gpu_backends("textured_compute_paths_equal_cpu") else { return };
        let cpu = oit_cpu::CpuBackend::default();
        for name in SCENES {
            let scene = scene(name);
            let base = Settings { raster: Some(RasterPath::Compute), ..settings(SIZE, "reference") };
            let cam = camera(&scene, &base, View::default());
            let reference = render(&cpu, &scene, &cam, &base);
            assert!(reference.stats.captured > 0, "{name}: {:?}", reference.stats);
            if name == "fence" {
                assert!(reference.stats.masked > 0, "{name}: the fence's holes are masked away");
            }
            for t in techniques() {
                let s = Settings { technique: t, ..base.clone() };
                let c = render(&cpu, &scene, &cam, &s);
                for (label, gpu) in &gpus {
                    let g = render(gpu.as_ref(), &scene, &cam, &s);
                    let what = format!("{t} on {name}, {label} compute");
                    checks::accounting(&g).unwrap_or_else(|e| panic!("{what}: {e}"));
                    checks::same_fragments_as_cpu_on(&scene, &g, &c, t)
                        .unwrap_or_else(|e| panic!("{what}: {e}"));
                    same_opaque(&g, &c).unwrap_or_else(|e| panic!("{what}: {e}"));
                    assert_eq!(g.stats.captured, c.stats.captured, "{what}: captured");
                    if t.is_exact() && c.stats.lost == 0 {
                        checks::exact(&reference, &g)
                            .unwrap_or_else(|e| panic!("{what} against the CPU's reference: {e}"));
                    }
                }
            }
        }
    }

    /// The masked fence at several cutoffs and sizes (several levels): each GPU compute path
    /// discards exactly the fragments oit-cpu discards.
    #[test]
    fn textured_masks_on_the_compute_paths_equal_cpu() {
        let Some(gpus) = gpu_backends("textured_masks_on_the_compute_paths_equal_cpu") else { return };
        let cpu = oit_cpu::CpuBackend::default();
        for (size, cutoff) in [(96, 0.5), (64, 0.3), (160, 0.75)] {
            let mut s = scene("fence");
            let o = s.objects.iter_mut().find(|o| o.name == "fence").unwrap();
            o.alpha_mode = oit_core::AlphaMode::Mask { cutoff };
            let base = Settings { raster: Some(RasterPath::Compute), ..settings(size, "reference") };
            let cam = camera(&s, &base, View::default());
            let c = render(&cpu, &s, &cam, &base);
            for (label, gpu) in &gpus {
                let g = render(gpu.as_ref(), &s, &cam, &base);
                let what = format!("fence at {size}, cutoff {cutoff}, {label} compute");
                same_opaque(&g, &c).unwrap_or_else(|e| panic!("{what}: {e}"));
                checks::exact(&c, &g).unwrap_or_else(|e| panic!("{what}: {e}"));
            }
        }
    }

    /// The hardware paths on textured scenes: each exact technique equals its own backend's
    /// hardware reference, the accounting holds, wgpu's and Vulkan's hardware paths agree on every
    /// count, and against the compute path (the CPU's fragments) every pixel the two rasterizers
    /// cover alike has the same colour within 1 in 8 bits; the opaque pass's counts are the CPU's
    /// within a hundredth of the fragments (a pixel on an edge may fall otherwise, and a fragment
    /// whose interpolated alpha lies at the cutoff may be kept on one and masked on the other).
    #[test]
    fn textured_hardware_paths_agree() {
        let Some(gpus) = gpu_backends("textured_hardware_paths_agree") else { return };
        let cpu = oit_cpu::CpuBackend::default();
        for name in SCENES {
            let scene = scene(name);
            let base = Settings { raster: Some(RasterPath::Hardware), ..settings(SIZE, "reference") };
            let cam = camera(&scene, &base, View::default());
            let c = render(&cpu, &scene, &cam, &Settings { raster: None, ..base.clone() });
            let near = edge_mask(&scene, &cam, SIZE, SIZE, checks::COVERAGE_SNAP);
            let references: Vec<Frame> =
                gpus.iter().map(|(_, g)| render(g.as_ref(), &scene, &cam, &base)).collect();
            let compute: Vec<Frame> = gpus
                .iter()
                .map(|(_, g)| {
                    render(
                        g.as_ref(),
                        &scene,
                        &cam,
                        &Settings { raster: Some(RasterPath::Compute), ..base.clone() },
                    )
                })
                .collect();
            for ((label, _), (h, k)) in gpus.iter().zip(references.iter().zip(&compute)) {
                let (hl, kl) = (h.layers.as_ref().unwrap(), k.layers.as_ref().unwrap());
                // besides the pixels on an edge, those where a masked fragment's alpha lies at
                // the cutoff, kept on one path and masked on the other (its transparent
                // fragments behind it then captured or held back): a few, and only where a mask is
                let cut: Vec<bool> =
                    near.iter().zip(hl.iter().zip(kl)).map(|(&n, (a, b))| n || a != b).collect();
                let at_cutoff = (0..cut.len()).filter(|&i| cut[i] && !near[i]).count();
                assert!(
                    at_cutoff == 0 || (c.stats.masked > 0 && at_cutoff <= cut.len() / 200),
                    "{name}, {label}: {at_cutoff} pixels off every edge cover otherwise"
                );
                checks::covered_alike_equal(&h.image, &k.image, hl, kl, &cut)
                    .unwrap_or_else(|e| panic!("{name}, {label}: hardware against compute: {e}"));
            }
            for t in techniques() {
                let s = Settings { technique: t, ..base.clone() };
                let frames: Vec<Frame> =
                    gpus.iter().map(|(_, g)| render(g.as_ref(), &scene, &cam, &s)).collect();
                for (((label, _), g), reference) in gpus.iter().zip(&frames).zip(&references) {
                    let what = format!("{t} on {name}, {label} hardware");
                    checks::accounting(g).unwrap_or_else(|e| panic!("{what}: {e}"));
                    assert_eq!(
                        g.stats.opaque_fragments, c.stats.opaque_fragments,
                        "{what}: opaque fragments"
                    );
                    let slack = c.stats.fragments / 100;
                    for (what_count, p, q) in [
                        ("occluded", g.stats.occluded, c.stats.occluded),
                        ("masked", g.stats.masked, c.stats.masked),
                    ] {
                        assert!(p.abs_diff(q) <= slack, "{what}: {what_count} {p} vs the CPU's {q}");
                    }
                    if t.is_exact() && g.stats.lost == 0 {
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

    /// The hardware paths' blend-unit captures (`--hardware-capture blend`) sample as the atomic
    /// captures do: on textured scenes each exact technique with a blend capture equals its
    /// backend's hardware reference, and the others count the fragments the atomic capture does.
    #[test]
    fn textured_blend_captures_sample_too() {
        let Some(gpus) = gpu_backends("textured_blend_captures_sample_too") else { return };
        // the particles over their opaque floor (the blend captures cut at its depth too)
        for name in ["particles:64", "grid:2x2:particles:8"] {
            let scene = scene(name);
            assert!(scene.has_opaque(), "{name}: its floor");
            let base = Settings { raster: Some(RasterPath::Hardware), ..settings(SIZE, "reference") };
            let cam = camera(&scene, &base, View::default());
            for (label, gpu) in &gpus {
                let reference = render(gpu.as_ref(), &scene, &cam, &base);
                let mut ran = 0;
                for t in ["dp", "ddp", "bdp2", "plain", "wavg", "adp"] {
                    let atomics = Settings { technique: t.parse().unwrap(), ..base.clone() };
                    let blend =
                        Settings { hardware_capture: oit_core::HardwareCapture::Blend, ..atomics.clone() };
                    let what = format!("{t} on {name}, {label} blend capture");
                    let b = match gpu.render(&scene, &cam, &blend) {
                        Ok(b) => b,
                        Err(e) if e.to_string().contains("blend") => {
                            eprintln!("{what}: skipped, {e}");
                            continue;
                        }
                        Err(e) => panic!("{what}: {e}"),
                    };
                    ran += 1;
                    let a = render(gpu.as_ref(), &scene, &cam, &atomics);
                    checks::accounting(&b).unwrap_or_else(|e| panic!("{what}: {e}"));
                    assert_eq!(b.stats.fragments, a.stats.fragments, "{what}: fragments");
                    same_opaque(&b, &a).unwrap_or_else(|e| panic!("{what}: {e}"));
                    if blend.technique.is_exact() && b.stats.lost == 0 {
                        checks::exact(&reference, &b).unwrap_or_else(|e| panic!("{what}: {e}"));
                    }
                }
                assert!(ran >= 3, "{label} on {name}: {ran} blend captures ran");
            }
        }
    }

    /// Textured frames on the compute paths under the other shadings and effects, and split into
    /// screen tiles by a memory budget (each tile's setup its own, its levels the full frame's):
    /// oit-cpu's fragments and, for the reference, oit-cpu's image within 1 in 8 bits; the
    /// hardware paths' tiled frames are their untiled ones.
    #[test]
    fn textured_shadings_effects_and_tiles_on_the_gpu() {
        let Some(gpus) = gpu_backends("textured_shadings_effects_and_tiles_on_the_gpu") else { return };
        let cpu = oit_cpu::CpuBackend::default();
        let scene = scene("particles:32");
        let base = Settings { raster: Some(RasterPath::Compute), ..settings(96, "reference") };
        let cam = camera(&scene, &base, View::default());
        let cases = [
            Settings { shading: oit_core::Shading::Flat, ..base.clone() },
            Settings { shading: oit_core::Shading::Vertex, ..base.clone() },
            Settings { effect: oit_core::Effect::Translucency, ..base.clone() },
            Settings { effect: oit_core::Effect::Fresnel, ..base.clone() },
            Settings { memory: Some(160 << 10), ..base.clone() },
            Settings { memory: Some(160 << 10), technique: "fabs:32".parse().unwrap(), ..base.clone() },
        ];
        for s in cases {
            let c = render(&cpu, &scene, &cam, &s);
            for (label, gpu) in &gpus {
                let what =
                    format!("{label} compute, {:?} {:?} {:?} {}", s.shading, s.effect, s.memory, s.technique);
                let g = render(gpu.as_ref(), &scene, &cam, &s);
                checks::accounting(&g).unwrap_or_else(|e| panic!("{what}: {e}"));
                checks::same_fragments_as_cpu(&g, &c, s.technique).unwrap_or_else(|e| panic!("{what}: {e}"));
                same_opaque(&g, &c).unwrap_or_else(|e| panic!("{what}: {e}"));
                if s.memory.is_some() {
                    assert!(g.stats.tiles > 1, "{what}: the budget must force tiles");
                    let hw = Settings { raster: Some(RasterPath::Hardware), ..s.clone() };
                    let tiled = render(gpu.as_ref(), &scene, &cam, &hw);
                    let whole = render(gpu.as_ref(), &scene, &cam, &Settings { memory: None, ..hw.clone() });
                    assert!(tiled.stats.tiles > 1, "{what}: hardware tiles");
                    checks::exact(&whole, &tiled).unwrap_or_else(|e| panic!("{what}, hardware: {e}"));
                }
            }
        }
    }
}
