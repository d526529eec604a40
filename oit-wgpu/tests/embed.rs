//! The embeddable pass against `Backend::render`: the user-owned scene of `examples/embed.rs`
//! (their vertex buffer and shader, world → clip on the GPU) through `OitPass`, and the same
//! scene as an oit `Scene` through the hardware path (world → clip on the host). Both use the
//! GPU's rasterizer; the transforms differ in float rounding, so only pixels next to a triangle
//! edge may differ.

use oit_core::{Backend, Image, Mesh, OitError, RasterPath, Scene, Settings, Shading, Technique};

#[path = "../examples/embed.rs"]
#[expect(dead_code, reason = "the example's `main` is not called here")]
mod example;

/// The example's scene as an oit scene: one object per quad, flat-shaded in its colour, in the
/// same order (so the primitive ids agree).
fn scene() -> Scene {
    let quads = example::quads();
    let meshes = quads
        .iter()
        .enumerate()
        .map(|(i, (corners, _))| {
            Mesh::new(format!("quad {i}"), corners.to_vec(), example::QUAD_TRIANGLES.to_vec())
        })
        .collect();
    let mut scene = Scene::from_meshes("embed example", meshes, glam::Vec4::ONE);
    for (object, (_, color)) in scene.objects.iter_mut().zip(&quads) {
        object.color = *color;
    }
    scene
}

/// Pixels whose centre lies within `r` pixels of a triangle edge of `scene`.
fn edge_mask(scene: &Scene, r: f32) -> Vec<bool> {
    let size = example::SIZE;
    let vp = example::camera().view_proj();
    let mut segments = Vec::new();
    for inst in &scene.instances {
        let (_, mesh) = scene.instance_parts(inst);
        let screen: Vec<glam::Vec2> = mesh
            .positions
            .iter()
            .map(|p| {
                let c = vp * (inst.transform.transform_point3(*p)).extend(1.0);
                let n = c.truncate() / c.w;
                glam::Vec2::new((n.x * 0.5 + 0.5) * size as f32, (1.0 - (n.y * 0.5 + 0.5)) * size as f32)
            })
            .collect();
        for t in &mesh.indices {
            for k in 0..3 {
                segments.push((screen[t[k] as usize], screen[t[(k + 1) % 3] as usize]));
            }
        }
    }
    let mut mask = vec![false; (size * size) as usize];
    for y in 0..size {
        for x in 0..size {
            let p = glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            mask[(y * size + x) as usize] = segments.iter().any(|&(a, b)| {
                let ab = b - a;
                let t = ((p - a).dot(ab) / ab.length_squared().max(1e-12)).clamp(0.0, 1.0);
                (a + ab * t - p).length() < r
            });
        }
    }
    mask
}

/// Worst channel difference over the pixels off the edges, and how many pixels differ there.
fn compare_off_edges(a: &Image, b: &Image, mask: &[bool]) -> (u8, usize) {
    let (mut worst, mut differ) = (0u8, 0usize);
    for ((p, q), &edge) in a.pixels.iter().zip(&b.pixels).zip(mask) {
        if edge {
            continue;
        }
        let d = (0..4).map(|i| p[i].abs_diff(q[i])).max().unwrap_or(0);
        worst = worst.max(d);
        differ += usize::from(d > 1);
    }
    (worst, differ)
}

#[test]
fn embedded_pass_matches_backend_render() {
    if oit_wgpu::backend_or_skip("embedded_pass_matches_backend_render").is_none() {
        return;
    }
    let scene = scene();
    let mask = edge_mask(&scene, 1.0);
    let edges = mask.iter().filter(|&&e| e).count();
    // Every technique of the catalogue either runs through the embedded pass and matches the
    // backend's own render, or is refused as unsupported; which is which is listed here, so a
    // technique that stops running (or starts, unannounced) fails the test.
    let mut all: Vec<String> = vec!["reference".into(), "fabs:2".into(), "mdts64:4".into()];
    all.extend(Technique::all().iter().map(ToString::to_string));
    for t in &all {
        let t = t.as_str();
        let technique: Technique = t.parse().unwrap();
        let supported = EMBED_SUPPORTED.contains(&t);
        let (frame, target, adapter) = match example::render(technique) {
            Err(OitError::Unsupported { what, .. }) => {
                assert!(
                    !supported,
                    "{t} is listed as supported by the embedded pass but was refused: {what}"
                );
                println!("{t}: refused as listed ({what})");
                continue;
            }
            r => {
                assert!(supported, "{t} ran through the embedded pass: add it to EMBED_SUPPORTED");
                r.unwrap()
            }
        };
        // the target texture holds the frame's image
        assert_eq!(target.pixels, frame.image.pixels, "{t}: target texture");
        let backend = oit_wgpu::WgpuBackend::new(Some(adapter.clone()));
        let settings = Settings {
            width: example::SIZE,
            height: example::SIZE,
            technique,
            shading: Shading::Flat,
            raster: Some(RasterPath::Hardware),
            ..Settings::default()
        };
        let own = backend.render(&scene, &example::camera(), &settings).unwrap();
        let (worst, differ) = compare_off_edges(&frame.image, &own.image, &mask);
        println!(
            "{t} on {adapter}: off-edge worst {worst}, {differ} differing of {} off-edge pixels; fragments {} vs {}, passes {} vs {}",
            mask.len() - edges,
            frame.stats.fragments,
            own.stats.fragments,
            frame.stats.geometry_passes,
            own.stats.geometry_passes
        );
        // EPR 0 off the edges: no channel differs by more than 1
        assert!(worst <= 1, "{t}: off-edge difference {worst}");
        // the same schedule, but for plain: the backend's hardware path has the blender do it in
        // one draw (`Plan::on_path`); the embedded pass keeps and sorts (a counting pass first)
        let sorting_pass = u32::from(technique == Technique::Plain);
        assert_eq!(frame.stats.geometry_passes, own.stats.geometry_passes + sorting_pass, "{t}");
        // a fragment count differs only by edge pixels
        assert!(frame.stats.fragments.abs_diff(own.stats.fragments) as usize <= edges, "{t}");
    }
}

/// The techniques the embedded pass runs (bdp, bdp2 and adp with the quads' boxes, which the
/// example gives it); the rest of the catalogue it refuses as unsupported (mdts without
/// `Settings::alpha`: it stores no alpha, and the pass does not know the caller's — it used to
/// composite every fragment as opaque, silently).
const EMBED_SUPPORTED: &[&str] = &[
    "reference",
    "plain",
    "fabs",
    "fabs:2",
    "wavg",
    "wsum",
    "wboit",
    "mboit:4",
    "mboit:6",
    "mdts64:4",
    "mdts64",
    "dp",
    "ddp",
    "mlp:4",
    "dfb",
    "ll",
    "bdp",
    "bdp2",
    "adp",
];

/// Without the instances' boxes, bdp and adp are refused before any pass runs, naming the method
/// that gives them; a box that is not one is refused when given.
#[test]
fn bdp_and_adp_without_boxes_name_the_method() {
    let Some(backend) = oit_wgpu::backend_or_skip("bdp_and_adp_without_boxes_name_the_method") else {
        return;
    };
    let gpu = backend.gpu().unwrap();
    for technique in [Technique::Bdp { passes: 1 }, Technique::Bdp { passes: 3 }, Technique::Adp] {
        let settings = Settings { width: 16, height: 16, technique, ..Settings::default() };
        let pass = oit_wgpu::OitPass::new(&gpu.device, &gpu.queue, settings, example::camera()).unwrap();
        let mut asked = false;
        let result = pass.frame(
            None,
            |_| panic!("{technique}: no pipeline is built for a refused frame"),
            |_, _| asked = true,
        );
        match result {
            Err(OitError::Unsupported { what, .. }) => {
                assert!(what.contains("OitPass::with_instance_boxes"), "{technique}: {what}");
                assert!(what.contains(&technique.to_string()), "{technique}: {what}");
            }
            other => panic!("{technique}: expected Unsupported, got {:?}", other.map(|f| f.stats)),
        }
        assert!(!asked, "{technique}: nothing drawn");
    }
    let pass =
        || oit_wgpu::OitPass::new(&gpu.device, &gpu.queue, Settings::default(), example::camera()).unwrap();
    let inverted = oit_core::Aabb { min: glam::Vec3::ONE, max: glam::Vec3::ZERO };
    let unit = oit_core::Aabb { min: glam::Vec3::ZERO, max: glam::Vec3::ONE };
    for (boxes, index) in [(vec![unit, inverted], "box 1"), (vec![oit_core::Aabb::EMPTY], "box 0")] {
        match pass().with_instance_boxes(&boxes) {
            Err(OitError::InvalidSettings(message)) => assert!(message.contains(index), "{message}"),
            other => panic!("{boxes:?}: expected InvalidSettings, got ok: {}", other.is_ok()),
        }
    }
    assert!(pass().with_instance_boxes(&[unit]).is_ok());
    assert!(pass().with_instance_boxes(&[]).is_ok(), "no instances, no boxes");
}

/// The largest channel difference between two images of one size.
fn worst_difference(a: &Image, b: &Image) -> u8 {
    assert_eq!((a.width, a.height), (b.width, b.height), "sizes");
    a.pixels
        .iter()
        .zip(&b.pixels)
        .map(|(p, q)| (0..4).map(|i| p[i].abs_diff(q[i])).max().unwrap_or(0))
        .max()
        .unwrap_or(0)
}

/// The render pipeline of a capture module over `SceneGeometry`'s vertex and fragment stages, as
/// `oit view` builds it (multisampled where the capture is).
fn scene_pipeline(
    device: &wgpu::Device,
    geometry: &oit_wgpu::embed::SceneGeometry,
    capture: &oit_wgpu::CaptureShader<'_>,
) -> wgpu::RenderPipeline {
    use oit_wgpu::embed::SceneGeometry;
    let source = format!("{}\n{}\n{}", capture.wgsl, SceneGeometry::WGSL, SceneGeometry::WGSL_MASKED);
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("scene geometry"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: None,
        bind_group_layouts: &[Some(capture.bind_group_layout), Some(geometry.bind_group_layout())],
        immediate_size: 0,
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("scene geometry"),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("hw_vs"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
        depth_stencil: None,
        multisample: capture.multisample,
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some(SceneGeometry::fragment_entry(capture)),
            compilation_options: Default::default(),
            targets: &[Some(capture.count_target.clone())],
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// An oit scene of transformed instances through `SceneGeometry` and the embedded pass: bdp,
/// bdp:P and adp (whose bounds pass draws the instances' world boxes) give `Backend::render`'s
/// image, fragments and passes on the hardware path, with the boxes from
/// `OitPass::with_scene_geometry` and from `OitPass::with_instance_boxes` alike. The same vertex
/// stage on both sides: no edge allowance.
#[test]
fn scene_geometry_bdp_and_adp_match_backend_render() {
    let Some(backend) = oit_wgpu::backend_or_skip("scene_geometry_bdp_and_adp_match_backend_render") else {
        return;
    };
    let gpu = backend.gpu().unwrap();
    let scene = oit_core::load_scene("grid:2x2:spheres:2").unwrap();
    assert!(scene.instances.iter().any(|i| i.transform != glam::Mat4::IDENTITY), "placed instances");
    let (w, h) = (64, 48);
    let camera =
        oit_core::Camera::orbit_scene(&scene, oit_core::View::default(), w as f32 / h as f32).unwrap();
    let geometry = oit_wgpu::embed::SceneGeometry::new(&gpu.device, &gpu.queue, &scene).unwrap();
    let boxes: Vec<oit_core::Aabb> = scene.instances.iter().map(|i| scene.instance_bounds(i)).collect();
    let absorption = scene.objects.iter().map(|o| o.absorption).sum::<f32>() / scene.objects.len() as f32;
    let cases = [
        (Technique::Bdp { passes: 1 }, oit_core::Effect::Transparency),
        (Technique::Bdp { passes: 3 }, oit_core::Effect::Transparency),
        (Technique::Bdp { passes: 1 }, oit_core::Effect::Translucency),
        (Technique::Adp, oit_core::Effect::Transparency),
        (Technique::Adp, oit_core::Effect::Fresnel),
    ];
    for (technique, effect) in cases {
        let settings = Settings {
            width: w,
            height: h,
            technique,
            effect,
            raster: Some(RasterPath::Hardware),
            ..Settings::default()
        };
        let own = backend.render(&scene, &camera, &settings).unwrap();
        let pass = oit_wgpu::OitPass::new(&gpu.device, &gpu.queue, settings.clone(), camera).unwrap();
        let given = oit_wgpu::OitPass::new(&gpu.device, &gpu.queue, settings.clone(), camera)
            .unwrap()
            .with_scene_bounds(scene.bounds(), absorption)
            .with_instance_boxes(&boxes)
            .unwrap();
        for (how, pass) in
            [("with_scene_geometry", pass.with_scene_geometry(&geometry)), ("with_instance_boxes", given)]
        {
            geometry.write_frame(&scene, &camera, &settings);
            let frame = pass
                .frame(
                    None,
                    |capture| scene_pipeline(&gpu.device, &geometry, capture),
                    |rpass, _| {
                        rpass.set_bind_group(1, geometry.bind_group(), &[]);
                        rpass.draw(0..geometry.vertex_count(), 0..1);
                    },
                )
                .unwrap();
            let worst = worst_difference(&frame.image, &own.image);
            println!(
                "{technique} {effect:?} ({how}): worst {worst}; fragments {} vs {}, passes {} vs {}, lost {} vs {}",
                frame.stats.fragments,
                own.stats.fragments,
                frame.stats.geometry_passes,
                own.stats.geometry_passes,
                frame.stats.lost,
                own.stats.lost
            );
            assert!(worst <= 1, "{technique} {effect:?} ({how}): a pixel differs by {worst}");
            assert_eq!(frame.stats.fragments, own.stats.fragments, "{technique} ({how})");
            assert_eq!(frame.stats.geometry_passes, own.stats.geometry_passes, "{technique} ({how})");
            assert_eq!(frame.stats.lost, own.stats.lost, "{technique} ({how})");
        }
    }
    // exact bounds (the fragments' own depth range): the bounds pass draws the caller's
    // geometry, so a pass without boxes runs bdp and adp too
    for technique in [Technique::Bdp { passes: 2 }, Technique::Adp] {
        let settings = Settings {
            width: w,
            height: h,
            technique,
            bounds: oit_core::BoundsMode::Exact,
            raster: Some(RasterPath::Hardware),
            ..Settings::default()
        };
        let own = backend.render(&scene, &camera, &settings).unwrap();
        let pass = oit_wgpu::OitPass::new(&gpu.device, &gpu.queue, settings.clone(), camera)
            .unwrap()
            .with_scene_bounds(scene.bounds(), absorption);
        geometry.write_frame(&scene, &camera, &settings);
        let frame = pass
            .frame(
                None,
                |capture| scene_pipeline(&gpu.device, &geometry, capture),
                |rpass, _| {
                    rpass.set_bind_group(1, geometry.bind_group(), &[]);
                    rpass.draw(0..geometry.vertex_count(), 0..1);
                },
            )
            .unwrap();
        let worst = worst_difference(&frame.image, &own.image);
        assert!(worst <= 1, "{technique} with exact bounds, no boxes: a pixel differs by {worst}");
        assert_eq!(frame.stats.geometry_passes, own.stats.geometry_passes, "{technique} exact");
        assert_eq!(frame.stats.lost, own.stats.lost, "{technique} exact");
    }
}

/// `--overflow tail` through the embedded pass: the fixed-K techniques' tail pass draws the
/// caller's geometry like their capture, and the frame equals the backend's own on the hardware
/// path (image, fragments, passes, losses and what was merged), with something merged.
#[test]
fn overflow_tail_through_the_embedded_pass_matches_backend_render() {
    let Some(backend) =
        oit_wgpu::backend_or_skip("overflow_tail_through_the_embedded_pass_matches_backend_render")
    else {
        return;
    };
    let gpu = backend.gpu().unwrap();
    let scene = oit_core::load_scene("grid:2x2:spheres:2").unwrap();
    let (w, h) = (64, 48);
    let camera =
        oit_core::Camera::orbit_scene(&scene, oit_core::View::default(), w as f32 / h as f32).unwrap();
    let geometry = oit_wgpu::embed::SceneGeometry::new(&gpu.device, &gpu.queue, &scene).unwrap();
    for technique in [Technique::Fabs { k: Some(2) }, Technique::Mdts64 { k: Some(2) }] {
        let settings = Settings {
            width: w,
            height: h,
            technique,
            overflow: oit_core::Overflow::Tail,
            raster: Some(RasterPath::Hardware),
            ..Settings::default()
        };
        let own = backend.render(&scene, &camera, &settings).unwrap();
        assert!(own.stats.merged > 0, "{technique}: the scene must overflow K for the test to mean anything");
        let pass = oit_wgpu::OitPass::new(&gpu.device, &gpu.queue, settings.clone(), camera)
            .unwrap()
            .with_scene_geometry(&geometry);
        geometry.write_frame(&scene, &camera, &settings);
        let frame = pass
            .frame(
                None,
                |capture| scene_pipeline(&gpu.device, &geometry, capture),
                |rpass, _| {
                    rpass.set_bind_group(1, geometry.bind_group(), &[]);
                    rpass.draw(0..geometry.vertex_count(), 0..1);
                },
            )
            .unwrap();
        let worst = worst_difference(&frame.image, &own.image);
        println!(
            "{technique} tail: worst {worst}; merged {} vs {}, lost {} vs {}",
            frame.stats.merged, own.stats.merged, frame.stats.lost, own.stats.lost
        );
        assert!(worst <= 1, "{technique} tail: a pixel differs by {worst}");
        assert_eq!(frame.stats.fragments, own.stats.fragments, "{technique}");
        assert_eq!(frame.stats.geometry_passes, own.stats.geometry_passes, "{technique}");
        assert_eq!(frame.stats.merged, own.stats.merged, "{technique}");
        assert_eq!(frame.stats.lost, own.stats.lost, "{technique}");
    }
}

/// A scene with an opaque wall through the embedded pass as an embedding renderer runs it: the
/// whole scene uploaded as a `SceneGeometry`, its opaque part drawn first into the geometry's depth
/// and colour (`SceneGeometry::draw_opaque_for`, or `draw_opaque` into the caller's encoder), then
/// its transparent part through the pass. The frame equals `Backend::render`'s of the whole scene
/// on the hardware path: the image byte for byte, the fragments, captured and occluded counts
/// (the same vertex stage and shading on both sides, the same depths and colours in the opaque
/// image), for an exact technique (fabs, also under an alpha override, which changes the blended
/// objects only) and a peel (dp), by `OitPass::frame` and, for fabs:K, `OitPass::record`; and for
/// the wall masked away (`nowall`: nothing drawn into the depth, nothing occluded). The pass runs
/// no opaque geometry pass of its own: two passes fewer.
#[test]
fn caller_opaque_depth_and_colour_match_backend_render() {
    let Some(backend) = oit_wgpu::backend_or_skip("caller_opaque_depth_and_colour_match_backend_render")
    else {
        return;
    };
    let gpu = backend.gpu().unwrap();
    let (w, h) = (64, 48);
    let cases = [
        ("wall:0.5:planes:16", Technique::Fabs { k: None }, None),
        ("wall:0.5:planes:16", Technique::Fabs { k: None }, Some(0.3)),
        ("wall:0.5:planes:16", Technique::Dp, None),
        ("wall:0.5:planes:16", Technique::Fabs { k: Some(4) }, None),
        ("nowall:0.5:planes:16", Technique::Fabs { k: None }, None),
    ];
    for (name, technique, alpha) in cases {
        let scene = oit_core::load_scene(name).unwrap();
        assert!(scene.has_opaque(), "{name}: the scene has a wall");
        let camera =
            oit_core::Camera::orbit_scene(&scene, oit_core::View::default(), w as f32 / h as f32).unwrap();
        let geometry = oit_wgpu::embed::SceneGeometry::new(&gpu.device, &gpu.queue, &scene).unwrap();
        assert!(geometry.has_opaque(), "{name}");
        let settings = Settings {
            width: w,
            height: h,
            technique,
            alpha,
            raster: Some(RasterPath::Hardware),
            ..Settings::default()
        };
        let what = format!("{name} {technique} alpha {alpha:?}");
        let own = backend.render(&scene, &camera, &settings).unwrap();
        if name.starts_with("wall") {
            assert!(own.stats.occluded > 0 && own.stats.captured > 0, "{what}: the wall hides some, not all");
        } else {
            assert_eq!(own.stats.occluded, 0, "{what}: the wall is masked away");
        }
        let mut pass = oit_wgpu::OitPass::new(&gpu.device, &gpu.queue, settings.clone(), camera)
            .unwrap()
            .with_scene_geometry(&geometry);
        geometry.write_frame(&scene, &camera, &settings);
        geometry.draw_opaque_for(&mut pass).unwrap();
        let frame = pass
            .frame(
                None,
                |capture| scene_pipeline(&gpu.device, &geometry, capture),
                |rpass, _| {
                    rpass.set_bind_group(1, geometry.bind_group(), &[]);
                    rpass.draw(0..geometry.vertex_count(), 0..1);
                },
            )
            .unwrap();
        let worst = worst_difference(&frame.image, &own.image);
        println!(
            "{what}: worst {worst}; fragments {} vs {}, captured {} vs {}, occluded {} vs {}, passes {} vs {}",
            frame.stats.fragments,
            own.stats.fragments,
            frame.stats.captured,
            own.stats.captured,
            frame.stats.occluded,
            own.stats.occluded,
            frame.stats.geometry_passes,
            own.stats.geometry_passes
        );
        assert_eq!(worst, 0, "{what}: the image differs");
        assert_eq!(frame.stats.fragments, own.stats.fragments, "{what}");
        assert_eq!(frame.stats.captured, own.stats.captured, "{what}");
        assert_eq!(frame.stats.occluded, own.stats.occluded, "{what}");
        assert_eq!(frame.stats.lost, own.stats.lost, "{what}");
        assert_eq!(frame.stats.geometry_passes + 2, own.stats.geometry_passes, "{what}");
        assert_eq!(frame.stats.opaque_fragments, 0, "{what}: the pass drew no opaque fragment");
        if technique == (Technique::Fabs { k: Some(4) }) {
            // recorded into the caller's encoder after the opaque part, drawn into a target of
            // its own
            let target = gpu.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("recorded target"),
                size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba8Unorm,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            });
            let view = target.create_view(&Default::default());
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            let opaque = geometry.draw_opaque(&mut encoder, &settings).expect("an opaque part");
            // the geometry's depth and colour are kept for frames of a size, made anew for another
            let mut other = gpu.device.create_command_encoder(&Default::default());
            let again = geometry.draw_opaque(&mut other, &settings).unwrap();
            assert_eq!(
                (again.depth.texture(), again.color.texture()),
                (opaque.depth.texture(), opaque.color.texture())
            );
            assert_eq!(opaque.color.texture().format(), oit_wgpu::embed::OPAQUE_COLOR_FORMAT);
            let bigger = Settings { width: w + 8, ..settings.clone() };
            let resized = geometry.draw_opaque(&mut other, &bigger).unwrap();
            assert_ne!(resized.depth.texture(), opaque.depth.texture());
            assert_eq!(resized.depth.texture().width(), w + 8);
            drop(other);
            let opaque = geometry.draw_opaque(&mut encoder, &settings).unwrap();
            pass.set_opaque(Some(&opaque.depth), Some(&opaque.color)).unwrap();
            pass.record(
                &mut encoder,
                &view,
                |capture| scene_pipeline(&gpu.device, &geometry, capture),
                |rpass, _| {
                    rpass.set_bind_group(1, geometry.bind_group(), &[]);
                    rpass.draw(0..geometry.vertex_count(), 0..1);
                },
            )
            .unwrap();
            gpu.queue.submit([encoder.finish()]);
            let stats = pass.read_stats().unwrap();
            assert_eq!(stats.captured, own.stats.captured, "{what} recorded");
            assert_eq!(stats.occluded, own.stats.occluded, "{what} recorded");
            let image = read_rgba8(gpu, &target);
            assert_eq!(image.pixels, own.image.pixels, "{what} recorded: the image differs");
        }
    }
}

/// An `Rgba8Unorm` texture's texels, read back.
fn read_rgba8(gpu: &oit_wgpu::Gpu, texture: &wgpu::Texture) -> Image {
    let (w, h) = (texture.width(), texture.height());
    let row = (w * 4).div_ceil(256) * 256;
    let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("read back"),
        size: u64::from(row * h),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: Some(h),
            },
        },
        texture.size(),
    );
    gpu.queue.submit([encoder.finish()]);
    buffer.slice(..).map_async(wgpu::MapMode::Read, |_| ());
    gpu.device.poll(wgpu::PollType::Wait { submission_index: None, timeout: None }).unwrap();
    let bytes = buffer.slice(..).get_mapped_range().unwrap();
    let pixels = (0..h)
        .flat_map(|y| (0..w).map(move |x| (y, x)))
        .map(|(y, x)| {
            let i = (y * row + x * 4) as usize;
            [bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]
        })
        .collect();
    Image { width: w, height: h, pixels }
}

/// `scene` without its opaque and masked instances: what is left is blended only, so
/// `SceneGeometry` uploads it whole, unsplit.
fn blended_only(mut scene: Scene) -> Scene {
    let objects = scene.objects.clone();
    scene.instances.retain(|i| !objects[i.object].is_opaque_pass());
    scene.name = format!("{} (blended only)", scene.name);
    scene
}

/// Textured scenes through `SceneGeometry` and the embedded pass (issue 38): the textures are
/// sampled in the transparent geometry passes and in the opaque part's draw
/// (`SceneGeometry::draw_opaque_for`, masked leaves and the fence's holes discarded there), so the
/// frame equals `Backend::render`'s of the whole scene on the hardware path: the same fragments,
/// captured, occluded and lost counts, and every pixel within 1 in 8 bits (the same vertex stage,
/// sampler and shading on both sides: measured 0); and the exact techniques' images equal the
/// embedded reference's. Scenes: billboards with a soft alpha texture over an opaque backdrop,
/// the same without the backdrop (a textured scene that is not split), the masked fence and the
/// foliage (textured opaque-pass objects, masked by the texture's alpha, beside blended ones).
#[test]
fn textured_scenes_match_backend_render() {
    let Some(backend) = oit_wgpu::backend_or_skip("textured_scenes_match_backend_render") else {
        return;
    };
    let gpu = backend.gpu().unwrap();
    let (w, h) = (64, 48);
    let scenes = [
        oit_core::load_scene("particles:24").unwrap(),
        blended_only(oit_core::load_scene("particles:24").unwrap()),
        oit_core::load_scene("fence").unwrap(),
        oit_core::load_scene("foliage").unwrap(),
    ];
    for scene in &scenes {
        assert!(oit_gpu::is_textured(scene), "{}: textured", scene.name);
        let camera =
            oit_core::Camera::orbit_scene(scene, oit_core::View::default(), w as f32 / h as f32).unwrap();
        let geometry = oit_wgpu::embed::SceneGeometry::new(&gpu.device, &gpu.queue, scene).unwrap();
        assert_eq!(geometry.has_opaque(), scene.has_opaque(), "{}", scene.name);
        let mut reference: Option<Image> = None;
        for (technique, alpha) in [
            (Technique::Reference, None),
            (Technique::Fabs { k: None }, None),
            (Technique::Dfb, None),
            (Technique::Dp, None),
            (Technique::Fabs { k: None }, Some(0.4)),
            (Technique::WeightedAverage, None),
        ] {
            let settings = Settings {
                width: w,
                height: h,
                technique,
                alpha,
                raster: Some(RasterPath::Hardware),
                ..Settings::default()
            };
            let what = format!("{} {technique} alpha {alpha:?}", scene.name);
            let own = backend.render(scene, &camera, &settings).unwrap();
            let mut pass = oit_wgpu::OitPass::new(&gpu.device, &gpu.queue, settings.clone(), camera)
                .unwrap()
                .with_scene_geometry(&geometry);
            geometry.write_frame(scene, &camera, &settings);
            geometry.draw_opaque_for(&mut pass).unwrap();
            let frame = pass
                .frame(
                    None,
                    |capture| scene_pipeline(&gpu.device, &geometry, capture),
                    |rpass, _| {
                        rpass.set_bind_group(1, geometry.bind_group(), &[]);
                        rpass.draw(0..geometry.vertex_count(), 0..1);
                    },
                )
                .unwrap();
            let worst = worst_difference(&frame.image, &own.image);
            println!(
                "{what}: worst {worst}; fragments {} vs {}, captured {} vs {}, occluded {} vs {}, masked {}",
                frame.stats.fragments,
                own.stats.fragments,
                frame.stats.captured,
                own.stats.captured,
                frame.stats.occluded,
                own.stats.occluded,
                own.stats.masked
            );
            assert!(own.stats.fragments > 0, "{what}: something drawn");
            assert!(worst <= 1, "{what}: a pixel differs by {worst}");
            assert_eq!(frame.stats.fragments, own.stats.fragments, "{what}");
            assert_eq!(frame.stats.captured, own.stats.captured, "{what}");
            assert_eq!(frame.stats.occluded, own.stats.occluded, "{what}");
            assert_eq!(frame.stats.lost, own.stats.lost, "{what}");
            if alpha.is_none() {
                match (technique.is_exact(), &reference) {
                    (_, None) => reference = Some(frame.image.clone()),
                    (true, Some(r)) => {
                        let differ = frame.image.pixels.iter().zip(&r.pixels).filter(|(a, b)| a != b).count();
                        assert_eq!(
                            differ, 0,
                            "{what}: an exact technique's image differs from the reference's"
                        );
                    }
                    (false, Some(_)) => {}
                }
            }
        }
    }
}

/// The textured scene's untextured twin draws other colours: the textures are what the
/// frames above sample (a pass that ignored them would match neither).
#[test]
fn textures_change_the_embedded_image() {
    let Some(backend) = oit_wgpu::backend_or_skip("textures_change_the_embedded_image") else {
        return;
    };
    let gpu = backend.gpu().unwrap();
    let (w, h) = (64, 48);
    let settings = Settings {
        width: w,
        height: h,
        technique: Technique::Reference,
        raster: Some(RasterPath::Hardware),
        ..Settings::default()
    };
    let mut images = Vec::new();
    for name in ["fence", "untextured:fence"] {
        let scene = oit_core::load_scene(name).unwrap();
        let camera =
            oit_core::Camera::orbit_scene(&scene, oit_core::View::default(), w as f32 / h as f32).unwrap();
        let geometry = oit_wgpu::embed::SceneGeometry::new(&gpu.device, &gpu.queue, &scene).unwrap();
        let mut pass = oit_wgpu::OitPass::new(&gpu.device, &gpu.queue, settings.clone(), camera)
            .unwrap()
            .with_scene_geometry(&geometry);
        geometry.write_frame(&scene, &camera, &settings);
        geometry.draw_opaque_for(&mut pass).unwrap();
        let frame = pass
            .frame(
                None,
                |capture| scene_pipeline(&gpu.device, &geometry, capture),
                |rpass, _| {
                    rpass.set_bind_group(1, geometry.bind_group(), &[]);
                    rpass.draw(0..geometry.vertex_count(), 0..1);
                },
            )
            .unwrap();
        images.push(frame.image);
    }
    let differ = images[0].pixels.iter().zip(&images[1].pixels).filter(|(a, b)| a != b).count();
    println!("fence against untextured:fence: {differ} pixels differ");
    assert!(differ > 100, "the fence's texture changes the image: {differ} pixels differ");
}

/// A caller's own multisampled fragment stage over `SceneGeometry`'s vertex stage: it takes
/// `@builtin(sample_mask)` and returns `oit_capture_samples`, as docs/embedding.md shows.
const USER_MASKED_WGSL: &str = "
@fragment
fn user_fs(in: HwOut, @builtin(front_facing) front: bool, @builtin(sample_mask) mask: u32) -> OitSampled {
    if (hw_culled(in, front)) {
        discard;
    }
    return oit_capture_samples(in.position.xy, in.position.z, hw_color(in), in.normal, in.prim, mask);
}
";

/// [`scene_pipeline`] with the caller's fragment stage [`USER_MASKED_WGSL`].
fn user_masked_pipeline(
    device: &wgpu::Device,
    geometry: &oit_wgpu::embed::SceneGeometry,
    capture: &oit_wgpu::CaptureShader<'_>,
) -> wgpu::RenderPipeline {
    let source = format!("{}\n{}\n{USER_MASKED_WGSL}", capture.wgsl, oit_wgpu::embed::SceneGeometry::WGSL);
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("caller's masked stage"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: None,
        bind_group_layouts: &[Some(capture.bind_group_layout), Some(geometry.bind_group_layout())],
        immediate_size: 0,
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("caller's masked stage"),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("hw_vs"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
        depth_stencil: None,
        multisample: capture.multisample,
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("user_fs"),
            compilation_options: Default::default(),
            targets: &[Some(capture.count_target.clone())],
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// The caller's own multisampled stage ([`USER_MASKED_WGSL`], through `oit_capture_samples`)
/// counts each fragment once: its output sample mask writes the count target at one covered
/// sample, so the target's samples add up to the fragments (`count_sum_texture_ms.wgsl`). On the
/// knot at 64² most fragments cover several samples, so a stage that wrote every covered sample
/// would count more fragments than the internal hardware path and fail the frame's accounting.
/// (`multisampled_pass_matches_backend_render`'s spheres at 64×48 do not tell the two apart:
/// their triangles are smaller than the samples' spacing, so each fragment covers one sample and
/// writing every covered sample changed no count, on lavapipe or on an H100.) Mutation tried:
/// `written = mask` in `oit_capture_samples`.
#[test]
fn callers_masked_stage_counts_each_fragment_once() {
    let Some(backend) = oit_wgpu::backend_or_skip("callers_masked_stage_counts_each_fragment_once") else {
        return;
    };
    let gpu = backend.gpu().unwrap();
    let scene = oit_core::load_scene("knot").unwrap();
    let (w, h) = (64, 64);
    let camera = oit_core::Camera::orbit_scene(&scene, oit_core::View::default(), 1.0).unwrap();
    let geometry = oit_wgpu::embed::SceneGeometry::new(&gpu.device, &gpu.queue, &scene).unwrap();
    for technique in [Technique::Reference, Technique::Ll] {
        let settings = Settings {
            width: w,
            height: h,
            technique,
            samples: 4,
            raster: Some(RasterPath::Hardware),
            ..Settings::default()
        };
        let own = backend.render(&scene, &camera, &settings).unwrap();
        let pass = oit_wgpu::OitPass::new(&gpu.device, &gpu.queue, settings.clone(), camera)
            .unwrap()
            .with_scene_geometry(&geometry);
        geometry.write_frame(&scene, &camera, &settings);
        let user = pass.frame(
            None,
            |capture| user_masked_pipeline(&gpu.device, &geometry, capture),
            |rpass, _| {
                rpass.set_bind_group(1, geometry.bind_group(), &[]);
                rpass.draw(0..geometry.vertex_count(), 0..1);
            },
        );
        let user = user.unwrap_or_else(|e| panic!("{technique}: the caller's stage: {e}"));
        println!(
            "{technique} on the knot at 4 samples: fragments {} (the caller's stage), {} (oit's)",
            user.stats.fragments, own.stats.fragments
        );
        assert_eq!(user.stats.fragments, own.stats.fragments, "{technique}: fragments");
        assert_eq!(user.stats.captured, own.stats.captured, "{technique}: captured");
        assert_eq!(worst_difference(&user.image, &own.image), 0, "{technique}: the image");
    }
}

/// The embedded pass at several samples a pixel (issue 40.5): a multisampled count target, the
/// capture's multisample state in the caller's pipeline, and `hw_fs_masked` handing the capture
/// each fragment's `sample_mask`. At `--samples 4` the frame equals `Backend::render`'s on the
/// hardware path at `--samples 4` (the same fragments, captured and lost counts, no pixel more
/// than 1 in 8 bits apart: measured 0), by `OitPass::frame` and, for fabs:4, `OitPass::record`;
/// the exact techniques' images equal the embedded reference's; the image is not the
/// single-sampled one (edges are resolved per sample). A technique that takes no samples is
/// refused by name, as `Backend::render` refuses it, and so is a count the pass was not told the
/// device draws.
#[test]
fn multisampled_pass_matches_backend_render() {
    let Some(backend) = oit_wgpu::backend_or_skip("multisampled_pass_matches_backend_render") else {
        return;
    };
    let gpu = backend.gpu().unwrap();
    let scene = oit_core::load_scene("grid:2x2:spheres:2").unwrap();
    let (w, h) = (64, 48);
    let camera =
        oit_core::Camera::orbit_scene(&scene, oit_core::View::default(), w as f32 / h as f32).unwrap();
    let geometry = oit_wgpu::embed::SceneGeometry::new(&gpu.device, &gpu.queue, &scene).unwrap();
    let run = |pass: &oit_wgpu::OitPass, settings: &Settings| {
        geometry.write_frame(&scene, &camera, settings);
        pass.frame(
            None,
            |capture| {
                assert_eq!(capture.multisample.count, settings.samples, "the capture's multisample state");
                scene_pipeline(&gpu.device, &geometry, capture)
            },
            |rpass, _| {
                rpass.set_bind_group(1, geometry.bind_group(), &[]);
                rpass.draw(0..geometry.vertex_count(), 0..1);
            },
        )
    };
    let mut reference: Option<Image> = None;
    for technique in [
        Technique::Reference,
        Technique::Fabs { k: None },
        Technique::Dfb,
        Technique::Ll,
        Technique::Fabs { k: Some(4) },
        // no mask: each fragment's alpha weighted by its coverage fraction (docs/msaa.md)
        Technique::Dp,
        Technique::WeightedAverage,
    ] {
        let settings = Settings {
            width: w,
            height: h,
            technique,
            samples: 4,
            raster: Some(RasterPath::Hardware),
            ..Settings::default()
        };
        let what = format!("{technique} at --samples 4");
        let own = backend.render(&scene, &camera, &settings).unwrap();
        let pass = oit_wgpu::OitPass::new(&gpu.device, &gpu.queue, settings.clone(), camera)
            .unwrap()
            .with_scene_geometry(&geometry);
        let frame = run(&pass, &settings).unwrap();
        let worst = worst_difference(&frame.image, &own.image);
        println!(
            "{what}: worst {worst}; fragments {} vs {}, captured {} vs {}, lost {} vs {}",
            frame.stats.fragments,
            own.stats.fragments,
            frame.stats.captured,
            own.stats.captured,
            frame.stats.lost,
            own.stats.lost
        );
        assert!(worst <= 1, "{what}: a pixel differs by {worst}");
        assert_eq!(frame.stats.fragments, own.stats.fragments, "{what}");
        assert_eq!(frame.stats.captured, own.stats.captured, "{what}");
        assert_eq!(frame.stats.lost, own.stats.lost, "{what}");
        assert_eq!(frame.stats.geometry_passes, own.stats.geometry_passes, "{what}");
        assert_eq!(frame.stats.storage_bytes, own.stats.storage_bytes, "{what}");
        assert_eq!(frame.stats.coverage, own.stats.coverage, "{what}: the coverage said");
        assert!(frame.stats.coverage.is_some(), "{what}: the coverage said");
        if matches!(technique, Technique::Dp | Technique::WeightedAverage) {
            // approximations of the per-sample reference, held to it in tests/tests/msaa.rs
            continue;
        }
        // fabs:4 keeps 4 fragments a pixel: approximate here, the others exact
        let exact = technique != Technique::Fabs { k: Some(4) };
        match (exact, &reference) {
            (_, None) => reference = Some(frame.image.clone()),
            (true, Some(r)) => {
                let differ = frame.image.pixels.iter().zip(&r.pixels).filter(|(a, b)| a != b).count();
                assert_eq!(differ, 0, "{what}: an exact technique's image differs from the reference's");
            }
            (false, Some(_)) => assert!(frame.stats.lost > 0, "{what}: K is exceeded"),
        }
        if technique == Technique::Reference {
            // the caller's own fragment stage through `oit_capture_samples`
            geometry.write_frame(&scene, &camera, &settings);
            let user = pass
                .frame(
                    None,
                    |capture| user_masked_pipeline(&gpu.device, &geometry, capture),
                    |rpass, _| {
                        rpass.set_bind_group(1, geometry.bind_group(), &[]);
                        rpass.draw(0..geometry.vertex_count(), 0..1);
                    },
                )
                .unwrap();
            let worst = worst_difference(&user.image, &own.image);
            println!(
                "{what}, the caller's oit_capture_samples: worst {worst}, fragments {}",
                user.stats.fragments
            );
            assert!(worst <= 1, "{what}, oit_capture_samples: a pixel differs by {worst}");
            assert_eq!(user.stats.fragments, own.stats.fragments, "{what}, oit_capture_samples");
            // the storage is sized from the count target: one count a fragment, not a sample
            assert_eq!(user.stats.storage_bytes, own.stats.storage_bytes, "{what}, oit_capture_samples");
            assert_eq!(user.stats.max_layers, own.stats.max_layers, "{what}, oit_capture_samples");
        }
        if technique == (Technique::Fabs { k: Some(4) }) {
            let target = gpu.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("recorded target"),
                size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba8Unorm,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            });
            let view = target.create_view(&Default::default());
            geometry.write_frame(&scene, &camera, &settings);
            gpu.queue.submit([]);
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            pass.record(
                &mut encoder,
                &view,
                |capture| scene_pipeline(&gpu.device, &geometry, capture),
                |rpass, _| {
                    rpass.set_bind_group(1, geometry.bind_group(), &[]);
                    rpass.draw(0..geometry.vertex_count(), 0..1);
                },
            )
            .unwrap();
            gpu.queue.submit([encoder.finish()]);
            let stats = pass.read_stats().unwrap();
            assert_eq!(stats.captured, own.stats.captured, "{what} recorded");
            assert_eq!(
                read_rgba8(gpu, &target).pixels,
                own.image.pixels,
                "{what} recorded: the image differs"
            );
        }
    }
    // the samples resolve the edges: the single-sampled reference is another image
    let reference = reference.unwrap();
    let settings1 = Settings {
        width: w,
        height: h,
        technique: Technique::Reference,
        raster: Some(RasterPath::Hardware),
        ..Settings::default()
    };
    let pass = oit_wgpu::OitPass::new(&gpu.device, &gpu.queue, settings1.clone(), camera)
        .unwrap()
        .with_scene_geometry(&geometry);
    let one = run(&pass, &settings1).unwrap();
    let differ = one.image.pixels.iter().zip(&reference.pixels).filter(|(a, b)| a != b).count();
    println!("reference at 1 sample against 4: {differ} pixels differ");
    assert!(differ > 20, "at 4 samples the edges are resolved per sample: {differ} pixels differ");
    // refused by name: 8 samples where the pass was not told the device draws them
    let (technique, samples) = (Technique::Reference, 8);
    let settings = Settings { width: w, height: h, technique, samples, ..Settings::default() };
    let pass = oit_wgpu::OitPass::new(&gpu.device, &gpu.queue, settings.clone(), camera)
        .unwrap()
        .with_scene_geometry(&geometry);
    match run(&pass, &settings) {
        Err(OitError::Unsupported { what, .. }) => {
            assert!(what.contains("with_adapter"), "{technique} {samples}: {what}")
        }
        other => {
            panic!("{technique} at {samples} samples: expected Unsupported, got {:?}", other.map(|f| f.stats))
        }
    }
}
