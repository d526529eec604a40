//! oit's one GPU layer: the frame contract both GPU backends implement ([`Frame`]), and every
//! technique's GPU frame written once against it ([`technique`]).
//!
//! oit-wgpu and oit-vulkan run the same WGSL (oit-shaders) through two device APIs. What a
//! technique does on the GPU — which per-pixel arrays it allocates, which geometry passes and
//! pixel kernels it runs in which order, what it reads back or leaves on the device for the
//! frame's end — is the same on both, so it is written here once: [`technique::render`] runs the
//! frame of the settings' technique on any [`Frame`]. A backend implements [`Frame`] (storage,
//! passes, kernels, read-backs, the speculation it keeps between frames) and runs, beside this,
//! only what its API alone can do: the hardware path's blend, depth-test and logic-op captures,
//! storage-image atomics, the interlock. Those are reached through the contract too
//! ([`Frame::storage_image`], [`Frame::histogram_capture`]), so a technique chooses them here and
//! a backend that lacks one refuses by name.
//!
//! Static dispatch: a technique is generic over `F: Frame<R>`, where `R` is the backend's
//! rasterizer type (the compute path's or the GPU's own), so nothing is boxed per pass.
//!
//! What a backend computes on the host before its passes is the same on both and runs without a
//! device: the frame uniform ([`FrameUniform`]), the compute rasterizer's input ([`host_setup`]:
//! the set-up triangles and one work item per triangle and [`TILE`]² screen tile), and the
//! workgroups of a pixel kernel ([`dispatch_size`]):
//!
//! ```
//! use oit_core::{load_scene, plan::Plan, Camera, Settings, View};
//!
//! let scene = load_scene("planes:4")?;
//! let camera = Camera::orbit_scene(&scene, View::default(), 1.0)?;
//! let settings = Settings { width: 64, height: 64, ..Settings::default() };
//! let plan = Plan::new("my-backend", &scene, &settings)?;
//! let uniform = oit_gpu::FrameUniform::new(&scene, &camera, &settings, &plan);
//! assert_eq!(uniform.pixel_count, 64 * 64);
//! let (_words, items) = oit_gpu::host_setup(&scene, &camera, &settings, false);
//! assert!(!items.is_empty());
//! assert_eq!(oit_gpu::dispatch_size(64 * 64), (64, 1));
//! # Ok::<(), oit_core::OitError>(())
//! ```
//!
//! Adding a technique: its plan (`oit_core::plan`), its WGSL and a manifest line in oit-shaders,
//! its CPU capture in oit-cpu, and its GPU frame as one function in [`technique`] with its line
//! in [`technique::render`]'s match; `docs/architecture.md` works one through.

/// The crate's README (what crates.io shows), whose example runs as a doc test with these.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

pub mod technique;

use bytemuck::{Pod, Zeroable};
use oit_core::plan::Plan;
use oit_core::{Camera, Effect, GpuFragments, OitError, Scene, Settings};

/// [`FrameUniform::opaque`]'s w in a frame's first scene pass: the compute rasterizer marks each
/// work item that captured nothing (raster_compute.wgsl's `mark_item`).
pub const MARKS_WRITE: u32 = 1;
/// [`FrameUniform::opaque`]'s w in a frame's later scene passes: the compute rasterizer skips the
/// marked work items (raster_compute.wgsl's `load_item`).
pub const MARKS_READ: u32 = 2;

/// [`FrameUniform::opaque`]'s w for a geometry pass: [`MARKS_WRITE`] where it is the frame's
/// first scene pass (`first`: no pass has counted the frame's fragments yet), else
/// [`MARKS_READ`]. Both backends set it so; a rasterizer whose items no writing pass marked in the
/// frame reads none (its setup writes them afresh).
pub fn item_marks(first: bool) -> u32 {
    if first { MARKS_WRITE } else { MARKS_READ }
}

/// Whether a compute-raster geometry pass with `uniform` first runs raster_compute.wgsl's
/// `classify_main` over its work items (one invocation an item, as `raster_loop_main`): in the
/// frame's first scene pass ([`MARKS_WRITE`]) over an opaque part whose cut it counts, at one
/// sample a pixel. That kernel counts the fragments of the items wholly behind the opaque depth
/// and wholly inside their triangles without the pass walking their pixels. Both backends ask
/// here.
pub fn classifies_items(uniform: &FrameUniform) -> bool {
    uniform.opaque[1] != 0 && uniform.opaque[3] == MARKS_WRITE && uniform.msaa[0] <= 1
}

/// The opaque pass's module (`opaque.wgsl`), whose passes time under their own label
/// ([`geometry_label`]).
pub const OPAQUE_MODULE: &str = "opaque";

/// The GPU time label of a geometry pass of `module`: `"opaque"` for the opaque pass's two
/// passes (`opaque.wgsl`, [`technique::opaque_pass`]), so a frame's pass times show what drawing
/// its opaque part costs apart from the transparent capture; `"geometry"` for every other.
/// Both backends label by it (oit-vulkan also times `classify_main` apart, as `"classify"`; in
/// oit-wgpu it shares its pass's compute pass and label).
pub fn geometry_label(module: &str) -> &'static str {
    if module == OPAQUE_MODULE { "opaque" } else { "geometry" }
}

/// Group 0's binding of the loss accounting (`acct` in prelude.wgsl).
pub const ACCT_BINDING: u32 = 15;

/// A blend capture's entry point (oit-shaders' `technique/blend.wgsl`, `technique/bdp_blend.wgsl`:
/// `..._fs`, `..._resolve_main`) for a frame of `samples` samples a pixel: above one, its
/// multisampled twin, `_ms` before that ending (`plain_blend_ms_fs`, `bdp_blend_ms_resolve_main`;
/// docs/msaa.md, "The blend captures at several samples"). Both GPU backends run them.
pub fn blend_entry(entry: &str, samples: u32) -> String {
    if samples > 1 {
        for end in ["_fs", "_resolve_main"] {
            if let Some(stem) = entry.strip_suffix(end) {
                return format!("{stem}_ms{end}");
            }
        }
    }
    entry.into()
}

/// Bytes a pixel of the GPU supersampled reference's running sums (`core/supersample.wgsl`): two
/// sums of linear RGB in f32, used in turn, so a frame that runs again after a wrong guess at its
/// sizes does not add its colour twice.
pub const SUPERSAMPLE_SUM_BYTES: u64 = 24;

/// The GPU backends' supersampled reference (`--supersample`, docs/msaa.md), written once: oit-core's
/// frames ([`oit_core::msaa::supersample_frames`]: one single-sample reference frame a sample
/// position, under a moved projection), each rendered by `frame(i, n, camera, single)` (the
/// backend adds the frame's linear colours into its running sums and the last, `i + 1 == n`,
/// writes their mean), their stats added up as [`oit_core::msaa::SupersampleTotals`] says; the
/// image is the last frame's. Stops at the first frame that fails.
pub fn supersampled(
    camera: &Camera,
    settings: &Settings,
    single_path: oit_core::RasterPath,
    mut frame: impl FnMut(u32, u32, &Camera, &Settings) -> Result<oit_core::Frame, OitError>,
) -> Result<oit_core::Frame, OitError> {
    let (single, cameras) = oit_core::msaa::supersample_frames(camera, settings);
    let single = Settings { raster: Some(single_path), ..single };
    let n = cameras.len() as u32;
    let mut totals = oit_core::msaa::SupersampleTotals::default();
    let mut last = None;
    for (i, sample_camera) in cameras.iter().enumerate() {
        let f = frame(i as u32, n, sample_camera, &single)?;
        totals.add(&f.stats, f.layers.as_deref(), f.lost_pixels.as_deref());
        last = Some(f);
    }
    let image = last.map(|f| f.image).unwrap_or(oit_core::Image { width: 0, height: 0, pixels: Vec::new() });
    Ok(oit_core::Frame { image, layers: totals.layers, lost_pixels: totals.lost_pixels, stats: totals.stats })
}

/// Group 0's binding of the opaque pass's keys (`opaque_keys` in prelude.wgsl): each sample's
/// nearest opaque `depth bits << 32 | primitive id` as one u64 (one sample a pixel at
/// `--samples 1`; sample i of pixel p at p · samples + i), all ones where none fell.
pub const OPAQUE_KEYS_BINDING: u32 = 16;

/// Group 0's binding of the opaque pass's colours (`opaque_rgb` in prelude.wgsl): 3 words a
/// sample (the winner's linear RGB, f32 bits), then [`OPAQUE_COUNTER_WORDS`] counters.
pub const OPAQUE_RGB_BINDING: u32 = 17;

/// Counters after the opaque colours: [masked, occluded, drawn] (drawn: the fragments the hardware
/// path's count-only draw counted, [`opaque_drawn_offset`]).
pub const OPAQUE_COUNTER_WORDS: u64 = 3;

/// Words of the opaque keys' buffer of a `width`×`height` frame at `samples` samples a pixel (2 a
/// sample), and of its colours' (3 a sample, the counters, then a word a [`TILE`]×[`TILE`] tile:
/// [`opaque_tiles`]): together [`oit_core::plan::OPAQUE_BYTES`] a sample ([`Plan::opaque_bytes`]
/// a pixel), and the counters and tiles (bookkeeping: a word for 64 pixels).
pub fn opaque_words(width: u32, height: u32, samples: u32) -> (u64, u64) {
    let samples = u64::from(width) * u64::from(height) * u64::from(samples.max(1));
    (samples.max(1) * 2, samples * 3 + OPAQUE_COUNTER_WORDS + opaque_tiles(width, height))
}

/// The compute rasterizer's tiles of a `width`×`height` frame ([`TILE`] pixels a side), each with
/// a word after the opaque colours' counters: the complement of the farthest opaque depth (its
/// bits) of any sample of the tile, written after the opaque pass (`opaque_tiles_main` of
/// opaque.wgsl), so that a work item whose triangle lies wholly behind it is skipped
/// (raster_compute.wgsl; 0, the buffer's clear value, skips nothing).
pub fn opaque_tiles(width: u32, height: u32) -> u64 {
    u64::from(width.div_ceil(TILE)) * u64::from(height.div_ceil(TILE))
}

/// The byte offset of the opaque colours' counters ([`OPAQUE_COUNTER_WORDS`]) in their buffer:
/// after 3 words a sample (`opaque_counter` in prelude.wgsl).
pub fn opaque_counters_offset(pixels: u64, samples: u32) -> u64 {
    pixels * u64::from(samples.max(1)) * 12
}

/// The byte offset in the opaque colours' buffer of the counter in which the hardware path's
/// count-only draw (`core/raster_hardware_early.wgsl`'s `hw_fs_count`, `opaque_counter(2u)`)
/// counts the fragments of a frame's first scene pass: its pass copies it to its fragment count
/// instead of summing its count target, which that draw does not write.
pub fn opaque_drawn_offset(pixels: u64, samples: u32) -> u64 {
    opaque_counters_offset(pixels, samples) + 2 * 4
}

/// Words of one `PixelState` (resolve.wgsl): 16 for the composite, 7 for the ties; the state
/// buffer keeps them as this many planes of a word a pixel (`load_state`/`store_state`).
pub const STATE_WORDS: u64 = 23;

/// The fewest words a storage buffer holds: 64 bytes, one of the widest elements any technique
/// binds, so that an array sized from zero fragments still binds.
pub const MIN_BUFFER_WORDS: u64 = 16;

/// The compute rasterizer's screen tile (pixels a side): `raster_compute.wgsl`'s `TILE`.
pub const TILE: u32 = 8;

/// The frame uniform (`FrameUniform` in fragment.wgsl), group 0, binding 0.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct FrameUniform {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Which pass of the technique this is.
    pub pass_index: u32,
    /// A technique parameter (K, M, a batch, a fill value...).
    pub param: u32,
    /// The effect, as `EFFECT_*` in fragment.wgsl.
    pub effect: u32,
    /// width × height.
    pub pixel_count: u32,
    /// 1 when the resolve counts ties (the plan's `count_ties`).
    pub ties: u32,
    /// 1 in the last capture pass the plan allows (`--max-peels`): what it leaves behind is lost.
    pub last_pass: u32,
    /// Camera forward (xyz).
    pub forward: [f32; 4],
    /// Background (rgb).
    pub background: [f32; 4],
    /// near, far, translucency's absorption per unit of length
    /// ([`Scene::absorption_per_length`](oit_core::Scene::absorption_per_length); 0 under the
    /// other effects, which do not read it), unused.
    pub lens: [f32; 4],
    /// The opaque pass ([`oit_core::Scene::layers`]): x 1 where the frame has its image and the
    /// pass's transparent fragments are cut at its depth (`opaque_cut` in prelude.wgsl); y 1 in
    /// the pass that counts the fragments the cut holds back (the frame's first scene pass);
    /// z 1 where the frame has an opaque part (its colour composited behind); w the compute
    /// rasterizer's work-item marks: [`MARKS_WRITE`] in the frame's first scene pass,
    /// [`MARKS_READ`] in its later ones, 0 elsewhere (raster_compute.wgsl's `ITEM_SPENT`).
    pub opaque: [u32; 4],
    /// Multisampling ([`oit_core::msaa`], docs/msaa.md): x the samples a pixel (1, 4 or 8); y the
    /// mask every kept coverage mask is ORed with (every sample under `--coverage pixel`, else
    /// 0), and [`MSAA_FRACTION`] where each fragment's alpha is weighted by its coverage
    /// fraction ([`oit_core::msaa::Coverage::Fraction`]); z and w the sample positions, a byte each (x | y << 4, in 1/16 pixel from the pixel's
    /// top-left corner), samples 0–3 in z and 4–7 in w ([`sample_position_words`]).
    pub msaa: [u32; 4],
}

/// The bit of [`FrameUniform::msaa`]'s y that weights each fragment's alpha by the fraction of
/// its pixel's samples it covers (`coverage_weighted` in fragment.wgsl): the techniques that keep
/// no coverage mask ([`oit_core::msaa::Coverage::Fraction`]).
pub const MSAA_FRACTION: u32 = 1 << 8;

/// The kernels of finish.wgsl that end a frame of `effect` (its image and its totals, one after
/// the other): both in one kernel (`totals_finish_main`, each pixel's state read once), except
/// for the heat map, whose colours are scaled by the deepest pixel's count, a total of the whole
/// frame that `totals_main` must finish first.
pub fn finish_kernels(effect: oit_core::Effect) -> &'static [&'static str] {
    match effect {
        oit_core::Effect::Complexity => &["totals_main", "finish_main"],
        _ => &["totals_finish_main"],
    }
}

/// The sample positions of `samples` samples ([`oit_core::msaa::positions`]) as the frame
/// uniform carries them: sample i's byte (x | y << 4, 1/16 pixel) at bits 8·(i mod 4) of word
/// i / 4.
pub fn sample_position_words(samples: u32) -> [u32; 2] {
    let mut words = [0u32; 2];
    for (i, &(x, y)) in oit_core::msaa::positions(samples).iter().enumerate() {
        words[i / 4] |= (u32::from(x) | u32::from(y) << 4) << (8 * (i % 4));
    }
    words
}

/// Whether any instance of `scene` draws a textured object ([`oit_core::Object::texture`]): the
/// frame then samples textures (texture.wgsl), its compute path sets up on the host
/// ([`host_setup`] packs the textures after the triangles) and its hardware path reads the
/// textures and each triangle's level from group 1's binding 4 ([`TextureRegion`],
/// [`triangle_levels`]).
pub fn is_textured(scene: &Scene) -> bool {
    scene.instances.iter().filter_map(|i| scene.objects.get(i.object)).any(|o| o.texture.is_some())
}

/// Where a compute frame's triangles are set up: by the device's setup kernels (setup.wgsl) or by
/// the host ([`host_setup`]), whose words and work list the frame then uploads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SetupSite {
    /// On the host, whatever the part: a CPU device (lavapipe), or `OIT_HOST_SETUP=1`.
    Host,
    /// On the device, whatever the part's size (textured parts excepted): `OIT_HOST_SETUP=0`, or a
    /// backend told so, as the setup kernels' tests do.
    Device,
    /// On the device, but a part of at most [`HOST_SETUP_TRIANGLES`] triangles on the host: a
    /// GPU's default.
    DeviceUnlessSmall,
}

/// The most triangles a part may have for a GPU to set it up on the host by default
/// ([`SetupSite::DeviceUnlessSmall`]): a wall's quad, a pedestal's box. The device's setup is five
/// kernels, each behind a barrier, whose time hardly depends on the count for so few triangles:
/// 0.19–0.20 ms a part on the H100 (bench/results/h100/setup-split-1024), most of it the vertex
/// kernel's chain of soft-float steps. The host sets up a handful of triangles in microseconds
/// and uploads their words and work list (8 bytes a covered 8×8 tile) with the frame.
pub const HOST_SETUP_TRIANGLES: u64 = 16;

/// Where a compute frame is set up on a device ([`SetupSite`]): as `OIT_HOST_SETUP` says (`1` or
/// `true`: the host; `0` or `false`: the device, for every part), else on the host on a CPU device
/// and on the device, small parts aside, on a GPU.
pub fn setup_site(cpu_device: bool) -> SetupSite {
    setup_site_by(std::env::var("OIT_HOST_SETUP").ok().as_deref(), cpu_device)
}

/// [`setup_site`] with `OIT_HOST_SETUP` given (`None`: unset).
fn setup_site_by(var: Option<&str>, cpu_device: bool) -> SetupSite {
    match env_flag(var) {
        Some(true) => SetupSite::Host,
        Some(false) => SetupSite::Device,
        None if cpu_device => SetupSite::Host,
        None => SetupSite::DeviceUnlessSmall,
    }
}

/// Whether a compute frame of `scene` is set up on the host ([`host_setup`]) rather than by the
/// device's setup kernels: where `site` says the host, for a small part where it says so
/// ([`HOST_SETUP_TRIANGLES`]), and for every textured scene, whose textures and triangles' levels
/// (chosen in f64, which the setup kernels do not port) the host packs after the triangles.
pub fn sets_up_on_host(site: SetupSite, scene: &Scene) -> bool {
    match site {
        SetupSite::Host => true,
        SetupSite::Device => is_textured(scene),
        SetupSite::DeviceUnlessSmall => is_small(scene) || is_textured(scene),
    }
}

/// Whether `scene` draws at most [`HOST_SETUP_TRIANGLES`] triangles over all its instances,
/// counted only until it is over: every frame asks, and a scene may place a million instances.
fn is_small(scene: &Scene) -> bool {
    let mut triangles = 0u64;
    for instance in &scene.instances {
        triangles += scene.instance_parts(instance).1.indices.len() as u64;
        if triangles > HOST_SETUP_TRIANGLES {
            return false;
        }
    }
    true
}

/// Words of a textured triangle's record in the compute path's triangle buffer ([`host_setup`]):
/// its vertices' texture coordinates (6 f32), the word of its level's descriptor in the texture
/// region, its cutoff (f32, `Triangle::cutoff`), the region's first word (its tables).
pub const TEXTURE_RECORD_WORDS: usize = 9;

/// Word of a triangle's record in `TriangleSetup::triangle_words` that [`host_setup`] points at
/// its texture record (the first of the three padding words; 0 where untextured).
pub const TRIANGLE_TEXTURE_WORD: usize = 41;

/// A frame's textures packed into words for the GPU's sampler (texture.wgsl), placed from word
/// `base` of the buffer that holds them: the sRGB decode (256 f32, [`oit_core::texture::srgb_to_linear`])
/// and the alpha decode (code / 255, 256 f32); per texture and level a descriptor of 4 words
/// (first texel word, width, height, `wrap_u | wrap_v << 8`: 0 repeat, 1 mirrored, 2 clamp);
/// the texels, `r | g << 8 | b << 16 | a << 24`, level by level.
#[derive(Clone, Debug)]
pub struct TextureRegion {
    /// The words, to be placed from `base` on.
    pub words: Vec<u32>,
    base: u32,
    /// Per texture: the word (in the buffer) of its level 0's descriptor, and its levels.
    textures: Vec<(u32, u32)>,
}

fn wrap_code(w: oit_core::Wrap) -> u32 {
    match w {
        oit_core::Wrap::Repeat => 0,
        oit_core::Wrap::MirroredRepeat => 1,
        oit_core::Wrap::ClampToEdge => 2,
    }
}

impl TextureRegion {
    /// `textures` packed from word `base` on.
    pub fn new(textures: &[oit_core::Texture], base: u32) -> TextureRegion {
        let mut words: Vec<u32> = oit_core::texture::srgb_to_linear().iter().map(|v| v.to_bits()).collect();
        words.extend((0..256u32).map(|a| (a as f32 / 255.0).to_bits()));
        let levels: usize = textures.iter().map(|t| t.mips().len()).sum();
        let mut texel = base as usize + words.len() + 4 * levels;
        let mut descriptors = Vec::with_capacity(4 * levels);
        let mut firsts = Vec::with_capacity(textures.len());
        for t in textures {
            firsts.push((base + (words.len() + descriptors.len()) as u32, t.level_count()));
            for l in t.mips() {
                descriptors.extend([
                    texel as u32,
                    l.width,
                    l.height,
                    wrap_code(t.wrap[0]) | wrap_code(t.wrap[1]) << 8,
                ]);
                texel += l.texels.len();
            }
        }
        words.extend(descriptors);
        for t in textures {
            for l in t.mips() {
                words.extend(l.texels.iter().map(|c| u32::from_le_bytes(*c)));
            }
        }
        TextureRegion { words, base, textures: firsts }
    }

    /// The region's first word: the tables' (texture.wgsl's `tables`).
    pub fn tables(&self) -> u32 {
        self.base
    }

    /// The word of the descriptor of level `lod` (clamped to the chain, as `Texture::sample`
    /// clamps it) of texture `texture`, or 0 where there is no such texture (untextured).
    pub fn descriptor(&self, texture: u32, lod: u32) -> u32 {
        match self.textures.get(texture as usize) {
            Some(&(first, levels)) => first + 4 * lod.min(levels.saturating_sub(1)),
            None => 0,
        }
    }
}

/// The hardware path's per-triangle levels of a textured frame: per primitive of `scene` (the
/// draw's triangle order), the word of the descriptor in `region` of the level its fragments
/// sample, 0 where untextured, chosen as oit-core's setup chooses it (`texture::level_for`, from
/// the snapped screen area of the same set-up triangles oit-cpu draws): the host runs the
/// frame's setup for it. A triangle that clipping cuts into pieces takes its first piece's level
/// (the GPU clips it itself, into one primitive); one that setup drops (no pixel centre in its
/// box) samples level 0, where the GPU's rasterizer gives it a fragment all the same.
pub fn triangle_levels(
    scene: &Scene,
    camera: &Camera,
    settings: &Settings,
    region: &TextureRegion,
) -> Vec<u32> {
    let setup = oit_core::setup::TriangleSetup::new(scene, camera, settings);
    let (bases, total) = scene.primitive_bases();
    let mut out = vec![0u32; total as usize];
    let mut last = u32::MAX;
    for t in &setup.triangles {
        if t.prim != last
            && let Some(slot) = out.get_mut(t.prim as usize)
        {
            *slot = region.descriptor(t.texture, t.lod);
        }
        last = t.prim;
    }
    // a dropped triangle of a textured object: level 0
    for (inst, &base) in scene.instances.iter().zip(&bases) {
        let (object, mesh) = scene.instance_parts(inst);
        if let Some(t) = object.texture {
            for slot in out.iter_mut().skip(base as usize).take(mesh.indices.len()) {
                if *slot == 0 {
                    *slot = region.descriptor(t as u32, 0);
                }
            }
        }
    }
    out
}

/// Whether the compute rasterizer runs a workgroup a work item and an invocation a pixel
/// (`raster_main`: GPUs, where it spreads a large triangle over the device) rather than an
/// invocation a work item walking its tile (`raster_loop_main`: CPU devices, where 64 invocations
/// of one small triangle mostly test nothing). `OIT_RASTER_PER_PIXEL=1` (or `true`) forces the
/// first and `0` (or `false`) the second on any device, so that a CPU device's tests run the
/// GPUs' kernel (tests/tests/raster_kernels.rs); otherwise the device type decides.
pub fn raster_per_pixel(cpu_device: bool) -> bool {
    env_flag(std::env::var("OIT_RASTER_PER_PIXEL").ok().as_deref()).unwrap_or(!cpu_device)
}

/// A yes-or-no variable's value (`OIT_RASTER_PER_PIXEL`, `OIT_GPU_TIMESTAMPS`, `OIT_HOST_SETUP`):
/// `1` or `true` (case aside) is yes, `0` or `false` no; unset or anything else says nothing.
fn env_flag(value: Option<&str>) -> Option<bool> {
    match value {
        Some("1") => Some(true),
        Some("0") => Some(false),
        Some(v) if v.eq_ignore_ascii_case("true") => Some(true),
        Some(v) if v.eq_ignore_ascii_case("false") => Some(false),
        _ => None,
    }
}

/// Whether `OIT_HOST_TIMES=1`: each GPU frame prints to stderr where its wall time goes, a line
/// `oit host times: ...` (both backends: recording and submitting, and the end-of-frame
/// readback's wait; oit-wgpu's compute raster set up on the host also its setup and upload;
/// oit-vulkan's also its span on the device, idle and untimed device time, and its commands by
/// kind). `bench/local/host_times.py` sums the lines. Read once.
pub fn host_times() -> bool {
    static ON: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *ON.get_or_init(|| std::env::var("OIT_HOST_TIMES").is_ok_and(|v| v == "1"))
}

/// Whether a device that can write timestamps times each dispatch and draw (a frame's `gpu_ms` and
/// `gpu_pass_ms`): on a GPU, not on a CPU device (lavapipe's timestamps cover a sliver of its
/// frames' wall time). `OIT_GPU_TIMESTAMPS=1` (or `true`) turns them on anywhere, so tests run the
/// timed path on lavapipe, and `0` (or `false`) off anywhere, so a GPU's frames can be timed by the
/// wall without a timestamp pair around every pass.
pub fn timestamps_wanted(cpu_device: bool) -> bool {
    timestamps_by(std::env::var("OIT_GPU_TIMESTAMPS").ok().as_deref(), cpu_device)
}

/// [`timestamps_wanted`] with `OIT_GPU_TIMESTAMPS` given (`None`: unset).
fn timestamps_by(var: Option<&str>, cpu_device: bool) -> bool {
    env_flag(var).unwrap_or(!cpu_device)
}

/// Workgroups of 64 for `invocations` invocations, as (x, y) with x ≤ 65535 (a kernel finds its
/// invocation's index from both: `kernel_pixel` in prelude.wgsl).
pub fn dispatch_size(invocations: u64) -> (u32, u32) {
    let groups = invocations.div_ceil(64);
    if groups <= 65_535 { (groups as u32, 1) } else { (65_535, groups.div_ceil(65_535) as u32) }
}

/// The compute raster's uniform (raster_compute.wgsl's): `items` work items (a GPU setup
/// overwrites the count), the frame's size, its shading, and the camera's forward direction.
pub fn raster_uniform(camera: &Camera, settings: &Settings, items: u32) -> [u32; 8] {
    let forward = camera.forward;
    [
        items,
        settings.width,
        settings.height,
        settings.shading.code(),
        forward.x.to_bits(),
        forward.y.to_bits(),
        forward.z.to_bits(),
        0,
    ]
}

/// The compute raster's indirect arguments for `items` work items, as the GPU setup's arguments
/// kernel writes them (`oit_core::gpu_setup::ARGS_WORDS`): the per-pixel dispatch, the per-item
/// one and the item count. A frame set up on the host (a textured one) uploads them, so that its
/// geometry passes dispatch and gate (`geometry_pass_if`) as a GPU-set-up frame's do.
pub fn raster_args(items: u64) -> [u32; oit_core::gpu_setup::ARGS_WORDS] {
    use oit_core::gpu_setup::{ARGS_ITEMS, ARGS_PER_ITEM, ARGS_WORDS};
    let dispatch = |invocations: u64| {
        let (x, y) = dispatch_size(invocations);
        [x, y, 1, 0]
    };
    let mut args = [0; ARGS_WORDS];
    // raster_main: a workgroup of TILE × TILE invocations an item; raster_loop_main: one an item
    args[..4].copy_from_slice(&dispatch(items * u64::from(TILE * TILE)));
    let per_item = (ARGS_PER_ITEM / 4) as usize;
    args[per_item..per_item + 4].copy_from_slice(&dispatch(items));
    args[(ARGS_ITEMS / 4) as usize] = items as u32;
    args
}

impl FrameUniform {
    /// The uniform of a frame of `settings` seen by `camera` under `plan` (pass 0, parameter 0):
    /// the same on every GPU backend.
    pub fn new(scene: &Scene, camera: &Camera, settings: &Settings, plan: &Plan) -> FrameUniform {
        FrameUniform {
            width: settings.width,
            height: settings.height,
            pass_index: 0,
            param: 0,
            effect: match settings.effect {
                Effect::Transparency => 0,
                Effect::Translucency => 1,
                Effect::Fresnel => 2,
                Effect::Complexity => 3,
            },
            pixel_count: settings.width * settings.height,
            ties: u32::from(plan.count_ties),
            last_pass: 0,
            forward: camera.forward.extend(0.0).to_array(),
            background: settings.background.extend(1.0).to_array(),
            lens: [camera.near, camera.far, scene.absorption_for(settings.effect) as f32, 0.0],
            opaque: [u32::from(plan.opaque), 0, u32::from(plan.opaque), 0],
            msaa: {
                let samples = settings.samples.max(1);
                let keep = if settings.pixel_coverage { oit_core::msaa::full_mask(samples) } else { 0 };
                let fraction = oit_core::msaa::coverage(settings) == Some(oit_core::msaa::Coverage::Fraction);
                let [lo, hi] = sample_position_words(samples);
                [samples, u32::from(keep) | if fraction { MSAA_FRACTION } else { 0 }, lo, hi]
            },
        }
    }
}

/// The host's setup of the compute path, set up and binned: the scene's (or, with `boxes`, its
/// instances' bounding boxes') triangle words (`oit_core::setup`), and the work list of the compute
/// rasterizer, one (triangle, tile) item for each [`TILE`]² tile of a triangle's pixel box that
/// it may cover (`TriangleSetup::work_items`), the tile as `ty << 16 | tx`. Both GPU backends
/// upload these where the device sets up on the host, as every textured frame does
/// ([`is_textured`]): after the triangles, the textured triangles' records and the texture region
/// ([`TextureRegion`]; raster_compute.wgsl reads them).
pub fn host_setup(
    scene: &Scene,
    camera: &Camera,
    settings: &Settings,
    boxes: bool,
) -> (Vec<u32>, Vec<[u32; 2]>) {
    let mut kept = HostSetup::default();
    kept.run(scene, camera, settings, boxes);
    (kept.words, kept.items)
}

/// [`host_setup`] kept from frame to frame: the setup's triangles, its scratch, the words and
/// the work list keep their storage, so a steady frame allocates nothing (fresh memory is a
/// page fault a page, a tenth of a textured frame's host setup where each frame made its own).
#[derive(Default)]
pub struct HostSetup {
    setup: Option<oit_core::setup::TriangleSetup>,
    scratch: oit_core::setup::SetupScratch,
    item_chunks: Vec<Vec<[u32; 2]>>,
    /// The triangle words ([`host_setup`]'s first).
    pub words: Vec<u32>,
    /// The work list ([`host_setup`]'s second).
    pub items: Vec<[u32; 2]>,
}

impl HostSetup {
    /// Sets this frame up into the kept storage: [`HostSetup::words`] and [`HostSetup::items`]
    /// then hold what [`host_setup`] returns.
    pub fn run(&mut self, scene: &Scene, camera: &Camera, settings: &Settings, boxes: bool) {
        use oit_core::setup::TriangleSetup;
        let r = if boxes {
            self.setup.insert(TriangleSetup::bounding_boxes(scene, camera, settings))
        } else {
            let r = self.setup.get_or_insert_with(|| TriangleSetup::empty(camera, settings));
            r.rebuild(scene, camera, settings, &mut self.scratch);
            r
        };
        r.triangle_words_into(&mut self.words);
        debug_assert_eq!(self.words.len() % oit_core::setup::TRIANGLE_WORDS, 0);
        if r.has_textures() {
            pack_textures(r, &mut self.words);
        }
        r.work_items_into(TILE, &mut self.items, &mut self.item_chunks);
    }

    /// Sets up a frame's two parts at once, each into its own kept setup: its transparent part
    /// and its opaque part ([`HostSetup::run`] each, without boxes), on two of rayon's threads.
    /// A textured frame with opaque parts sets both up on the host, and a part of a few hundred
    /// small instances (`foliage`'s leaves) spreads over few cores: side by side, the frame
    /// waits for the longer of the two rather than both.
    pub fn run_both(parts: [(&mut HostSetup, &Scene); 2], camera: &Camera, settings: &Settings) {
        let [(a, first), (b, second)] = parts;
        rayon::join(|| a.run(first, camera, settings, false), || b.run(second, camera, settings, false));
    }
}

/// Appends to a textured setup's triangle words (`words`) each textured triangle's record
/// ([`TEXTURE_RECORD_WORDS`]), pointed at by its [`TRIANGLE_TEXTURE_WORD`], and the texture
/// region ([`TextureRegion`]) after them: what raster_compute.wgsl samples.
fn pack_textures(r: &oit_core::setup::TriangleSetup, words: &mut Vec<u32>) {
    use oit_core::setup::TRIANGLE_WORDS;
    let count = r.textures.len();
    let textured = r.triangles.iter().filter(|t| (t.texture as usize) < count).count();
    let records = words.len();
    let region = TextureRegion::new(&r.textures, (records + textured * TEXTURE_RECORD_WORDS) as u32);
    words.reserve(textured * TEXTURE_RECORD_WORDS + region.words.len());
    for (i, t) in r.triangles.iter().enumerate() {
        if (t.texture as usize) >= count {
            continue;
        }
        words[i * TRIANGLE_WORDS + TRIANGLE_TEXTURE_WORD] = words.len() as u32;
        for uv in t.uv {
            words.extend([uv.x.to_bits(), uv.y.to_bits()]);
        }
        words.extend([region.descriptor(t.texture, t.lod), t.cutoff.to_bits(), region.tables()]);
    }
    words.extend(region.words);
}

/// Initial contents of a storage buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Init {
    /// All zero bits.
    Zero,
    /// Every 32-bit word set to this.
    Fill(u32),
    /// None the frame relies on: every word the frame reads, it wrote first (an array whose
    /// entries are taken by a counter and written whole before any is read: fabs's slots, a
    /// linked list's nodes, dfb's entries). A buffer reused from an earlier frame is left as that
    /// frame left it, which saves a pass over the whole array every frame; a new one is set to
    /// [`UNWRITTEN`], so a frame that reads a word it did not write shows it in its image on
    /// the first frame (and fails the conformance bodies, which compare it with the reference).
    Unwritten,
}

/// Every word of a new [`Init::Unwritten`] buffer: as a depth key (high word), a negative depth in
/// front of every fragment; as a colour payload, a half-transparent purple; as a link or an
/// index, far past any array's end.
pub const UNWRITTEN: u32 = 0xa5a5_a5a5;

impl Init {
    /// The word every 32-bit word of a new buffer starts as.
    pub fn word(self) -> u32 {
        match self {
            Init::Zero => 0,
            Init::Fill(v) => v,
            Init::Unwritten => UNWRITTEN,
        }
    }

    /// The word every 32-bit word of a buffer is set to before the frame uses it: `fresh` is
    /// whether the buffer is new (else reused from an earlier frame). `None`: left as it is.
    pub fn fill(self, fresh: bool) -> Option<u32> {
        (fresh || self != Init::Unwritten).then(|| self.word())
    }
}

/// The texel format of a storage image a technique keeps its atomic words in
/// (`--atomic-storage image`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// One 32-bit unsigned word a texel.
    R32Uint,
    /// One 64-bit unsigned word a texel.
    R64Uint,
}

impl ImageFormat {
    /// Bytes of one texel.
    pub fn bytes(self) -> u64 {
        match self {
            ImageFormat::R32Uint => 4,
            ImageFormat::R64Uint => 8,
        }
    }
}

/// One frame on a GPU, as a technique sees it: storage, passes, kernels, read-backs. `R` is the
/// backend's rasterizer (a geometry pass runs the technique's `capture` over every fragment it
/// generates).
///
/// Storage comes in two kinds, so that a frame's `storage_bytes` is what the plan counts and
/// nothing else: [`Frame::array`] is the technique's storage (counted, checked against the
/// memory budget; `Plan::arrays` names it), [`Frame::scratch`] is bookkeeping (a flag, a
/// counter, a sizing count: not counted, as oit-cpu counts none).
pub trait Frame<R: ?Sized> {
    /// A storage buffer of the frame (a handle: cheap to clone).
    type Buffer: Clone;

    /// The frame's plan: refusals, sizing and stop rules (oit-core's).
    fn plan(&self) -> &Plan;
    /// The frame's settings.
    fn settings(&self) -> &Settings;
    /// Pixels of the frame (its width × height).
    fn pixels(&self) -> u32;
    /// The backend's name, for refusals (`"wgpu"`, `"vulkan"`).
    fn backend(&self) -> &'static str;

    /// A storage buffer of `words` 32-bit words of the technique's storage, initialised to
    /// `init`: counted in the frame's storage and checked against its budget and the device's
    /// limits.
    fn array(&mut self, label: &str, words: u64, init: Init) -> Result<Self::Buffer, OitError>;
    /// A small storage buffer of `words` words of bookkeeping (flags, counters), initialised to
    /// `init`; not the technique's storage.
    fn scratch(&mut self, label: &str, words: u64, init: Init) -> Result<Self::Buffer, OitError>;
    /// A small buffer bound where a pass's WGSL declares an array this mode does not use.
    fn placeholder(&mut self) -> Result<Self::Buffer, OitError>;
    /// Sets every word of `buffer` to `value` (in the frame's command stream).
    fn fill(&mut self, buffer: &Self::Buffer, value: u32) -> Result<(), OitError>;
    /// Copies the first `bytes` of `src` to the start of `dst` (in the frame's command stream).
    fn copy(&mut self, src: &Self::Buffer, dst: &Self::Buffer, bytes: u64) -> Result<(), OitError>;
    /// Reads `buffer` back (waits for everything recorded so far: a round trip).
    fn read_u32(&mut self, buffer: &Self::Buffer) -> Result<Vec<u32>, OitError>;

    /// A storage image of the frame's size with `layers` layers of `format`, bound at `binding`
    /// of group 0 from now on, every 32-bit half of every texel set to `fill`: the technique's
    /// storage, counted as [`Frame::array`]'s. For `--atomic-storage image`; a backend or device
    /// without storage-image atomics refuses by name (the default).
    fn storage_image(
        &mut self,
        label: &str,
        binding: u32,
        layers: u32,
        format: ImageFormat,
        fill: u32,
    ) -> Result<(), OitError> {
        let _ = (label, binding, layers, fill);
        Err(OitError::Unsupported {
            backend: self.backend().into(),
            what: format!(
                "--atomic-storage image ({format:?} storage-image atomics) for {}; use --atomic-storage buffer",
                self.settings().technique
            ),
        })
    }

    /// Marks the passes that follow as the last capture pass the plan allows (or not).
    fn last_pass(&mut self, last: bool);

    /// Whether the geometry passes that follow cut their fragments at the opaque pass's depth
    /// (where the frame has an opaque part; off for the opaque pass itself and the instances'
    /// bounding boxes, which oit-cpu does not cut either).
    fn cut(&mut self, on: bool);
    /// Where the opaque pass counted the fragments it drew (word 0 of `count`, left on the
    /// device): read with the frame's end into `Stats::opaque_fragments`.
    fn note_opaque(&mut self, count: &Self::Buffer);

    /// One geometry pass of `module`'s `capture` (pass index `pass`, parameter `param`,
    /// `buffers` bound from binding 2 of group 0) through `raster`. The frame's first geometry
    /// pass over the scene counts the scene's fragments.
    fn geometry_pass(
        &mut self,
        raster: &R,
        module: &'static str,
        buffers: &[&Self::Buffer],
        pass: u32,
        param: u32,
    ) -> Result<(), OitError>;
    /// [`Frame::geometry_pass`], counting the fragments it generates into a word of scratch it
    /// returns, left on the device (ll's sizing pass, for [`Frame::fragment_capacity`]).
    fn geometry_pass_counted(
        &mut self,
        raster: &R,
        module: &'static str,
        buffers: &[&Self::Buffer],
        pass: u32,
        param: u32,
    ) -> Result<Self::Buffer, OitError>;
    /// A geometry pass that has work only where word 0 of `flag` (left by the frame's earlier
    /// passes) is not zero: gated on the device where the raster can gate its work (no round
    /// trip, the pass counted on the device where it runs), else the flag is read back first.
    fn geometry_pass_if(
        &mut self,
        raster: &R,
        module: &'static str,
        buffers: &[&Self::Buffer],
        pass: u32,
        param: u32,
        flag: &Self::Buffer,
    ) -> Result<(), OitError>;
    /// Whether the fragments of the scene are counted yet (the frame's first scene pass ran).
    fn fragments(&self) -> GpuFragments;
    /// Sets what [`Frame::fragments`] says: a pass over something else than the scene (the
    /// bounding boxes of bdp's and adp's bounds) leaves the scene's count as it was.
    fn set_fragments(&mut self, fragments: GpuFragments);

    /// Runs compute `entry` of `module` once per pixel.
    fn pixel_kernel(
        &mut self,
        module: &'static str,
        entry: &'static str,
        buffers: &[&Self::Buffer],
        pass: u32,
        param: u32,
    ) -> Result<(), OitError> {
        let pixels = u64::from(self.pixels());
        self.kernel_over(module, entry, buffers, pixels, pass, param, entry)
    }
    /// Runs compute `entry` of `module` over `invocations` invocations, timed under `label`.
    #[expect(clippy::too_many_arguments, reason = "a dispatch is that many things")]
    fn kernel_over(
        &mut self,
        module: &'static str,
        entry: &'static str,
        buffers: &[&Self::Buffer],
        invocations: u64,
        pass: u32,
        param: u32,
        label: &'static str,
    ) -> Result<(), OitError>;

    /// The deepest pixel of a counting pass whose count lies in word 0 of `max`: an earlier
    /// frame's where the frame speculates (checked at its end, where a frame whose count is not
    /// `alike` runs again), else read back now and kept for the next frame.
    fn deepest_alike(
        &mut self,
        max: &Self::Buffer,
        alike: Box<dyn Fn(u32, u32) -> bool>,
    ) -> Result<u32, OitError>;
    /// [`Frame::deepest_alike`] where only an equal count will do.
    fn deepest(&mut self, max: &Self::Buffer) -> Result<u32, OitError> {
        self.deepest_alike(max, Box::new(|speculated, counted| speculated == counted))
    }
    /// The capacity, in elements of `bytes` bytes, of arrays sized by the count in word 0 of
    /// `count` (dfb's and ll's fragment total): that count rounded up to its size class, an
    /// earlier frame's where the frame speculates (checked at the end), else read back now.
    fn fragment_capacity(&mut self, count: &Self::Buffer, bytes: u64) -> Result<u32, OitError>;
    /// The passes an earlier frame's peel loop ran at this view's kind, where this frame may
    /// record that many without reading back in between (taken: the next call gives `None`).
    fn take_speculated_peels(&mut self) -> Result<Option<u32>, OitError>;
    /// The passes this frame's peel loop ran reading back, kept for the next frame.
    fn note_peels(&mut self, peels: u32);
    /// Word 0 of `flag` must be 0 at the frame's end; where it is not, the frame ran on a wrong
    /// speculation and runs again.
    fn check_at_end(&mut self, flag: &Self::Buffer);
    /// Word 0 of `flag` must be 0 at the frame's end (read back with the frame's totals); where
    /// it is not, the frame met what its capture cannot render honestly and fails with
    /// [`OitError::Unsupported`] saying `what` (ddp's blend capture at several samples, which
    /// cannot order equal depths at a sample's range end: [`technique::ddp_blend_sample_state`]).
    fn refuse_at_end(&mut self, flag: &Self::Buffer, what: String);
    /// Where a tail pass counts the fragments it merged (word 1 of `words`), read with the
    /// frame's end.
    fn note_merged(&mut self, words: &Self::Buffer);
    /// The per-pixel fragment counts the frame hands back as its `layers` (the reference's).
    fn note_layers(&mut self, counts: &Self::Buffer);

    /// adp's histogram pass by a capture of the backend's own (logic-op OR into render targets
    /// on Vulkan's hardware path under `--hardware-capture blend`), over adp's `buffers`: `true`
    /// where it ran, `false` where the backend has none and the atomic capture runs instead.
    fn histogram_capture(&mut self, raster: &R, buffers: &[&Self::Buffer]) -> Result<bool, OitError> {
        let _ = (raster, buffers);
        Ok(false)
    }
}

/// The rasterizers of a frame: the scene's, and one over the instances' bounding boxes (bdp's and
/// adp's `--bounds boxes`), made where a frame asks for it.
pub trait Rasters<R: ?Sized> {
    /// Rasterizes the scene.
    fn scene(&self) -> &R;
    /// Makes a rasterizer of the instances' bounding boxes and runs `pass` with it.
    fn with_boxes(&self, pass: &mut dyn FnMut(&R) -> Result<(), OitError>) -> Result<(), OitError>;
    /// Rasterizes the frame's opaque part ([`oit_core::Layers::opaque`]), where it has one.
    fn opaque(&self) -> Option<&R> {
        None
    }
}

#[cfg(test)]
mod tests {
    /// The setup kernel's spread pieces are oit-core's (`gpu_setup::SPREAD_PIECES`, which sizes
    /// the counters' buffer and the dispatches of `setup_count_main` and `setup_items_main` on both
    /// backends).
    #[test]
    fn spread_pieces_are_the_setups() {
        use oit_core::gpu_setup::{COUNTER_WORDS, SPREAD_ITEMS, SPREAD_PIECES};
        for (name, value) in [("SPREAD_PIECES", SPREAD_PIECES), ("SPREAD_ITEMS", SPREAD_ITEMS)] {
            let line = format!("const {name}: u32 = {value}u;");
            assert!(oit_shaders::SETUP.contains(&line), "setup.wgsl has no `{line}`");
        }
        assert!(oit_shaders::SETUP.contains("const SPREAD_FIRST: u32 = 4u;"));
        assert_eq!(COUNTER_WORDS, 4 + 2 * SPREAD_PIECES);
    }

    /// `OIT_GPU_TIMESTAMPS` decides where it is set, in either spelling, and the device type
    /// where it is not (or is neither): GPUs time their passes, CPU devices do not.
    #[test]
    fn timestamps_follow_the_variable_then_the_device() {
        for cpu in [false, true] {
            for on in ["1", "true", "TRUE"] {
                assert!(super::timestamps_by(Some(on), cpu), "{on} on cpu={cpu}");
            }
            for off in ["0", "false", "False"] {
                assert!(!super::timestamps_by(Some(off), cpu), "{off} on cpu={cpu}");
            }
            assert_eq!(super::timestamps_by(None, cpu), !cpu);
            assert_eq!(super::timestamps_by(Some("yes"), cpu), !cpu);
        }
    }

    /// `OIT_HOST_SETUP` forces the site either way; unset (or neither spelling), a CPU device sets
    /// up on the host and a GPU on the device, save parts of at most `HOST_SETUP_TRIANGLES`
    /// triangles (a wall's 2 and a box's 12, not planes:16's 32), and textured parts go to the
    /// host everywhere.
    #[test]
    fn setup_site_follows_the_variable_the_device_and_the_parts_size() {
        use super::{HOST_SETUP_TRIANGLES, SetupSite, sets_up_on_host, setup_site_by as setup_site};
        for cpu in [false, true] {
            for host in ["1", "true", "TRUE"] {
                assert_eq!(setup_site(Some(host), cpu), SetupSite::Host);
            }
            for device in ["0", "false", "False"] {
                assert_eq!(setup_site(Some(device), cpu), SetupSite::Device);
            }
        }
        assert_eq!(setup_site(None, true), SetupSite::Host);
        assert_eq!(setup_site(Some("yes"), true), SetupSite::Host);
        assert_eq!(setup_site(None, false), SetupSite::DeviceUnlessSmall);
        let load = |name: &str| oit_core::load_scene(name).expect("a built-in scene");
        let (small, planes) = (load("planes:8"), load("planes:16"));
        assert_eq!(small.triangle_count(), HOST_SETUP_TRIANGLES);
        assert!(planes.triangle_count() > HOST_SETUP_TRIANGLES);
        // an instance's triangles count each time it is placed
        let grid = load("grid:3x3:planes:1");
        assert!(grid.triangle_count() > HOST_SETUP_TRIANGLES);
        assert!(!sets_up_on_host(SetupSite::DeviceUnlessSmall, &grid));
        let textured = load("particles");
        assert!(super::is_textured(&textured));
        for (site, small_on_host, large_on_host) in [
            (SetupSite::Host, true, true),
            (SetupSite::Device, false, false),
            (SetupSite::DeviceUnlessSmall, true, false),
        ] {
            assert_eq!(sets_up_on_host(site, &small), small_on_host, "{site:?}");
            assert_eq!(sets_up_on_host(site, &planes), large_on_host, "{site:?}");
            assert!(sets_up_on_host(site, &textured), "{site:?}: textured parts set up on the host");
        }
    }

    /// The most pieces a task leaves (`gpu_setup::MAX_PIECES_PER_TASK`, which sizes the spread
    /// kernels' dispatch) is the fan of setup.wgsl's clip polygon: its corners less two.
    #[test]
    fn pieces_per_task_are_the_clip_polygons_fan() {
        let corners = 3 + 6; // a triangle, and a corner more for each of the six clip planes
        for poly in
            ["var<private> poly: array<ClipVertex, 9>;", "var<private> next_poly: array<ClipVertex, 9>;"]
        {
            assert!(oit_shaders::SETUP.contains(poly), "setup.wgsl has no `{poly}`");
        }
        assert_eq!(oit_core::gpu_setup::MAX_PIECES_PER_TASK, corners - 2);
    }

    /// The work-item marks' modes are raster_compute.wgsl's, and its mark bit lies above every
    /// tile row a frame of the largest size has (a row takes the tile word's upper 16 bits).
    #[test]
    fn item_marks_are_the_rasters() {
        for (name, value) in [("MARKS_WRITE", super::MARKS_WRITE), ("MARKS_READ", super::MARKS_READ)] {
            let line = format!("const {name}: u32 = {value}u;");
            assert!(oit_shaders::COMPUTE_RASTER.contains(&line), "raster_compute.wgsl has no `{line}`");
        }
        assert!(oit_shaders::COMPUTE_RASTER.contains("const ITEM_SPENT: u32 = 0x80000000u;"));
        assert!(oit_shaders::COMPUTE_RASTER.contains("const ITEM_COUNTED: u32 = 0x40000000u;"));
        let rows = oit_core::MAX_SIZE.div_ceil(super::TILE);
        assert!(rows < 1 << 14, "{rows} tile rows reach the mark bits");
    }

    /// A host-set-up frame's indirect arguments are those `setup_finish_main` (setup.wgsl) writes
    /// for the same item count: a workgroup an item for `raster_main` (x capped at 65,535, the
    /// rest in y), a workgroup of 64 items for `raster_loop_main` at `ARGS_PER_ITEM`, the count at
    /// `ARGS_ITEMS`.
    #[test]
    fn host_raster_args_are_the_setups() {
        assert_eq!(super::raster_args(0), [0, 1, 1, 0, 0, 1, 1, 0, 0, 0, 0, 0]);
        assert_eq!(super::raster_args(3), [3, 1, 1, 0, 1, 1, 1, 0, 3, 0, 0, 0]);
        assert_eq!(super::raster_args(100_000), [65_535, 2, 1, 0, 1563, 1, 1, 0, 100_000, 0, 0, 0]);
    }

    /// Whether a scene draws a textured object: the particles do, their untextured twin does not.
    #[test]
    fn textured_scenes_are_told_apart() {
        let scene = oit_core::load_scene("particles:4").unwrap();
        assert!(super::is_textured(&scene));
        let plain = oit_core::load_scene("untextured:particles:4").unwrap();
        assert!(!super::is_textured(&plain));
    }

    /// The packed textures are what the sampler reads: a texel of each level at its descriptor's
    /// place, and each textured triangle's record names its level's descriptor and texture
    /// coordinates.
    #[test]
    fn textures_pack_behind_the_triangles() {
        use oit_core::setup::{TRIANGLE_WORDS, TriangleSetup};
        let scene = oit_core::load_scene("particles:4").unwrap();
        let camera = oit_core::Camera::orbit_scene(&scene, oit_core::View::default(), 1.0).unwrap();
        let settings = oit_core::Settings { width: 64, height: 64, ..Default::default() };
        let (words, _) = super::host_setup(&scene, &camera, &settings, false);
        let setup = TriangleSetup::new(&scene, &camera, &settings);
        let n = setup.triangles.len();
        assert!(n > 0 && words.len() > n * TRIANGLE_WORDS);
        let mut textured = 0;
        for (i, t) in setup.triangles.iter().enumerate() {
            let rec = words[i * TRIANGLE_WORDS + super::TRIANGLE_TEXTURE_WORD] as usize;
            // the backdrop is untextured
            if t.texture == oit_core::setup::NO_TEXTURE {
                assert_eq!(rec, 0, "triangle {i}");
                continue;
            }
            textured += 1;
            assert!(rec >= n * TRIANGLE_WORDS, "triangle {i}");
            assert_eq!(f32::from_bits(words[rec + 2]), t.uv[1].x);
            let tables = words[rec + 8] as usize;
            assert_eq!(f32::from_bits(words[tables + 255]), 1.0);
            assert_eq!(f32::from_bits(words[tables + 256 + 51]), 0.2);
            let d = words[rec + 6] as usize;
            let level = &setup.textures[t.texture as usize].mips()[t.lod as usize];
            assert_eq!((words[d + 1], words[d + 2]), (level.width, level.height));
            let last = level.texels.len() - 1;
            assert_eq!(words[words[d] as usize + last], u32::from_le_bytes(level.texels[last]));
        }
        assert!(textured > 0);
        let region = super::TextureRegion::new(&setup.textures, 0);
        let levels = super::triangle_levels(&scene, &camera, &settings, &region);
        assert_eq!(levels.len(), scene.triangle_count() as usize);
        // the sprites' triangles name a descriptor (after the two tables), the backdrop's none
        assert!(levels.iter().any(|&d| d >= 512) && levels.iter().all(|&d| d == 0 || d >= 512));
    }
}
