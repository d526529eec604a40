//! A wgpu user's own scene through oit's embeddable pass: the user opens the device, owns the
//! vertex buffer, the vertex shader (world → clip on the GPU with their own uniform) and the draw
//! call; oit supplies the capture module, its storage, and the resolve into the user's texture.
//!
//! As a renderer does, the user draws their opaque geometry first (a grey wall, with a trivial
//! pipeline of their own, into their colour target and depth buffer), then runs the OIT pass with
//! that depth and colour ([`OitPass::with_opaque`]): the transparent quads behind the wall are
//! cut (counted as occluded) and the rest composite over the wall and the cleared target.
//!
//! `cargo run -p oit-wgpu --example embed -- [technique] [out.png]` (default `fabs`, `embed.png`).

use glam::{Mat4, Vec3, Vec4};
use oit_core::{Aabb, Camera, Frame, Image, OitError, Settings, Technique};
use oit_wgpu::{CaptureShader, GeometryPass, OitPass};
use wgpu::util::DeviceExt;

/// Image side.
pub const SIZE: u32 = 128;

/// The user's scene: three translucent quads (corners, colour), two of them cutting through each
/// other, so the order of the fragments changes across each pixel row.
pub fn quads() -> Vec<([Vec3; 4], Vec4)> {
    let quad = |m: Mat4, color: Vec4| {
        let c = [
            Vec3::new(-1.0, -0.8, 0.0),
            Vec3::new(1.0, -0.8, 0.0),
            Vec3::new(1.0, 0.8, 0.0),
            Vec3::new(-1.0, 0.8, 0.0),
        ];
        (c.map(|p| m.transform_point3(p)), color)
    };
    vec![
        quad(Mat4::from_rotation_y(0.6), Vec4::new(0.9, 0.15, 0.1, 0.5)),
        quad(Mat4::from_rotation_y(-0.6), Vec4::new(0.1, 0.8, 0.2, 0.5)),
        quad(
            Mat4::from_translation(Vec3::new(0.3, 0.2, -0.7)) * Mat4::from_scale(Vec3::splat(0.8)),
            Vec4::new(0.15, 0.3, 0.95, 0.6),
        ),
    ]
}

/// Each quad's two triangles, as indices into its corners (triangle `t` of quad `q` is
/// primitive `2q + t`).
pub const QUAD_TRIANGLES: [[u32; 3]; 2] = [[0, 1, 2], [0, 2, 3]];

/// The user's camera.
pub fn camera() -> Camera {
    Camera::look_at(Vec3::new(0.4, 0.5, 3.5), Vec3::ZERO, 45.0, 1.0, 1.0, 8.0)
}

/// The user's opaque wall: a grey quad standing in the scene, turned so that the red quad passes
/// through it (corners, linear RGB).
pub fn wall() -> ([Vec3; 4], Vec3) {
    let m = Mat4::from_translation(Vec3::new(0.5, 0.0, -0.3)) * Mat4::from_rotation_y(-0.3);
    let c = [
        Vec3::new(-0.6, -1.2, 0.0),
        Vec3::new(0.6, -1.2, 0.0),
        Vec3::new(0.6, 1.2, 0.0),
        Vec3::new(-0.6, 1.2, 0.0),
    ];
    (c.map(|p| m.transform_point3(p)), Vec3::new(0.45, 0.45, 0.42))
}

/// The user's opaque pipeline: their uniform's transform and a constant colour, with a depth test
/// (`Less`) writing their depth buffer. oit never sees it.
const WALL_WGSL: &str = r#"
struct UserUniform { view_proj: mat4x4<f32> }
@group(0) @binding(0) var<uniform> user: UserUniform;

@vertex
fn wall_vs(@location(0) p: vec3<f32>) -> @builtin(position) vec4<f32> {
    return user.view_proj * vec4<f32>(p, 1.0);
}
"#;

/// The user's shader: their vertex stage, and a fragment stage that hands the fragment to oit.
const USER_WGSL: &str = r#"
struct UserUniform { view_proj: mat4x4<f32> }
@group(1) @binding(0) var<uniform> user: UserUniform;

struct UserOut {
    @builtin(position) position: vec4<f32>,
    // flat: each quad's colour exactly as given (interpolating a constant may round it, and
    // bdp keeps 8-bit colours, so a rounding can move a pixel by more than one step)
    @location(0) @interpolate(flat) color: vec4<f32>,
    @location(1) @interpolate(flat) prim: u32,
}

@vertex
fn user_vs(@location(0) p: vec3<f32>, @location(1) c: vec4<f32>, @builtin(vertex_index) i: u32) -> UserOut {
    return UserOut(user.view_proj * vec4<f32>(p, 1.0), c, i / 3u);
}

@fragment
fn user_fs(v: UserOut) -> @location(0) vec4<f32> {
    return oit_capture(v.position.xy, v.position.z, v.color, v.prim);
}
"#;

/// The user's side: their device, vertex buffer, uniform, pipeline layout and target texture.
pub struct User {
    /// The user's device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// The adapter's name.
    pub adapter: String,
    vertex_buf: wgpu::Buffer,
    vertex_count: u32,
    uniform: wgpu::Buffer,
    user_layout: wgpu::BindGroupLayout,
    user_group: wgpu::BindGroup,
    /// The target texture oit's image goes into, where the user draws their opaque wall first.
    pub target: wgpu::Texture,
    /// The user's depth buffer (`Depth32Float`; the wall's depths, read by oit, not written).
    pub depth: wgpu::Texture,
    wall_vertices: wgpu::Buffer,
    wall_pipeline: wgpu::RenderPipeline,
}

impl User {
    /// Opens the device the user's way, with the features oit needs, and makes their buffers and
    /// a `SIZE × SIZE` target of `format` (usable as a copy destination and a render attachment).
    pub fn new(format: wgpu::TextureFormat) -> Result<User, OitError> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        desc.backends = wgpu::Backends::VULKAN;
        let instance = wgpu::Instance::new(desc);
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            ..Default::default()
        }))
        .map_err(|e| OitError::Device(format!("no adapter: {e}")))?;
        let features =
            oit_wgpu::required_features() | (adapter.features() & wgpu::Features::FLOAT32_BLENDABLE);
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("user"),
            required_features: features,
            // oit's group 0 binds more storage buffers than wgpu's default limit of 8 a stage (the
            // per-pixel state, the technique's arrays, the loss accounting and the opaque image):
            // ask for what the adapter has, as oit's own device does
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|e| OitError::Device(format!("cannot open the device: {e}")))?;

        // The user's vertex buffer (position, RGBA), uniform and target.
        let mut vertices: Vec<f32> = Vec::new();
        for (corners, color) in quads() {
            for i in QUAD_TRIANGLES.iter().flatten() {
                vertices.extend(corners[*i as usize].to_array());
                vertices.extend(color.to_array());
            }
        }
        let vertex_count = (vertices.len() / 7) as u32;
        let vertex_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("user vertices"),
            contents: bytemuck::cast_slice(&vertices),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("user uniform"),
            contents: bytemuck::cast_slice(&camera().view_proj().to_cols_array()),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let user_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("user"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let user_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("user"),
            layout: &user_layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: uniform.as_entire_binding() }],
        });
        let target = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("user target"),
            size: wgpu::Extent3d { width: SIZE, height: SIZE, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::COPY_DST
                | wgpu::TextureUsages::COPY_SRC
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        let depth = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("user depth"),
            size: wgpu::Extent3d { width: SIZE, height: SIZE, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Depth32Float,
            // TEXTURE_BINDING: oit loads it
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let (corners, grey) = wall();
        let wall_vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("user wall"),
            contents: bytemuck::cast_slice(
                &QUAD_TRIANGLES.iter().flatten().map(|&i| corners[i as usize].to_array()).collect::<Vec<_>>(),
            ),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let wgsl = format!(
            "{WALL_WGSL}\n@fragment\nfn wall_fs() -> @location(0) vec4<f32> {{ return vec4<f32>({:?}, {:?}, {:?}, 1.0); }}\n",
            grey.x, grey.y, grey.z
        );
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("user wall"),
            source: wgpu::ShaderSource::Wgsl(wgsl.into()),
        });
        let wall_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("user wall"),
            bind_group_layouts: &[Some(&user_layout)],
            immediate_size: 0,
        });
        let wall_pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("user wall"),
            layout: Some(&wall_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("wall_vs"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: 3 * 4,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x3],
                })],
            },
            primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: wgpu::TextureFormat::Depth32Float,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("wall_fs"),
                compilation_options: Default::default(),
                targets: &[Some(format.into())],
            }),
            multiview_mask: None,
            cache: None,
        });
        Ok(User {
            device,
            queue,
            adapter: adapter.get_info().name,
            vertex_buf,
            vertex_count,
            uniform,
            user_layout,
            user_group,
            target,
            depth,
            wall_vertices,
            wall_pipeline,
        })
    }

    /// The user's opaque pass, recorded into their `encoder`: the target cleared to the
    /// background and the depth buffer to 1.0, then the wall drawn into both with the user's
    /// camera (their uniform: the same transform the OIT pass's draws use).
    pub fn draw_opaque(&self, encoder: &mut wgpu::CommandEncoder) {
        let bg = Settings::default().background.as_dvec3();
        let color = self.target.create_view(&Default::default());
        let depth = self.depth.create_view(&Default::default());
        let mut rpass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("user opaque"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &color,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color { r: bg.x, g: bg.y, b: bg.z, a: 1.0 }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        rpass.set_pipeline(&self.wall_pipeline);
        rpass.set_bind_group(0, &self.user_group, &[]);
        rpass.set_vertex_buffer(0, self.wall_vertices.slice(..));
        rpass.draw(0..6, 0..1);
    }

    /// `pass` given the user's depth buffer and target as its opaque image.
    pub fn over_opaque(&self, pass: OitPass) -> Result<OitPass, OitError> {
        let depth = self.depth.create_view(&Default::default());
        let color = self.target.create_view(&Default::default());
        pass.with_opaque(&depth, Some(&color))
    }

    /// oit's pass on the user's device for `technique` at `camera`, with the quads' world-space
    /// boxes (for bdp and adp, whose bounds pass oit draws from them).
    pub fn pass(&self, technique: Technique, camera: Camera) -> Result<OitPass, OitError> {
        let settings = Settings { width: SIZE, height: SIZE, technique, ..Settings::default() };
        let boxes: Vec<Aabb> = quads()
            .iter()
            .map(|(corners, _)| {
                let mut b = Aabb::EMPTY;
                corners.iter().for_each(|&c| b.include(c));
                b
            })
            .collect();
        OitPass::new(&self.device, &self.queue, settings, camera)?.with_instance_boxes(&boxes)
    }

    /// The user's pipeline over one of oit's capture modules.
    pub fn pipeline(&self, capture: &CaptureShader<'_>) -> wgpu::RenderPipeline {
        let device = &self.device;
        let attributes = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x4];
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("user + oit"),
            source: wgpu::ShaderSource::Wgsl(format!("{}\n{USER_WGSL}", capture.wgsl).into()),
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("user"),
            bind_group_layouts: &[Some(capture.bind_group_layout), Some(&self.user_layout)],
            immediate_size: 0,
        });
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("user"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("user_vs"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: 7 * 4,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &attributes,
                })],
            },
            // no culling: the back faces are seen through the front ones
            primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
            depth_stencil: None,
            multisample: Default::default(),
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

    /// The user's draws.
    pub fn draw(&self, rpass: &mut wgpu::RenderPass<'_>, _pass: &GeometryPass<'_>) {
        rpass.set_bind_group(1, &self.user_group, &[]);
        rpass.set_vertex_buffer(0, self.vertex_buf.slice(..));
        rpass.draw(0..self.vertex_count, 0..1);
    }

    /// Moves the user's camera (their uniform, written on the queue).
    pub fn set_camera(&self, camera: &Camera) {
        self.queue.write_buffer(&self.uniform, 0, bytemuck::cast_slice(&camera.view_proj().to_cols_array()));
    }

    /// What the user would sample: the target read back (RGBA byte order whatever its format).
    pub fn read_target(&self) -> Result<Image, OitError> {
        let readback = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("user readback"),
            size: u64::from(SIZE * SIZE * 4),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self.device.create_command_encoder(&Default::default());
        encoder.copy_texture_to_buffer(
            self.target.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &readback,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(SIZE * 4),
                    rows_per_image: None,
                },
            },
            self.target.size(),
        );
        self.queue.submit([encoder.finish()]);
        readback.slice(..).map_async(wgpu::MapMode::Read, |_| {});
        self.device
            .poll(wgpu::PollType::Wait { submission_index: None, timeout: None })
            .map_err(|e| OitError::Device(format!("waiting for the GPU failed: {e}")))?;
        let data = readback.slice(..).get_mapped_range().map_err(|e| OitError::Device(e.to_string()))?;
        let bgra = matches!(
            self.target.format(),
            wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
        );
        Ok(Image {
            width: SIZE,
            height: SIZE,
            pixels: data
                .chunks_exact(4)
                .map(|p| if bgra { [p[2], p[1], p[0], p[3]] } else { [p[0], p[1], p[2], p[3]] })
                .collect(),
        })
    }
}

/// Renders the user's scene with `technique` through [`OitPass::frame`]: returns oit's frame and
/// the image read back from the user's target texture, and the adapter's name.
pub fn render(technique: Technique) -> Result<(Frame, Image, String), OitError> {
    let user = User::new(wgpu::TextureFormat::Rgba8Unorm)?;
    let pass = user.pass(technique, camera())?;
    let view = user.target.create_view(&Default::default());
    let frame = pass.frame(Some(&view), |c| user.pipeline(c), |r, p| user.draw(r, p))?;
    Ok((frame, user.read_target()?, user.adapter.clone()))
}

/// Renders the user's wall and then their quads with `technique` through [`OitPass::frame`]
/// over the wall's depth and colour, into an `Rgba8UnormSrgb` target (the wall's linear colour
/// stored encoded, decoded again by oit's load): returns oit's frame, the target read back and
/// the adapter's name.
pub fn render_over_wall(technique: Technique) -> Result<(Frame, Image, String), OitError> {
    let user = User::new(wgpu::TextureFormat::Rgba8UnormSrgb)?;
    let mut encoder = user.device.create_command_encoder(&Default::default());
    user.draw_opaque(&mut encoder);
    user.queue.submit([encoder.finish()]);
    let pass = user.over_opaque(user.pass(technique, camera())?)?;
    let view = user.target.create_view(&Default::default());
    let frame = pass.frame(Some(&view), |c| user.pipeline(c), |r, p| user.draw(r, p))?;
    Ok((frame, user.read_target()?, user.adapter.clone()))
}

/// The camera of frame `i` of the loop: orbiting the quads, a degree a frame.
pub fn orbit(i: u32) -> Camera {
    let angle = (i as f32).to_radians();
    let eye = glam::Quat::from_rotation_y(angle) * Vec3::new(0.4, 0.5, 3.5);
    Camera::look_at(eye, Vec3::ZERO, 45.0, 1.0, 1.0, 8.0)
}

/// A frame loop as a real application runs it: each frame the camera moves, the user writes
/// their uniform, draws their wall into their target and depth buffer, oit records into the
/// user's encoder over them ([`OitPass::record`]: nothing submitted, nothing read back) and draws
/// the image into the same target, the user submits. Returns frames per second over `frames` frames after
/// one warm-up frame (waited for before and after the timed loop), and the pass's allocations
/// after the warm-up and at the end.
pub fn frame_loop(technique: Technique, frames: u32) -> Result<(f64, u64, u64), OitError> {
    let user = User::new(wgpu::TextureFormat::Rgba8UnormSrgb)?;
    let mut pass = user.over_opaque(user.pass(technique, orbit(0))?)?;
    let view = user.target.create_view(&Default::default());
    let one = |pass: &mut OitPass, i: u32| -> Result<(), OitError> {
        let camera = orbit(i);
        pass.set_view(pass.settings().clone(), camera)?;
        user.set_camera(&camera);
        let mut encoder = user.device.create_command_encoder(&Default::default());
        user.draw_opaque(&mut encoder);
        pass.record(&mut encoder, &view, |c| user.pipeline(c), |r, p| user.draw(r, p))?;
        user.queue.submit([encoder.finish()]);
        Ok(())
    };
    let wait = || {
        user.device
            .poll(wgpu::PollType::Wait { submission_index: None, timeout: None })
            .map_err(|e| OitError::Device(format!("waiting for the GPU failed: {e}")))
    };
    one(&mut pass, 0)?;
    wait()?;
    let warm = pass.allocations();
    let start = std::time::Instant::now();
    for i in 1..=frames {
        one(&mut pass, i)?;
    }
    wait()?;
    let fps = f64::from(frames) / start.elapsed().as_secs_f64();
    Ok((fps, warm, pass.allocations()))
}

fn main() -> Result<(), OitError> {
    let mut args = std::env::args().skip(1);
    let technique: Technique = args.next().as_deref().unwrap_or("fabs:8").parse()?;
    let out = args.next().unwrap_or_else(|| "embed.png".into());
    let (frame, image, adapter) = render_over_wall(technique)?;
    image.save_png(std::path::Path::new(&out))?;
    let s = &frame.stats;
    println!(
        "{technique} on {adapter}, over the user's wall: {} fragments ({} captured, {} behind the wall, {} lost), \
         {} geometry passes, gpu {:?} ms, wrote {out}",
        s.fragments, s.captured, s.occluded, s.lost, s.geometry_passes, s.gpu_ms
    );
    match frame_loop(technique, 120) {
        Ok((fps, warm, end)) => println!(
            "{technique}, recorded into the user's encoder, camera orbiting: {fps:.1} frames per second over 120 frames \
             ({SIZE}×{SIZE}; buffers created: {warm} after the first frame, {end} after the loop)"
        ),
        Err(OitError::Unsupported { what, .. }) => println!("no frame loop for {technique}: {what}"),
        Err(e) => return Err(e),
    }
    Ok(())
}
