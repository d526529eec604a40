//! Settings of one frame: size, technique, shading, effect, background.

use std::str::FromStr;

use glam::{Vec3, Vec4};
use serde::Serialize;

use crate::{BoundsMode, Effect, OitError, RasterPath, Technique};

/// How a fragment's colour is computed, so that the fragments of one mesh differ and order
/// matters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Shading {
    /// colour × (0.3 + 0.7·|n·l|), l the camera's forward direction, n the interpolated normal.
    #[default]
    Headlight,
    /// The object's colour alone.
    Flat,
    /// The per-vertex colours, interpolated perspective-correct, unlit (object colour where the
    /// mesh has none); alpha from the object.
    Vertex,
    /// The world-space normal mapped to colour: 0.5 + 0.5·n.
    Normal,
}

impl Shading {
    /// The code GPU shaders switch on (`shade` in oit-wgpu's `common.wgsl`): 0 headlight, 1 flat,
    /// 2 vertex, 3 normal.
    pub fn code(self) -> u32 {
        match self {
            Shading::Headlight => 0,
            Shading::Flat => 1,
            Shading::Vertex => 2,
            Shading::Normal => 3,
        }
    }
}

impl FromStr for Shading {
    type Err = OitError;
    fn from_str(s: &str) -> Result<Shading, OitError> {
        match s.trim().to_ascii_lowercase().as_str() {
            "headlight" => Ok(Shading::Headlight),
            "flat" => Ok(Shading::Flat),
            "vertex" => Ok(Shading::Vertex),
            "normal" => Ok(Shading::Normal),
            other => Err(OitError::InvalidSettings(format!(
                "unknown shading '{other}': use headlight, flat, vertex or normal"
            ))),
        }
    }
}

impl Shading {
    /// The straight-alpha linear colour of a fragment. `normal` is the interpolated (not yet
    /// normalized) world-space normal, `vertex_color` the interpolated vertex colour if the mesh
    /// has one, `forward` the camera's viewing direction.
    #[inline]
    pub fn shade(self, base: Vec4, normal: Vec3, vertex_color: Option<Vec3>, forward: Vec3) -> Vec4 {
        let n = normal.normalize_or_zero();
        let rgb = match self {
            Shading::Headlight => base.truncate() * (0.3 + 0.7 * n.dot(forward).abs()),
            Shading::Flat => base.truncate(),
            Shading::Vertex => vertex_color.unwrap_or(base.truncate()),
            Shading::Normal => n * 0.5 + Vec3::splat(0.5),
        };
        rgb.clamp(Vec3::ZERO, Vec3::ONE).extend(base.w.clamp(0.0, 1.0))
    }
}

/// Everything that shapes one frame besides the scene and the camera.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Settings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// The technique.
    pub technique: Technique,
    /// Linear RGB behind everything.
    pub background: Vec3,
    /// Replaces every object's alpha when set.
    pub alpha: Option<f32>,
    /// Stops the peeling techniques (dp, ddp, mlp, adp batches) after this many capture passes.
    pub max_peels: Option<u32>,
    /// Fragment colours.
    pub shading: Shading,
    /// What is made of the sorted fragments.
    pub effect: Effect,
    /// How bucket techniques find the depth range.
    pub bounds: BoundsMode,
    /// Capture path on GPU backends (`None`: the backend's default for the technique).
    pub raster: Option<RasterPath>,
    /// What single-pass bucket depth peeling stores.
    pub bdp_mode: BdpMode,
    /// How the hardware raster path of GPU backends captures for `bdp`, `dp` and `ddp`.
    pub hardware_capture: HardwareCapture,
    /// Where this frame lies in a larger one (`None`: it is the whole frame). Set by the tiling
    /// loop ([`crate::tiling`]): the frame is then the `width × height` window at
    /// (`region.x`, `region.y`) of a `region.full_width × region.full_height` frame, and its
    /// fragments are exactly that window's fragments of the full frame.
    pub region: Option<Region>,
    /// The memory budget of one frame's storage in bytes (`--memory`; `None`: what the device
    /// allows). A frame that needs more runs in screen tiles that each fit ([`crate::tiling`]).
    pub memory: Option<u64>,
    /// What `fabs:K`, `mdts:K` and `mdts64:K` make of the fragments a pixel has beyond its K
    /// (`--overflow`); other techniques, and those three sized from a counting pass, ignore it.
    pub overflow: Overflow,
    /// Where `mdts:K`, `mdts64:K` and `fabs:K` keep the words they update atomically
    /// (`--atomic-storage`); other techniques ignore it.
    pub atomic_storage: AtomicStorage,
    /// The blender's colour target on the hardware raster path (`--blend-target`): `plain`, and
    /// `wavg`/`wsum` with `--hardware-capture blend` (which refuse `unorm8` when they render).
    /// The compute path and oit-cpu have no blender and ignore it (their captures are exact), so
    /// [`Settings::validate`] takes every target with every technique.
    pub blend_target: BlendTarget,
    /// Samples a pixel (`--samples`): 1 (the default: one sample at the centre), 4 or 8 (the
    /// standard patterns, [`crate::msaa`]). Above 1 a fragment carries its coverage mask and the
    /// techniques that take it composite per sample (docs/msaa.md); the others refuse it.
    pub samples: u32,
    /// With `samples` above 1: the reference technique renders the supersampled reference
    /// (`--supersample`), every sample rasterized and shaded as a pixel of its own at its
    /// position, the pixel the mean of its samples, against which MSAA's own error is measured
    /// (`oit compare` then judges the techniques, MSAA, against it). Other techniques ignore it.
    pub supersample: bool,
    /// With `samples` above 1: every technique but the reference composites each fragment over
    /// all of the pixel's samples, whatever its mask (`--coverage pixel`): per-pixel capture of
    /// the multisampled fragments, the baseline whose edge seams per-sample coverage removes.
    /// The reference stays per sample (the target the baseline is measured against).
    pub pixel_coverage: bool,
    /// With `samples` above 1: a technique that keeps no mask weighs each fragment's alpha by its
    /// coverage fraction even where its own choice is per pixel (`--coverage fraction`; bdp's
    /// colour mode: [`crate::msaa::coverage`]), so that the two can be measured side by side.
    /// The techniques that keep masks ignore it.
    pub fraction_coverage: bool,
}

/// The colour target the blender writes on the hardware path, for `plain` and (with
/// `--hardware-capture blend`) `wavg`/`wsum`. The per-pixel fragment count beside it stays in
/// f32 (R16F on a device without `FLOAT32_BLENDABLE`). Narrower targets are what renderers use
/// and what the speed baseline should be measured with; their rounding is measured against the
/// reference like any approximation (`tests/tests/blend_target.rs` bounds it).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BlendTarget {
    /// RGBA32F: `plain` equals oit-cpu up to f32 rounding; `wavg`/`wsum` add the 8-bit
    /// integers α·c and α exactly (while a pixel's sum stays below 2^24).
    #[default]
    F32,
    /// RGBA16F, the accumulation target of McGuire & Bavoil's weighted blended OIT (JCGT 2013):
    /// `wavg`/`wsum` add α·c and α in [0, 1], each addition rounded to 11 significant bits.
    F16,
    /// RGBA8 unorm, what a renderer blending into an 8-bit colour buffer gets: `plain` only
    /// (the weighted sums leave [0, 1]).
    Unorm8,
}

impl BlendTarget {
    /// The parameter `blend.wgsl`'s weighted blend and resolve read for `technique` (`wavg` or
    /// `wsum`) blended into this target, on every GPU backend: bit 0 set for the weighted average,
    /// bit 1 for sums of α·c and α in [0, 1] (RGBA16F) rather than of the 8-bit integers
    /// (RGBA32F). An 8-bit target cannot hold the sums, nor is any other technique weighted.
    pub fn weighted_param(self, technique: Technique) -> Result<u32, OitError> {
        let average = match technique {
            Technique::WeightedAverage => 1,
            Technique::WeightedSum => 0,
            other => return Err(OitError::InvalidSettings(format!("{other} is not wavg or wsum"))),
        };
        let units = match self {
            BlendTarget::F32 => 0,
            BlendTarget::F16 => 2,
            BlendTarget::Unorm8 => {
                return Err(OitError::InvalidSettings(format!(
                    "--blend-target unorm8 holds [0, 1] and {technique}'s sums leave it: use f16 or f32"
                )));
            }
        };
        Ok(average | units)
    }
}

impl std::fmt::Display for BlendTarget {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            BlendTarget::F32 => "f32",
            BlendTarget::F16 => "f16",
            BlendTarget::Unorm8 => "unorm8",
        })
    }
}

impl FromStr for BlendTarget {
    type Err = OitError;
    fn from_str(s: &str) -> Result<BlendTarget, OitError> {
        match s.trim().to_ascii_lowercase().as_str() {
            "f32" | "rgba32f" => Ok(BlendTarget::F32),
            "f16" | "rgba16f" => Ok(BlendTarget::F16),
            "unorm8" | "rgba8" => Ok(BlendTarget::Unorm8),
            other => Err(OitError::InvalidSettings(format!(
                "unknown blend target '{other}': use f32, f16 or unorm8"
            ))),
        }
    }
}

/// Where the atomic-array techniques (`mdts:K`, `mdts64:K`, `fabs:K`) keep the words they update
/// atomically.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum AtomicStorage {
    /// Storage buffers (std atomics on oit-cpu): every backend.
    #[default]
    Buffer,
    /// Storage images, as the CUDA-rasterizer papers' OpenGL ports used them (Liu et al. 2009's
    /// `imageAtomicMin` on `R32_UINT` for mdts, `R64_UINT` for mdts64 where the device has
    /// `VK_EXT_shader_image_atomic_int64`; Huang et al. 2011's per-pixel counter by
    /// `imageAtomicAdd` for fabs): oit-vulkan only. WGSL's `textureAtomic*` return no value, and
    /// every one of these captures needs the old value, so oit-wgpu cannot write them.
    Image,
}

impl FromStr for AtomicStorage {
    type Err = OitError;
    fn from_str(s: &str) -> Result<AtomicStorage, OitError> {
        match s.trim().to_ascii_lowercase().as_str() {
            "buffer" | "buffers" => Ok(AtomicStorage::Buffer),
            "image" | "images" => Ok(AtomicStorage::Image),
            other => Err(OitError::InvalidSettings(format!(
                "unknown atomic storage '{other}': use buffer or image"
            ))),
        }
    }
}

/// What the fixed-size techniques (`fabs:K`, `mdts:K`, `mdts64:K`) make of a pixel's fragments
/// beyond the K nearest.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Overflow {
    /// Dropped and counted in `Stats::lost` (the papers' behaviour).
    #[default]
    Drop,
    /// Merged into a per-pixel tail behind the K nearest, after multi-layer alpha blending
    /// (Salvi & Vaidyanathan 2014): one more geometry pass adds every fragment behind the pixel's
    /// K-th nearest into order-independent integer sums (Σα·c, Σα, n of its RGBA8 colour), and
    /// the resolve composites their weighted average (Bavoil & Myers 2008) behind the K sorted
    /// fragments. Counted in `Stats::merged`. Transparency only.
    Tail,
}

impl FromStr for Overflow {
    type Err = OitError;
    fn from_str(s: &str) -> Result<Overflow, OitError> {
        match s.trim().to_ascii_lowercase().as_str() {
            "drop" => Ok(Overflow::Drop),
            "tail" => Ok(Overflow::Tail),
            other => Err(OitError::InvalidSettings(format!("unknown overflow '{other}': use drop or tail"))),
        }
    }
}

/// A frame's place in a larger frame: its top-left pixel and the larger frame's size. Backends
/// size everything per pixel by the frame's own `width × height`, as for any frame; setup snaps
/// with the full viewport and shifts the snapped coordinates by the origin (an exact integer
/// shift, so the fragments are the full frame's, bit for bit), and the hardware raster path draws
/// the full frame's viewport into the window's target ([`Region::viewport`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
pub struct Region {
    /// Column of the window's left edge in the full frame.
    pub x: u32,
    /// Row of the window's top edge in the full frame (row 0 at the top).
    pub y: u32,
    /// The full frame's width in pixels.
    pub full_width: u32,
    /// The full frame's height in pixels.
    pub full_height: u32,
}

impl Region {
    /// The viewport `[x, y, width, height]` (pixels, row 0 at the top) that draws the full
    /// frame into this window's target: the full frame's size, placed at minus the window's
    /// origin. The window's target cuts what lies outside it, and the rasterizer clips and
    /// samples in the full frame's viewport, so a window's fragments are the untiled frame's
    /// there, edges included (a clip-space mapping of the window, [`Region::clip_matrix`], moves
    /// the float arithmetic of clipping and edge setup, and pixels on an edge may land on either
    /// side of a tile seam). `None` where the full frame is over `max_side` pixels a side (the
    /// device's largest viewport): such a window maps through [`Region::clip_matrix`] instead.
    pub fn viewport(&self, max_side: u32) -> Option<[f32; 4]> {
        (self.full_width <= max_side && self.full_height <= max_side)
            .then(|| [-(self.x as f32), -(self.y as f32), self.full_width as f32, self.full_height as f32])
    }

    /// The clip-space transform that maps the window `width × height` at this region's origin
    /// onto the whole viewport of a `width × height` target: applied after the projection
    /// (`clip_matrix · proj · view`), a rasterizer with the window's viewport draws what the full
    /// frame's viewport draws there. x and y only (z and w are untouched, so depths and the
    /// near and far planes are the full frame's). Float arithmetic: pixels on an edge may differ
    /// from the full frame's as the hardware path's edges may anyway.
    pub fn clip_matrix(&self, width: u32, height: u32) -> glam::Mat4 {
        let (fw, fh) = (self.full_width as f32, self.full_height as f32);
        let (w, h) = (width.max(1) as f32, height.max(1) as f32);
        // x_t = ndc·W/w + (W − 2x)/w − 1 and y_t = ndc·H/h + 1 − (H − 2y)/h, times w_clip
        let sx = fw / w;
        let tx = (fw - 2.0 * self.x as f32) / w - 1.0;
        let sy = fh / h;
        let ty = 1.0 - (fh - 2.0 * self.y as f32) / h;
        glam::Mat4::from_cols(
            Vec4::new(sx, 0.0, 0.0, 0.0),
            Vec4::new(0.0, sy, 0.0, 0.0),
            Vec4::new(0.0, 0.0, 1.0, 0.0),
            Vec4::new(tx, ty, 0.0, 1.0),
        )
    }
}

/// How `bdp`, `dp` and `ddp` capture fragments on a GPU backend's hardware raster path (other
/// techniques and the compute path ignore it).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum HardwareCapture {
    /// Fragment-stage storage-buffer atomics, the same capture function as the compute
    /// rasterizer (integer `atomicMax` of the packed colours for bdp, a 64-bit `atomicMin` of
    /// (depth, payload) for dp). The default: measured faster than blending on the H100 (3.0 vs
    /// 0.12 Gfrag/s, the project design's platform facts).
    #[default]
    Atomics,
    /// The papers' graphics-pipeline mechanisms: MAX blending into 8 `Rgba32Float` targets for
    /// bdp's colour mode (HPG 2009), a depth test against a fresh depth attachment, the previous
    /// layer read from a depth texture and an occlusion query per peel for dp (Everitt 2001), MAX
    /// blending of (−d, d) into an `Rg32Float` target per pass for ddp (Bavoil & Myers 2008),
    /// additive blending into float targets for wavg/wsum; on oit-vulkan also adp's histogram by
    /// logic-op OR into 8 `R32G32B32A32_UINT` targets (HPG 2009; wgpu has no logic ops).
    Blend,
}

impl FromStr for HardwareCapture {
    type Err = OitError;
    fn from_str(s: &str) -> Result<HardwareCapture, OitError> {
        match s.trim().to_ascii_lowercase().as_str() {
            "atomics" => Ok(HardwareCapture::Atomics),
            "blend" => Ok(HardwareCapture::Blend),
            other => Err(OitError::InvalidSettings(format!(
                "unknown hardware capture '{other}': use atomics or blend"
            ))),
        }
    }
}

/// What the buckets of `bdp` hold.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BdpMode {
    /// Colour mode for transparency with one pass, depth mode otherwise (multi-pass `bdp:P` and
    /// every effect but transparency need depths).
    #[default]
    Auto,
    /// 32 subintervals of packed RGBA8 colours (HPG 2009 section 3.2, for transparency).
    Color,
    /// 16 subintervals, each keeping its nearest and farthest fragment (HPG 2009 eq. 2–4).
    Depth,
}

impl FromStr for BdpMode {
    type Err = OitError;
    fn from_str(s: &str) -> Result<BdpMode, OitError> {
        match s.trim().to_ascii_lowercase().as_str() {
            "auto" => Ok(BdpMode::Auto),
            "color" | "colour" => Ok(BdpMode::Color),
            "depth" => Ok(BdpMode::Depth),
            other => Err(OitError::InvalidSettings(format!(
                "unknown bdp mode '{other}': use auto, color or depth"
            ))),
        }
    }
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            width: 512,
            height: 512,
            technique: Technique::Reference,
            background: Vec3::new(0.06, 0.07, 0.09),
            alpha: None,
            max_peels: None,
            shading: Shading::Headlight,
            effect: Effect::Transparency,
            bounds: BoundsMode::Auto,
            raster: None,
            bdp_mode: BdpMode::Auto,
            hardware_capture: HardwareCapture::Atomics,
            region: None,
            memory: None,
            overflow: Overflow::Drop,
            atomic_storage: AtomicStorage::Buffer,
            blend_target: BlendTarget::F32,
            samples: 1,
            supersample: false,
            pixel_coverage: false,
            fraction_coverage: false,
        }
    }
}

/// Largest width or height accepted.
pub const MAX_SIZE: u32 = 16_384;

/// The most worker threads a CPU backend accepts: 4 × the machine's available parallelism. More
/// buys nothing and each costs a stack and start-up time (`--threads 100000` ran for minutes).
pub fn max_threads() -> usize {
    4 * std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// Checks a thread count against 1 ..= [`max_threads`].
pub fn check_threads(threads: usize) -> Result<(), OitError> {
    let max = max_threads();
    if threads == 0 {
        return Err(OitError::InvalidSettings("--threads must be at least 1".into()));
    }
    if threads > max {
        return Err(OitError::InvalidSettings(format!(
            "--threads {threads} is over {max} (4 × this machine's {} cores): use at most {max}, or leave it out for one per core",
            max / 4
        )));
    }
    Ok(())
}

impl Settings {
    /// Whether `bdp:passes` runs in colour mode (packed colours in 32 buckets, transparency only,
    /// one pass) under these settings, or in depth mode; `bdp_mode: Auto` picks colour mode
    /// where it can. Colour mode asked for where it cannot run is an error. The one rule every
    /// backend follows.
    pub fn bdp_color_mode(&self, passes: u32) -> Result<bool, OitError> {
        let fits = passes == 1 && self.effect == Effect::Transparency;
        match self.bdp_mode {
            BdpMode::Depth => Ok(false),
            BdpMode::Auto => Ok(fits),
            BdpMode::Color if fits => Ok(true),
            BdpMode::Color => Err(OitError::InvalidSettings(
                "bdp's colour mode holds colours only, in one pass: use --bdp-mode depth for bdp:P or for effects other than transparency".into(),
            )),
        }
    }

    /// Checks every setting; backends call this before allocating anything.
    pub fn validate(&self) -> Result<(), OitError> {
        if self.width == 0 || self.height == 0 {
            return Err(OitError::InvalidSettings(format!(
                "image size {}x{} is empty: use at least 1x1, e.g. --size 512x512",
                self.width, self.height
            )));
        }
        if self.width > MAX_SIZE || self.height > MAX_SIZE {
            return Err(OitError::InvalidSettings(format!(
                "image size {}x{} is over {MAX_SIZE} pixels on a side",
                self.width, self.height
            )));
        }
        if let Some(a) = self.alpha
            && !(0.0..=1.0).contains(&a)
        {
            return Err(OitError::InvalidSettings(format!("alpha {a} is outside [0, 1]")));
        }
        if !self.background.is_finite()
            || self.background.min_element() < 0.0
            || self.background.max_element() > 1.0
        {
            return Err(OitError::InvalidSettings("background channels must lie in [0, 1]".into()));
        }
        if self.max_peels == Some(0) {
            return Err(OitError::InvalidSettings("--max-peels must be at least 1".into()));
        }
        crate::msaa::check_samples(self.samples)?;
        if self.supersample && self.samples == 1 {
            return Err(OitError::InvalidSettings(
                "--supersample is the supersampled reference at the sample count: use it with --samples 4 or 8".into(),
            ));
        }
        if self.fraction_coverage && (self.samples == 1 || self.pixel_coverage) {
            return Err(OitError::InvalidSettings(
                "--coverage fraction weighs the multisampled fragments' alpha: use it with --samples 4 or 8"
                    .into(),
            ));
        }
        if self.pixel_coverage && self.samples == 1 {
            return Err(OitError::InvalidSettings(
                "--coverage pixel composites the multisampled fragments per pixel: use it with --samples 4 or 8".into(),
            ));
        }
        if self.memory == Some(0) {
            return Err(OitError::InvalidSettings(
                "--memory must be at least 1 byte, e.g. --memory 512M".into(),
            ));
        }
        // `--blend-target unorm8` with wavg/wsum is refused only where the target is used (the GPU
        // backends' blend capture, `BlendTarget::weighted_param`): oit-cpu, the compute path and
        // the atomics capture ignore the target, as `--help` says (issue 41.6)
        if let Some(r) = self.region {
            let inside =
                |origin: u32, size: u32, full: u32| u64::from(origin) + u64::from(size) <= u64::from(full);
            if r.full_width > MAX_SIZE
                || r.full_height > MAX_SIZE
                || !inside(r.x, self.width, r.full_width)
                || !inside(r.y, self.height, r.full_height)
            {
                return Err(OitError::InvalidSettings(format!(
                    "region {}x{} at ({}, {}) does not lie within its {}x{} frame",
                    self.width, self.height, r.x, r.y, r.full_width, r.full_height
                )));
            }
        }
        Ok(())
    }

    /// The memory budget of a frame's storage: the device's (`device`, a name and bytes) or
    /// `--memory`, whichever is smaller. Every backend checks its storage against this.
    pub fn memory_budget(&self, device: (String, u64)) -> (String, u64) {
        match self.memory {
            Some(m) if m < device.1 => (format!("the memory budget (--memory {m})"), m),
            _ => device,
        }
    }

    /// The object's colour with the alpha override applied.
    pub fn material_color(&self, color: Vec4) -> Vec4 {
        match self.alpha {
            Some(a) => color.truncate().extend(a),
            None => color,
        }
    }

    /// Pixels in the image.
    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }
}

/// Parses `WxH` (e.g. `512x512`).
pub fn parse_size(text: &str) -> Result<(u32, u32), OitError> {
    let bad = || OitError::InvalidSettings(format!("size '{text}' is not WIDTHxHEIGHT, e.g. 512x512"));
    let (w, h) = text.trim().split_once(['x', 'X']).ok_or_else(bad)?;
    let w: u32 = w.trim().parse().map_err(|_| bad())?;
    let h: u32 = h.trim().parse().map_err(|_| bad())?;
    if w == 0 || h == 0 {
        return Err(OitError::InvalidSettings(format!("size '{text}' is empty: use at least 1x1")));
    }
    Ok((w, h))
}

/// Parses a byte count: a whole or decimal number with an optional binary suffix, `K`, `M`, `G`
/// or `T` (× 1024, 1024², 1024³, 1024⁴; `KiB`, `MB`, ... read the same), e.g. `512M`, `2G`,
/// `1.5G`, `100000`.
pub fn parse_memory(text: &str) -> Result<u64, OitError> {
    let bad = || {
        OitError::InvalidSettings(format!(
            "memory '{text}' is not a byte count: use a number with an optional K, M, G or T (binary), e.g. 512M or 2G"
        ))
    };
    let t = text.trim();
    let digits = t.find(|c: char| !(c.is_ascii_digit() || c == '.')).unwrap_or(t.len());
    let (number, suffix) = t.split_at(digits);
    let number: f64 = number.parse().map_err(|_| bad())?;
    let suffix = suffix.trim().to_ascii_lowercase();
    let suffix = suffix.strip_suffix('b').unwrap_or(&suffix);
    let suffix = suffix.strip_suffix('i').unwrap_or(suffix);
    let scale: f64 = match suffix {
        "" => 1.0,
        "k" => 1024.0,
        "m" => 1024.0 * 1024.0,
        "g" => 1024.0 * 1024.0 * 1024.0,
        "t" => 1024.0 * 1024.0 * 1024.0 * 1024.0,
        _ => return Err(bad()),
    };
    let bytes = (number * scale).floor();
    if !bytes.is_finite() || bytes >= u64::MAX as f64 {
        return Err(bad());
    }
    if bytes < 1.0 {
        return Err(OitError::InvalidSettings(format!("memory '{text}' is less than one byte")));
    }
    Ok(bytes as u64)
}

/// Parses `R,G,B` in [0, 1] (e.g. `1,1,1`).
pub fn parse_rgb(text: &str) -> Result<Vec3, OitError> {
    let bad = || OitError::InvalidSettings(format!("colour '{text}' is not R,G,B with each in [0, 1]"));
    let parts: Vec<f32> =
        text.split(',').map(|p| p.trim().parse::<f32>()).collect::<Result<_, _>>().map_err(|_| bad())?;
    match parts[..] {
        [r, g, b] if [r, g, b].iter().all(|c| (0.0..=1.0).contains(c)) => Ok(Vec3::new(r, g, b)),
        _ => Err(bad()),
    }
}

#[cfg(test)]
mod thread_tests {
    use super::*;

    #[test]
    fn memory_sizes() {
        assert_eq!(parse_memory("512M").unwrap(), 512 << 20);
        assert_eq!(parse_memory("2G").unwrap(), 2 << 30);
        assert_eq!(parse_memory("2GiB").unwrap(), 2 << 30);
        assert_eq!(parse_memory("1.5k").unwrap(), 1536);
        assert_eq!(parse_memory(" 100000 ").unwrap(), 100_000);
        for bad in ["", "M", "12Q", "-5M", "0", "1e99T", "0.1"] {
            assert!(parse_memory(bad).is_err(), "{bad}");
        }
        let s = Settings { memory: Some(1000), ..Settings::default() };
        assert_eq!(s.memory_budget(("device".into(), 5000)).1, 1000);
        assert_eq!(s.memory_budget(("device".into(), 500)), ("device".to_string(), 500));
    }

    #[test]
    fn regions_lie_within_their_frame() {
        let r = |x, y| Settings {
            width: 10,
            height: 5,
            region: Some(Region { x, y, full_width: 20, full_height: 10 }),
            ..Settings::default()
        };
        assert!(r(10, 5).validate().is_ok());
        assert!(r(11, 0).validate().is_err());
        assert!(r(0, 6).validate().is_err());
        assert!(r(u32::MAX, 0).validate().is_err());
    }

    /// The clip matrix puts a window's corners at the corners of its viewport.
    #[test]
    fn region_clip_matrix() {
        let region = Region { x: 30, y: 10, full_width: 100, full_height: 50 };
        let m = region.clip_matrix(20, 40);
        // full-frame pixel (x, y) → ndc
        let ndc = |x: f32, y: f32| Vec4::new(x / 100.0 * 2.0 - 1.0, 1.0 - y / 50.0 * 2.0, 0.5, 1.0);
        let a = m * ndc(30.0, 10.0);
        let b = m * ndc(50.0, 50.0);
        assert!((a.x + 1.0).abs() < 1e-6 && (a.y - 1.0).abs() < 1e-6, "{a}");
        assert!((b.x - 1.0).abs() < 1e-6 && (b.y + 1.0).abs() < 1e-6, "{b}");
        assert_eq!((a.z, a.w), (0.5, 1.0));
    }

    /// Issue 13.11: thread counts are bounded by the machine.
    #[test]
    fn threads_are_bounded() {
        assert!(check_threads(0).is_err());
        assert!(check_threads(1).is_ok());
        assert!(check_threads(max_threads()).is_ok());
        let e = check_threads(100_000).unwrap_err().to_string();
        assert!(e.contains("100000") && e.contains(&max_threads().to_string()), "{e}");
    }
}
