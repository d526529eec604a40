//! A technique's plan for one frame: the rules every backend executes and none restates — what
//! the combination of technique and settings refuses, how many capture passes run, when peeling
//! stops, how scene-sized arrays are sized, what the 32-bit `mdts` stores for alpha, and the
//! storage a frame allocates.
//!
//! Backends build one [`Plan`] per frame ([`Plan::new`], before allocating anything) and ask it;
//! the WGSL mirrors of the per-fragment rules (bucket index, eq. 5, packing) live in
//! [`crate::rules`] and are parity-tested against the shaders.

use crate::{Effect, OitError, Scene, Settings, Technique};

/// How a technique's per-pixel arrays are sized.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sizing {
    /// A fixed number of slots (`fabs:K`, `mdts:K`, `mlp:M`'s M).
    Fixed(u32),
    /// From the scene: a counting pass measures the deepest pixel ([`Plan::slots`]).
    FromCount,
    /// Exactly the frame's fragments (`dfb`, `ll`): a counting pass totals them
    /// ([`Counted::fragments`]), and storage is a per-pixel part and one entry per fragment.
    Exact,
    /// The technique has no per-pixel array whose size follows the scene.
    None,
}

/// Bytes of the resolve state every technique keeps per pixel (23 words: the composite's 16 and
/// the ties' 7), counted in [`Plan::storage_bytes`] and not in `Stats::storage_bytes`.
pub const RESOLVE_STATE_BYTES: u64 = 92;

/// Bytes a frame holds per pixel beside its technique's storage, on every backend: the RGBA8
/// image (4), the per-pixel lost counters it keeps while it runs (4) and the per-pixel losses it
/// hands back (`Frame::lost_pixels`, 4). The reference adds its per-pixel fragment counts
/// (`Frame::layers`, [`LAYERS_BYTES`]). Counted in [`Plan::frame_bytes`], not in
/// `Stats::storage_bytes`.
pub const OUTPUT_BYTES: u64 = 12;

/// Bytes a pixel's fragment count takes in a frame that hands its counts back (`Frame::layers`:
/// the reference's).
pub const LAYERS_BYTES: u64 = 4;

/// What a frame's counting pass found: the deepest pixel's fragments and the frame's. Zeros
/// (`Counted::default()`) before a count, or for a technique that runs none.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counted {
    /// Fragments of the deepest pixel.
    pub deepest: u32,
    /// Fragments of the whole frame (one geometry pass's).
    pub fragments: u64,
}

/// What one geometry pass of a [`Plan::schedule`] does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PassKind {
    /// The opaque pass ([`crate::Scene::layers`]): the opaque part's nearest (depth, primitive
    /// id) per pixel (a 64-bit MIN), then the colour of the fragment that holds it.
    Opaque,
    /// Each pixel's depth range, over the instances' bounding boxes or the scene (bdp, adp).
    Bounds,
    /// Each pixel's fragments counted, to size the arrays.
    Count,
    /// adp's 1024-bin depth histogram.
    Histogram,
    /// One capture into the arrays (bdp runs P of them).
    Capture,
    /// A peel: the next layer(s) of every pixel (dp, ddp, mlp).
    Peel,
    /// One adp batch of 32 equalized buckets.
    Batch,
    /// The fill of an exact allocation (reference, dfb, ll).
    Fill,
    /// `fabs:K` where a pixel overflowed: its K nearest keys, then their payloads.
    Overflow,
    /// `--overflow tail` where a pixel overflowed: every fragment behind its K-th nearest added to
    /// its tail sums.
    Tail,
}

/// One array of a technique's storage ([`Plan::arrays`]): `element_bytes` per element, and
/// `per_pixel` elements a pixel, `per_fragment` a fragment of the frame, `fixed` once.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Array {
    /// What the array holds.
    pub name: &'static str,
    /// Bytes of one element.
    pub element_bytes: u64,
    /// Elements per pixel.
    pub per_pixel: u64,
    /// Elements per fragment of the frame (exact allocations).
    pub per_fragment: u64,
    /// Elements once per frame.
    pub fixed: u64,
}

impl Array {
    /// The array's bytes for a frame of `pixels` pixels and `fragments` fragments, in whole
    /// 32-bit words.
    pub fn bytes(&self, pixels: u64, fragments: u64) -> u64 {
        pixels
            .saturating_mul(self.per_pixel)
            .saturating_add(fragments.saturating_mul(self.per_fragment))
            .saturating_add(self.fixed)
            .saturating_mul(self.element_bytes)
            // an array of elements smaller than a word (the coverage masks, a byte each) is
            // allocated in whole 32-bit words on every backend, as a GPU storage buffer must be
            .saturating_add(3)
            / 4
            * 4
    }
}

/// How `technique` runs as an order-free sum: the plan's matches over the techniques list every
/// other technique by name and leave these to their one entry ([`Technique::sums`]), so a
/// technique of that family is not listed here. A technique that is neither is a bug that every
/// plan test finds (`every_technique_has_a_plan`).
fn sums_of(technique: Technique) -> crate::Sums {
    technique
        .sums()
        .unwrap_or_else(|| panic!("{technique} has no arm in the plan and is not an order-free sum"))
}

/// The plan of one frame: see the module docs.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    /// The technique.
    pub technique: Technique,
    /// Whether a bounds pass gives each pixel's depth range first (bdp, adp).
    pub bounds_pass: bool,
    /// Where that pass takes the range from: the settings' [`BoundsMode`](crate::BoundsMode)
    /// resolved for the scene ([`BoundsMode::resolve`](crate::BoundsMode::resolve): exact where
    /// the frame has an opaque part, unless the settings name the boxes); never `Auto`.
    pub bounds: crate::BoundsMode,
    /// bdp only: the one-pass colour mode (32 packed colours) instead of the depth mode.
    pub bdp_color: bool,
    /// How the per-pixel arrays are sized.
    pub sizing: Sizing,
    /// Peels, capture passes or batches at most (`--max-peels`; unbounded when not set).
    pub peel_limit: u32,
    /// `mdts` (32-bit) only: the 8-bit alpha every fragment gets, since its words hold RGB.
    pub mdts_alpha8: u32,
    /// Whether the resolve counts ties ([`crate::Stats::tied`]): the technique orders equal
    /// depths by its key's payload (colour or normal), not by primitive id as the reference does,
    /// so a run of equal depths with two payloads or more reaching the resolve may be out of the
    /// reference's order. `dp`, `ddp`, `mlp`, `mdts64` (depth bits above the payload in one 64-bit
    /// atomic word: no room for an id), `mdts` (20 depth bits above colour bits: equal at 2⁻²⁰)
    /// `bdp`'s depth mode (a subinterval's min and max keys) and `adp` (a bin's nearest and
    /// farthest keys). Not `plain`, which orders by
    /// primitive id alone and never claims depth order, nor `fabs`: it carries the
    /// primitive id and sorts by (depth, id) as the reference does, nor `dfb` and `ll`, whose
    /// entries carry it likewise; not the colour mode of `bdp` nor the order-free `wavg`/`wsum`.
    pub count_ties: bool,
    /// `plain` composited as its fragments arrive, by a rasterizer that hands each pixel its
    /// fragments in submission order ([`Plan::on_path`]): a hardware path's blender (one draw,
    /// back to front) or oit-cpu's banded pass (each pixel's fragments from one thread, highest
    /// primitive first, front to back). Per pixel a running colour and transmittance and a
    /// fragment count; one geometry pass, no counting pass. Elsewhere (a compute rasterizer,
    /// whose threads reach a pixel in no fixed order) `plain` keeps each pixel's fragments and
    /// sorts them by primitive id.
    pub in_order: bool,
    /// `--overflow tail` on a fixed-size `fabs:K`, `mdts:K` or `mdts64:K`: a pixel's fragments
    /// behind its K nearest are merged into a tail (5 sums of 64 bits a pixel, one more geometry
    /// pass where a pixel overflowed) instead of dropped. False where K comes from a counting
    /// pass: nothing can overflow there.
    pub tail: bool,
    /// `--atomic-storage image` on `mdts:K`, `mdts64:K` or `fabs:K`: their atomic words live in
    /// storage images ([`crate::AtomicStorage::Image`]; a backend without them refuses, see
    /// [`Plan::refuse_image_atomics`]). False for every other technique, which ignores the
    /// setting (the reference a comparison renders beside them runs under the same settings).
    pub image_atomics: bool,
    /// Whether the scene has opaque or masked instances ([`crate::Scene::has_opaque`]): the frame
    /// runs the opaque pass first ([`PassKind::Opaque`], two geometry passes over the opaque
    /// part) into [`OPAQUE_BYTES`] a sample ([`Plan::opaque_bytes`]), and the technique captures
    /// only what lies in front.
    pub opaque: bool,
    /// Samples a pixel (`Settings::samples`): above 1 each entry of `reference`, `dfb`, `ll` and
    /// `fabs` carries its coverage mask beside it, a byte ([`Plan::arrays`]; docs/msaa.md).
    pub samples: u32,
    /// `dp`, `ddp` or `mlp` peeling per sample ([`crate::msaa::peels_per_sample`]): its keys are
    /// (depth, primitive id), the peeled layers' payloads and masks are fetched by the next pass,
    /// and each sample composites into accumulators of its own ([`Plan::arrays`]); one pass more
    /// than its peels ([`Plan::schedule`]).
    pub sample_peel: bool,
    /// Samples a pixel of the multisampled render targets a GPU hardware path's own capture
    /// blends into, and the colour target's bytes a sample: plain's blender, and `wavg`, `wsum`,
    /// `bdp`'s colour mode, `dp` and `ddp` (per sample: dp's layer target's bytes, beside its two
    /// depth targets and its accumulators; ddp's range target's, two of them, beside its hand-overs
    /// and accumulators) under `--hardware-capture blend`, on a GPU backend's hardware
    /// raster path at several samples (docs/msaa.md, "The blend captures at several samples";
    /// there the path is always named, `Settings::raster`: at several samples the GPU backends'
    /// default is the compute path). Their arrays are those targets, each sample counted
    /// ([`Plan::arrays`]), so the budget and `--memory`'s tiles count them. `None` elsewhere (at
    /// one sample a target is a pixel's, the arrays as they were).
    pub blend_targets: Option<(u32, u64)>,
    /// Whether the backend sizes the per-fragment arrays (`dfb`'s, `ll`'s, the reference's) in
    /// size classes ([`Plan::fragment_capacity`]): the GPU backends (`wgpu`, `vulkan`), whose
    /// buffers come from a pool that nearby views share. oit-cpu allocates exactly.
    pub pooled: bool,
}

/// Bytes a sample of the opaque pass's image holds: its nearest opaque (depth, primitive id) key
/// (8) and that fragment's linear RGB (3 × 4). One sample a pixel at `--samples 1`; at several
/// samples the image is kept a sample ([`Plan::opaque_bytes`], docs/msaa.md).
pub const OPAQUE_BYTES: u64 = 20;

impl Plan {
    /// The plan for `settings` on `scene`, or the reason the combination is refused (the same on
    /// every backend; `backend` names the one asking, for the message).
    pub fn new(backend: &str, scene: &Scene, settings: &Settings) -> Result<Plan, OitError> {
        let technique = settings.technique;
        if matches!(technique, Technique::Mdts { .. }) && settings.effect == Effect::Fresnel {
            return Err(OitError::Unsupported {
                backend: backend.into(),
                what: "fresnel with mdts: its 12 + 12 spare bits hold RGB only; use mdts64".into(),
            });
        }
        if matches!(
            technique,
            Technique::Plain
                | Technique::WeightedAverage
                | Technique::WeightedSum
                | Technique::Wboit
                | Technique::Mboit { .. }
        ) && matches!(settings.effect, Effect::Translucency | Effect::Fresnel)
        {
            return Err(OitError::Unsupported {
                backend: backend.into(),
                what: format!(
                    "the {:?} effect with {technique}: it never orders fragments; use a sorting technique (dp, fabs, adp, ...)",
                    settings.effect
                ),
            });
        }
        // an order-free sum technique's integer sums hold so many fragments a pixel, and a pixel
        // holds at most one fragment a triangle: a scene of more triangles could wrap a sum in
        // silence, and is refused (`Sums::max_triangles`)
        if let Some(limit) = technique.sums().and_then(|s| s.max_triangles)
            && scene.triangle_count() > limit
        {
            return Err(OitError::Unsupported {
                backend: backend.into(),
                what: format!(
                    "{technique} on a scene of {} triangles: its per-pixel sums hold {limit} fragments \
                     a pixel, and a pixel can take one a triangle; use an exact technique (ll, dfb) or \
                     split the scene",
                    scene.triangle_count()
                ),
            });
        }
        if matches!(technique, Technique::Kbuf { k: Some(_) }) && settings.overflow == crate::Overflow::Tail {
            return Err(OitError::Unsupported {
                backend: backend.into(),
                what: "--overflow tail with kbuf:K: the k-buffer drops what lies behind its K \
                       (counted as lost); use fabs:K for a tail, or kbuf without K (sized from \
                       the scene)"
                    .into(),
            });
        }
        let fixed_k = matches!(
            technique,
            Technique::Fabs { k: Some(_) }
                | Technique::Mdts { k: Some(_) }
                | Technique::Mdts64 { k: Some(_) }
        );
        // other techniques have no K to overflow and ignore the setting (the reference a
        // comparison renders beside fabs:K runs under the same settings)
        if settings.overflow == crate::Overflow::Tail && fixed_k && settings.effect != Effect::Transparency {
            return Err(OitError::Unsupported {
                backend: backend.into(),
                what: format!(
                    "--overflow tail with the {:?} effect: the tail merges colours by weight and keeps no \
                     order or normals; use --overflow drop",
                    settings.effect
                ),
            });
        }
        let bdp_color = match technique {
            Technique::Bdp { passes } => settings.bdp_color_mode(passes)?,
            _ => false,
        };
        let sizing = match technique {
            Technique::Fabs { k }
            | Technique::Mdts { k }
            | Technique::Mdts64 { k }
            | Technique::Kbuf { k } => k.map_or(Sizing::FromCount, Sizing::Fixed),
            Technique::Mlp { m } => Sizing::Fixed(m),
            Technique::Dfb | Technique::Ll => Sizing::Exact,
            // where no rasterizer keeps submission order (a compute rasterizer), each pixel's
            // fragments are kept and sorted by primitive id: as many slots as the deepest pixel
            // (none where one does: Plan::on_path)
            Technique::Plain => Sizing::FromCount,
            _ => Sizing::None,
        };
        // alpha is not stored by mdts: the override, else the mean of the objects' alphas
        let alpha = match settings.alpha {
            Some(a) => a,
            None => {
                // the blended objects' (those a technique captures), with their transmission
                let blended = scene.objects.iter().filter(|o| !o.is_opaque_pass());
                let (sum, n) = blended.fold((0.0f32, 0usize), |(s, n), o| (s + o.effective_alpha(), n + 1));
                sum / n.max(1) as f32
            }
        };
        // the hardware path's own captures into multisampled targets (docs/msaa.md)
        let blend_targets = (settings.samples > 1
            && matches!(backend, "wgpu" | "vulkan")
            && settings.raster == Some(crate::RasterPath::Hardware)
            && (technique == Technique::Plain
                || settings.hardware_capture == crate::HardwareCapture::Blend
                    && (matches!(technique, Technique::WeightedAverage | Technique::WeightedSum)
                        || bdp_color
                        || matches!(technique, Technique::Dp | Technique::Ddp)
                            && crate::msaa::peels_per_sample(settings))))
        .then(|| {
            let colour = match settings.blend_target {
                // dp's layer target, (payload, mask) in two u32; ddp's range, two f32
                _ if matches!(technique, Technique::Dp | Technique::Ddp) => 8,
                crate::BlendTarget::F32 => 16,
                crate::BlendTarget::F16 => 8,
                crate::BlendTarget::Unorm8 => 4,
            };
            (settings.samples, colour)
        });
        let sample_peel = crate::msaa::peels_per_sample(settings);
        if sample_peel {
            let primitives = scene.primitive_bases().1;
            if primitives > crate::msaa::PEEL_KEY_PRIMITIVES {
                return Err(OitError::Unsupported {
                    backend: backend.into(),
                    what: format!(
                        "{technique} at {} samples keys each fragment by its primitive id in 29 bits, and the \
                         scene has {primitives} triangles (at most {} fit); use --coverage fraction, or \
                         another technique",
                        settings.samples,
                        crate::msaa::PEEL_KEY_PRIMITIVES
                    ),
                });
            }
        }
        Ok(Plan {
            blend_targets,
            in_order: false,
            samples: settings.samples,
            sample_peel,
            pooled: matches!(backend, "wgpu" | "vulkan"),
            technique,
            bounds_pass: matches!(technique, Technique::Bdp { .. } | Technique::Adp),
            bounds: settings.bounds.resolve(scene.has_opaque()),
            bdp_color,
            sizing,
            peel_limit: settings.max_peels.unwrap_or(u32::MAX),
            mdts_alpha8: (alpha.clamp(0.0, 1.0) * 255.0 + 0.5) as u32,
            tail: fixed_k && settings.overflow == crate::Overflow::Tail,
            image_atomics: settings.atomic_storage == crate::AtomicStorage::Image
                && matches!(
                    technique,
                    Technique::Fabs { .. } | Technique::Mdts { .. } | Technique::Mdts64 { .. }
                ),
            count_ties: match technique {
                Technique::Dp
                | Technique::Ddp
                | Technique::Mlp { .. }
                | Technique::Mdts { .. }
                | Technique::Mdts64 { .. }
                | Technique::Adp => true,
                Technique::Bdp { .. } => !bdp_color,
                _ => false,
            },
            opaque: scene.has_opaque(),
        })
    }

    /// The refusal of a backend that keeps its atomic words in buffers only, where the plan asks
    /// for storage images (`Ok` where it does not).
    pub fn refuse_image_atomics(&self, backend: &str) -> Result<(), OitError> {
        if !self.image_atomics {
            return Ok(());
        }
        Err(OitError::Unsupported {
            backend: backend.into(),
            what: format!(
                "--atomic-storage image for {}: storage-image atomics run on the vulkan backend only \
                 (WGSL's textureAtomic* return no value; the CPU has no images); use --atomic-storage \
                 buffer or --backend vulkan",
                self.technique
            ),
        })
    }

    /// The refusal of a backend or raster path without an ordered fragment-stage interlock
    /// (`VK_EXT_fragment_shader_interlock`'s `fragmentShaderPixelInterlock`), where the plan's
    /// technique needs one (`kbuf`); `Ok` for every other technique. `why` says what this backend
    /// or path lacks.
    pub fn refuse_interlock(&self, backend: &str, why: &str) -> Result<(), OitError> {
        if !self.needs_interlock() {
            return Ok(());
        }
        Err(OitError::Unsupported {
            backend: backend.into(),
            what: format!(
                "{}: the k-buffer keeps its slots sorted inside the fragment shader's ordered critical \
                 section (VK_EXT_fragment_shader_interlock), and {why}; use --backend vulkan --raster \
                 hardware on a device with fragmentShaderPixelInterlock, or fabs:K, which keeps the \
                 same K nearest fragments",
                self.technique
            ),
        })
    }

    /// Whether the technique runs inside a fragment-stage interlock
    /// ([`crate::TechniqueKind::needs_interlock`]).
    pub fn needs_interlock(&self) -> bool {
        self.technique.kind().needs_interlock()
    }

    /// The plan as a backend's `path` runs it: on a hardware raster path `plain` is the blender's
    /// (one draw in submission order into float targets), and on oit-cpu's (`RasterPath::Cpu`)
    /// its banded pass's (each pixel's fragments from one thread, in reverse submission order,
    /// composited as they come): [`Plan::in_order`]. Every other technique is the same on every
    /// path.
    pub fn on_path(mut self, path: crate::RasterPath) -> Plan {
        if self.technique == Technique::Plain
            && matches!(path, crate::RasterPath::Hardware | crate::RasterPath::Cpu)
        {
            self.in_order = true;
            self.sizing = Sizing::None;
        }
        self
    }

    /// Slots per pixel for a scene whose deepest pixel holds `deepest` fragments (from the
    /// counting pass; ignored for fixed sizes): never zero, so an empty frame still has a shape.
    pub fn slots(&self, deepest: u32) -> u32 {
        match self.sizing {
            Sizing::Fixed(k) => k,
            Sizing::FromCount | Sizing::Exact | Sizing::None => deepest.max(1),
        }
    }

    /// The technique's arrays, as the GPU backends lay them out (oit-cpu reports the same bytes;
    /// its host-side layouts differ in places): each one's name, element size and
    /// count (per pixel, per fragment of the frame, and fixed), given what the frame's counting
    /// pass found (`Counted::default()` before it is known; per-pixel slots are [`Plan::slots`]
    /// of the deepest pixel). This is the one definition of a technique's storage: each backend
    /// allocates these arrays (the per-fragment ones for [`Plan::fragment_capacity`] elements)
    /// and reports their bytes in `Stats::storage_bytes`, and `tests/tests/plan.rs` holds every
    /// backend and raster path to it, to the byte.
    ///
    /// `dfb` and `ll` need exactly what the frame's fragments need: a fragment is a 64-bit key
    /// (depth bits, primitive id) and a 32-bit payload, 12 bytes; `dfb` adds a count and an offset
    /// a pixel (each array one entry longer, the offsets' last entry the total), `ll` a head a
    /// pixel, a 4-byte link a node and the node counter. The reference stores every fragment too
    /// (an offset a pixel and the total, a fill cursor a pixel, then 12-byte entries). Bookkeeping is not counted: the counting
    /// pass's own counters, the prefix sum's block totals on the GPU (one word per 256 pixels and
    /// per 256 of those), a peel loop's one-word flag, the resolve state (counted once, in
    /// [`Plan::storage_bytes`]).
    pub fn arrays(&self, counted: Counted) -> Vec<Array> {
        let k = u64::from(self.slots(counted.deepest));
        let per_pixel = |name, element_bytes, per_pixel| Array {
            name,
            element_bytes,
            per_pixel,
            per_fragment: 0,
            fixed: 0,
        };
        let bounds = per_pixel("depth bounds (min, max depth bits)", 4, 2);
        let mut arrays = self.own_arrays(k, per_pixel, bounds);
        if self.tail {
            arrays.push(per_pixel("tail sums (Σα·r, Σα·g, Σα·b, Σα, count)", 8, 5));
        }
        if self.samples > 1 {
            // the coverage mask of each entry, a byte beside it (8 samples at most)
            let masks = "coverage masks";
            match self.technique {
                Technique::Fabs { .. } | Technique::Kbuf { .. } => arrays.push(per_pixel(masks, 1, k)),
                Technique::Reference | Technique::Dfb | Technique::Ll => arrays.push(Array {
                    name: masks,
                    element_bytes: 1,
                    per_pixel: 0,
                    per_fragment: 1,
                    fixed: 0,
                }),
                _ => {}
            }
        }
        arrays
    }

    /// [`Plan::arrays`] but the tail's.
    fn own_arrays(
        &self,
        k: u64,
        per_pixel: impl Fn(&'static str, u64, u64) -> Array,
        bounds: Array,
    ) -> Vec<Array> {
        use crate::rules::{BDP_COLOR_SUBINTERVALS, BDP_DEPTH_SUBINTERVALS, BUCKETS, HISTOGRAM_WORDS};
        let samples = u64::from(self.samples);
        // the multisampled targets of a hardware path's own capture: samples and the colour
        // target's bytes a sample (one sample of RGBA32F where there are none)
        let (targets, colour) = self.blend_targets.map_or((1, 16), |(t, c)| (u64::from(t), c));
        match self.technique {
            // per sample (docs/msaa.md): the keys are (depth, primitive id), the layer the last
            // pass peeled waits for its payload and mask, which the next pass fetches, and each
            // sample composites into its own (premultiplied RGB, transmittance)
            // per sample on the blender (`--hardware-capture blend`): two depth targets, the
            // layer (colour, mask) and two primitive targets (ties peeled in primitive order) a
            // sample, and each sample's accumulator
            Technique::Dp if self.blend_targets.is_some() => vec![
                per_pixel("peel depths (two Depth32Float targets)", 4, 2 * targets),
                per_pixel("peeled layer (colour, mask)", colour, targets),
                per_pixel("peeled primitives (two R32Uint targets)", 4, 2 * targets),
                per_pixel("sample accumulators (RGB, transmittance)", 16, samples),
            ],
            // ddp per sample on the blender: two range targets a sample, each sample's near and
            // far hand-overs and accumulators, and the fragments handed over
            Technique::Ddp if self.blend_targets.is_some() => vec![
                per_pixel("range targets (two Rg32Float)", colour, 2 * targets),
                per_pixel("near hand-overs (depth key, colour)", 8, samples),
                per_pixel("far hand-overs (depth key, colour)", 8, samples),
                per_pixel("fragments handed over", 4, 1),
                per_pixel("sample accumulators (front and back RGB, transmittance)", 32, samples),
            ],
            Technique::Dp if self.sample_peel => vec![
                per_pixel("nearest (depth key, primitive id)", 8, 1),
                per_pixel("previous peel's key", 8, 1),
                per_pixel("peeled layer (colour, mask)", 8, 1),
                per_pixel("sample accumulators (RGB, transmittance)", 16, samples),
            ],
            // mlp:M per sample: the M slots a pass inserts into, the M keys the pass before kept
            // (whose payloads and masks this pass fetches; the deepest of them is where the pass
            // starts), those payloads and masks
            Technique::Mlp { .. } if self.sample_peel => vec![
                per_pixel("sorted slots (depth key, primitive id)", 8, k),
                per_pixel("previous pass's keys", 8, k),
                per_pixel("peeled layers (colours, masks)", 8, k),
                per_pixel("sample accumulators (RGB, transmittance)", 16, samples),
            ],
            Technique::Ddp if self.sample_peel => vec![
                per_pixel("near (depth key, primitive id)", 8, 1),
                per_pixel("far (depth key, primitive id)", 8, 1),
                per_pixel("open key range", 16, 1),
                per_pixel("peeled layers (colours, masks)", 16, 1),
                per_pixel("sample accumulators (front and back RGB, transmittance)", 32, samples),
            ],
            Technique::Reference => vec![
                Array { name: "offsets", element_bytes: 4, per_pixel: 1, per_fragment: 0, fixed: 1 },
                per_pixel("fill cursors", 4, 1),
                Array {
                    name: "entries (depth key, colour)",
                    element_bytes: 12,
                    per_pixel: 0,
                    per_fragment: 1,
                    fixed: 0,
                },
            ],
            // composited in submission order as the fragments come (a blender, oit-cpu's banded
            // pass): the running premultiplied colour and transmittance, 32-bit floats (the
            // blender's colour target; a device without 32-bit float blending gets 16-bit ones,
            // half the bytes), and the fragment count (the blender's count target)
            // (the hardware path's blender at several samples: each sample's, the colour target
            // of `--blend-target`, the count an R32Float; `Plan::blend_targets`, which
            // `Plan::new` knows from the named path where `Plan::on_path` has not run)
            Technique::Plain if self.in_order || self.blend_targets.is_some() => vec![
                per_pixel("colour and transmittance (RGBA float)", colour, targets),
                per_pixel("fragment count", 4, targets),
            ],
            // where no rasterizer keeps submission order (a compute rasterizer): a counter and
            // K slots of (primitive id, payload), sorted by id
            Technique::Plain => {
                vec![per_pixel("counter", 4, 1), per_pixel("slots (primitive id, payload)", 8, k)]
            }
            Technique::Dp => {
                vec![per_pixel("nearest (depth key, colour)", 8, 1), per_pixel("previous peel's depth", 4, 1)]
            }
            Technique::Ddp => vec![
                per_pixel("near (depth key, colour)", 8, 1),
                per_pixel("far (depth key, colour)", 8, 1),
                per_pixel("open depth range", 8, 1),
            ],
            // `--hardware-capture blend` at several samples: the sums in a colour target
            // (`--blend-target`) and the count in an R32Float one, a sample each
            Technique::WeightedAverage | Technique::WeightedSum if self.blend_targets.is_some() => vec![
                per_pixel("blended sums (colour target)", colour, targets),
                per_pixel("fragment count", 4, targets),
            ],
            // (in `--hardware-capture blend`'s multisampled targets, a pixel's buckets a sample)
            Technique::Bdp { .. } if self.bdp_color => {
                vec![bounds, per_pixel("colour buckets", 4, u64::from(BDP_COLOR_SUBINTERVALS) * targets)]
            }
            Technique::Bdp { .. } => vec![
                bounds,
                per_pixel(
                    "min and max buckets, per capture pass",
                    8,
                    u64::from(self.bdp_capture_passes()) * 2 * u64::from(BDP_DEPTH_SUBINTERVALS),
                ),
            ],
            Technique::Adp => vec![
                bounds,
                per_pixel("depth histogram (1024 bits)", 4, HISTOGRAM_WORDS as u64),
                per_pixel("buckets (farthest of each bin)", 8, BUCKETS as u64),
                per_pixel("nearest of each bin", 8, BUCKETS as u64),
            ],
            Technique::Mdts { .. } | Technique::Mdts64 { .. } => vec![per_pixel("sorted slots", 8, k)],
            Technique::Mlp { .. } => vec![
                per_pixel("sorted slots", 8, k),
                per_pixel("fragments at the previous pass's deepest depth", 4, 1),
            ],
            Technique::Fabs { .. } => vec![
                per_pixel("counter", 4, 1),
                per_pixel("slots (depth key, primitive id)", 8, k),
                per_pixel("payloads", 4, k),
            ],
            // sorted in place, an empty slot all ones: no counter
            Technique::Kbuf { .. } => {
                vec![per_pixel("sorted slots (depth key, primitive id)", 8, k), per_pixel("payloads", 4, k)]
            }
            Technique::Dfb => vec![
                Array { name: "counts", element_bytes: 4, per_pixel: 1, per_fragment: 0, fixed: 1 },
                Array { name: "offsets", element_bytes: 4, per_pixel: 1, per_fragment: 0, fixed: 1 },
                Array {
                    name: "entries (depth key, colour)",
                    element_bytes: 12,
                    per_pixel: 0,
                    per_fragment: 1,
                    fixed: 0,
                },
            ],
            Technique::Ll => vec![
                per_pixel("heads", 4, 1),
                Array { name: "node counter", element_bytes: 4, per_pixel: 0, per_fragment: 0, fixed: 1 },
                Array {
                    name: "nodes (depth key, colour, link)",
                    element_bytes: 16,
                    per_pixel: 0,
                    per_fragment: 1,
                    fixed: 0,
                },
            ],
            // the order-free sums (`Technique::sums`): their one array of u64 sums
            t => vec![per_pixel(sums_of(t).array, 8, sums_of(t).words)],
        }
    }

    /// Bytes of storage a frame of this plan allocates over `pixels` pixels, given what its
    /// counting pass found: the technique's [`Plan::arrays`] and the resolve state every
    /// technique keeps. One number every backend checks against its memory budget
    /// ([`Plan::check_budget`]) before it allocates.
    pub fn storage_bytes(&self, pixels: u64, counted: Counted) -> u64 {
        let frame = RESOLVE_STATE_BYTES + self.opaque_bytes();
        let fragments = self.fragment_capacity(counted.fragments);
        self.arrays(counted)
            .iter()
            .fold(pixels.saturating_mul(frame), |sum, a| sum.saturating_add(a.bytes(pixels, fragments)))
    }

    /// Bytes a pixel of the opaque pass's image: [`OPAQUE_BYTES`] a sample (the key and the
    /// colour of each sample's nearest opaque fragment, docs/msaa.md), where the scene has an
    /// opaque part; 0 elsewhere.
    pub fn opaque_bytes(&self) -> u64 {
        if self.opaque { OPAQUE_BYTES * u64::from(self.samples.max(1)) } else { 0 }
    }

    /// The elements a frame allocates its per-fragment arrays for, given the fragments it
    /// counted: on a [`Plan::pooled`] backend (the GPU backends) the count rounded up to its
    /// [`size_class`] (at most 1/8 more), which is what they allocate and report in
    /// `Stats::storage_bytes`; elsewhere the count itself. A prepared scene's frame that sized
    /// its arrays from an earlier frame's count without waiting (the GPU backends' speculation)
    /// allocates, and reports, that earlier count's capacity where its own fits it.
    pub fn fragment_capacity(&self, fragments: u64) -> u64 {
        match u32::try_from(fragments) {
            Ok(n) if self.pooled => u64::from(size_class(n)),
            _ => fragments,
        }
    }

    /// Bytes of the outputs a frame of `pixels` pixels holds beside its storage
    /// ([`OUTPUT_BYTES`] a pixel, and [`LAYERS_BYTES`] more for the reference's counts).
    pub fn output_bytes(&self, pixels: u64) -> u64 {
        pixels.saturating_mul(OUTPUT_BYTES + self.layers_bytes())
    }

    /// Bytes of what a frame run in screen tiles keeps of the whole frame while its tiles run,
    /// whatever their size: the stitched image (4 a pixel), per-pixel losses (4) and, for the
    /// reference, per-pixel counts ([`LAYERS_BYTES`]). [`crate::tiling::run`] sizes tiles by what
    /// `--memory` leaves beside it.
    pub fn stitched_bytes(&self, pixels: u64) -> u64 {
        pixels.saturating_mul(8 + self.layers_bytes())
    }

    fn layers_bytes(&self) -> u64 {
        if self.technique == Technique::Reference { LAYERS_BYTES } else { 0 }
    }

    /// Bytes a frame of this plan holds over `pixels` pixels, given what its counting pass found:
    /// its storage ([`Plan::storage_bytes`]) and its outputs ([`Plan::output_bytes`]). What every
    /// backend checks against its memory budget ([`Plan::check_budget`]) before it allocates, and
    /// what [`crate::tiling::run`] sizes tiles by.
    pub fn frame_bytes(&self, pixels: u64, counted: Counted) -> u64 {
        self.storage_bytes(pixels, counted).saturating_add(self.output_bytes(pixels))
    }

    /// The frame's geometry passes, in order, for a scene whose deepest pixel holds `layers`
    /// distinct depths (its fragment count where no two are equal) and, for `adp`, whose fullest
    /// histogram holds `bins` occupied bins: the schedule every backend runs, written once. Peels
    /// stop when a pass finds nothing left (that empty pass is run: it is how a peel learns it is
    /// done) or at the peel limit; `mlp` stops when a pass kept everything it met; `fabs:K` adds
    /// two passes when a pixel holds more than K.
    /// `tests/tests/plan.rs` holds every backend's `Stats::geometry_passes` to the total.
    pub fn schedule(&self, layers: u32, bins: u32) -> Vec<(PassKind, u32)> {
        let peels = |n: u32| n.min(self.peel_limit);
        let mut passes = Vec::new();
        if self.opaque {
            passes.push((PassKind::Opaque, 2));
        }
        if self.bounds_pass {
            passes.push((PassKind::Bounds, 1));
        }
        if self.needs_count() || self.technique == Technique::Reference {
            passes.push((PassKind::Count, 1));
        }
        match self.technique {
            Technique::Reference | Technique::Dfb | Technique::Ll => passes.push((PassKind::Fill, 1)),
            // per sample: every peel, then one pass that fetches the last peeled layer's
            // payload and mask (the pass that finds nothing where the peels ran out first)
            Technique::Dp if self.sample_peel => {
                passes.push((PassKind::Peel, peels(layers).saturating_add(1)))
            }
            Technique::Ddp if self.sample_peel => {
                passes.push((PassKind::Peel, peels(layers.div_ceil(2)).saturating_add(1)))
            }
            // per sample: M layers a pass, then the pass that fetches the last pass's M
            Technique::Mlp { m } if self.sample_peel => {
                passes.push((PassKind::Peel, peels(layers.div_ceil(m.max(1))).saturating_add(1)))
            }
            Technique::Dp => passes.push((PassKind::Peel, peels(layers.saturating_add(1)))),
            Technique::Ddp => passes.push((PassKind::Peel, peels(layers.div_ceil(2).saturating_add(1)))),
            Technique::Mlp { m } => passes.push((PassKind::Peel, peels(layers.div_ceil(m.max(1)).max(1)))),
            Technique::Bdp { .. } => passes.push((PassKind::Capture, self.bdp_capture_passes().max(1))),
            Technique::Adp => {
                passes.push((PassKind::Histogram, 1));
                passes.push((PassKind::Batch, self.adp_batches(bins)));
            }
            Technique::Plain | Technique::Mdts { .. } | Technique::Mdts64 { .. } | Technique::Kbuf { .. } => {
                passes.push((PassKind::Capture, 1))
            }
            Technique::Fabs { .. } => {
                passes.push((PassKind::Capture, 1));
                // a pixel past K keeps its K nearest by (depth, primitive id): two more passes,
                // its keys by atomic min, then their payloads (never when sized from a count)
                if matches!(self.sizing, Sizing::Fixed(k) if layers > k) {
                    passes.push((PassKind::Overflow, 2));
                }
            }
            // the order-free sums (`Technique::sums`): their passes (mboit's moments, then its
            // weighted colours)
            t => passes.push((PassKind::Capture, sums_of(t).passes)),
        }
        // the tail: one pass over the fragments behind each overflowing pixel's K-th nearest, run
        // where some pixel holds more than K
        if self.tail && matches!(self.sizing, Sizing::Fixed(k) if layers > k) {
            passes.push((PassKind::Tail, 1));
        }
        passes
    }

    /// Checks [`Plan::frame_bytes`] (storage and outputs) against `budget` (a name and bytes: the
    /// host's available memory, a device's): a clear error naming the size, the budget and what
    /// helps. Returns the bytes checked.
    pub fn check_budget(&self, pixels: u64, counted: Counted, budget: (&str, u64)) -> Result<u64, OitError> {
        let needed = self.frame_bytes(pixels, counted);
        check_total(
            &format!("{} storage and outputs of a frame of {pixels} pixels", self.technique),
            needed,
            budget,
        )?;
        Ok(needed)
    }

    /// The fragments of an exact allocation (`dfb`, `ll`) as the 32-bit index both backends give
    /// them (per-pixel offsets, node indices; `ll`'s end-of-list marker is `u32::MAX`), or a
    /// clear error naming the limit and what helps.
    pub fn check_fragments(&self, fragments: u64) -> Result<u32, OitError> {
        const LIMIT: u64 = u32::MAX as u64 - 1;
        let per_fragment = if self.technique == Technique::Ll { 16 } else { 12 };
        u32::try_from(fragments).ok().filter(|&n| u64::from(n) <= LIMIT).ok_or_else(|| OitError::TooLarge {
            what: format!("{} storage of {fragments} fragments", self.technique),
            needed: fragments.saturating_mul(per_fragment),
            limit_name: "32-bit fragment indices (2³² − 2 fragments)".into(),
            limit: LIMIT * per_fragment,
            hint: "use a smaller --size, or a fixed size per pixel (fabs:K)".into(),
        })
    }

    /// Why a frame of this plan must read back from the device in mid-frame (a count that sizes
    /// its storage, a peel that stops when a pass finds nothing, adp's histogram), which a frame
    /// recorded into a caller's command stream cannot do; `None` where it records in one go.
    pub fn mid_frame_readback(&self) -> Option<&'static str> {
        match self.technique {
            _ if self.needs_count() => {
                Some("its storage is sized by a counting pass read back in mid-frame; give K")
            }
            Technique::Dp | Technique::Ddp | Technique::Mlp { .. } => {
                Some("it stops peeling when a pass read back finds nothing left")
            }
            Technique::Adp => Some("its batches are chosen from a histogram read back in mid-frame"),
            Technique::Reference | Technique::Dfb | Technique::Ll => {
                Some("it sizes its storage from counts read back in mid-frame")
            }
            _ => None,
        }
    }

    /// True when the technique needs the counting pass before it can size its arrays.
    pub fn needs_count(&self) -> bool {
        matches!(self.sizing, Sizing::FromCount | Sizing::Exact)
    }

    /// The stop rule of peeling and batching: after `done` peels (or capture passes, or adp
    /// batches), may another run? Peeling also stops when a pass finds nothing (the occlusion
    /// query, or a per-pixel flag), which the backend observes.
    pub fn may_peel(&self, done: u32) -> bool {
        done < self.peel_limit
    }

    /// Capture passes `bdp:P` runs: P, or fewer under `--max-peels` (at least one).
    pub fn bdp_capture_passes(&self) -> u32 {
        match self.technique {
            Technique::Bdp { passes } => passes.min(self.peel_limit.max(1)),
            _ => 0,
        }
    }

    /// adp batches for a pixel set whose histograms hold at most `bins` occupied bins.
    pub fn adp_batches(&self, bins: u32) -> u32 {
        bins.div_ceil(crate::rules::BUCKETS as u32).min(self.peel_limit)
    }
}

/// The refusal of a hardware path's own capture of `settings.technique` (plain's blender, the
/// blend captures) at several samples a pixel where it is not done (`Ok` at one, and for those
/// that are; docs/msaa.md, "The blend captures at several samples"). `wavg`, `wsum` and `bdp`
/// blend into multisampled targets, each fragment at one of its samples, combined by the blend's
/// own operator; `plain` blends each sample (per-sample coverage), over opaque objects too (each
/// sample's composite over that sample's opaque colour). Refused: `plain` under `--coverage
/// pixel` or `--coverage fraction`, which its blender cannot give: both composite every fragment
/// over the whole pixel in submission order (at full alpha, or at alpha times the fraction of the
/// samples it keeps), so every fragment must reach one common accumulation, while a fragment of a
/// multisampled pass writes only samples it covers (its output sample mask narrows its coverage,
/// never widens it) and two fragments that share no sample never meet in the blender; and `dp`'s
/// and `ddp`'s blend captures (`--hardware-capture blend`), which peel each sample (a depth or a
/// range target a sample), under the coverages that peel the pixel (`--coverage pixel`,
/// `--coverage fraction`, translucency: [`crate::msaa::peels_per_sample`]) and under `--max-peels`
/// (each sample peels its own layers, so the limit cuts a fragment off at one sample while
/// another peeled it, and the count, made once a fragment at its lowest sample, calls it captured
/// where it is missing). Each GPU backend asks where it would run one, before the capture's
/// passes.
pub fn refuse_multisampled_own_capture(backend: &str, settings: &Settings) -> Result<(), OitError> {
    let samples = settings.samples;
    if samples <= 1 {
        return Ok(());
    }
    let technique = settings.technique;
    let what = match technique {
        Technique::Dp | Technique::Ddp if !crate::msaa::peels_per_sample(settings) => format!(
            "{technique} with --hardware-capture blend at --samples {samples} under --coverage pixel, \
             --coverage fraction or translucency: its blend capture peels each sample; use \
             --hardware-capture atomics or --raster compute (docs/msaa.md)"
        ),
        Technique::Dp | Technique::Ddp if settings.max_peels.is_some() => format!(
            "{technique} with --hardware-capture blend at --samples {samples} under --max-peels: its blend \
             capture peels each sample, so the limit cuts a fragment off at one sample while another \
             peeled it, which its count (a fragment once) cannot see; use --hardware-capture atomics, \
             which counts what the limit cuts at each sample (docs/msaa.md)"
        ),
        Technique::Plain if settings.pixel_coverage || settings.fraction_coverage => format!(
            "plain on the hardware path at --samples {samples} with --coverage {}: its blender composites \
             each sample (--coverage sample), and a fragment writes only the samples it covers, so it \
             cannot weigh a fragment by its pixel's coverage; drop --coverage for the blender's per-sample \
             composite, or use --raster compute for this coverage (docs/msaa.md)",
            if settings.pixel_coverage { "pixel" } else { "fraction" }
        ),
        _ => return Ok(()),
    };
    Err(OitError::Unsupported { backend: backend.into(), what })
}

/// Checks `needed` bytes of a frame's storage (`what`) against `budget`; see [`Plan::check_budget`].
pub fn check_total(what: &str, needed: u64, budget: (&str, u64)) -> Result<(), OitError> {
    let (limit_name, limit) = budget;
    if needed > limit {
        return Err(OitError::TooLarge {
            what: what.into(),
            needed,
            limit_name: limit_name.into(),
            limit,
            hint: format!(
                "use fewer passes (bdp:P), fewer slots (fabs:K, mdts:K, mlp:M) or a smaller --size; {:.1}% of this would fit",
                100.0 * limit as f64 / needed as f64
            ),
        });
    }
    Ok(())
}

/// How long [`host_memory_budget`] keeps a reading of `/proc/meminfo`.
pub const MEMINFO_TTL: std::time::Duration = std::time::Duration::from_millis(100);

/// The memory budget of a frame's technique storage on this host: half of `MemAvailable` of
/// `/proc/meminfo`, else a fixed 4 GiB where the host does not say (not Linux). Half, because the
/// storage is not all a frame holds: the set-up triangles, the image and its per-pixel outputs
/// (layers, losses) and the allocator's slack come on top (an 8192² `fabs` frame of the armadillo
/// whose storage was just under all of `MemAvailable` was killed by the kernel at 24 GB).
///
/// Read at most every [`MEMINFO_TTL`]: a read of `/proc/meminfo` costs about 16 µs of a core on
/// this project's 2-core VM, and a frame asks several times (its plan's check, its context, each
/// array its pool makes), which a 64² frame of a few hundred microseconds felt.
pub fn host_memory_budget() -> (&'static str, u64) {
    static LAST: std::sync::Mutex<Option<(std::time::Instant, Option<u64>)>> = std::sync::Mutex::new(None);
    let now = std::time::Instant::now();
    let cached =
        LAST.lock().ok().and_then(|last| last.filter(|(at, _)| now.duration_since(*at) < MEMINFO_TTL));
    let available = match cached {
        Some((_, available)) => available,
        None => {
            let available = std::fs::read_to_string("/proc/meminfo").ok().and_then(|text| {
                let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
                let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
                Some(kib.saturating_mul(1024))
            });
            if let Ok(mut last) = LAST.lock() {
                *last = Some((now, available));
            }
            available
        }
    };
    match available {
        Some(bytes) => ("half the host's available memory (MemAvailable / 2)", bytes / 2),
        None => ("oit's fixed memory budget (the host does not report its available memory)", 4 << 30),
    }
}

/// The capacity allocated for `n` elements counted by an earlier frame: `n` rounded up to a
/// multiple of an eighth of its power of two (at most 1/8 more; 8 classes an octave), so counts
/// that differ a little from frame to frame take the same buffers from the pool.
pub fn size_class(n: u32) -> u32 {
    if n <= 8 {
        return n;
    }
    let step = 1u32 << (31 - n.leading_zeros() - 3);
    n.div_ceil(step).saturating_mul(step)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::load_scene;

    /// The per-sample peels' key holds a primitive id in 29 bits (`msaa::peel_key`): a scene of
    /// 2²⁹ triangles (ids up to 2²⁹ − 1) is planned, one of 2²⁹ + 2²¹ is refused by name there,
    /// and one sample or a technique that keeps no such key takes it. (One mesh of 2²¹ triangles,
    /// instanced.) Mutations caught: the limit tested with `>=` (the scene of exactly 2²⁹
    /// refused), the check left out.
    #[test]
    fn per_sample_peels_refuse_ids_past_their_key() {
        let mut scene = load_scene("planes:1").unwrap();
        let tris = 1usize << 21;
        let object = scene.instances[0].object;
        let mesh = scene.objects[object].mesh;
        scene.meshes[mesh].indices = vec![[0, 1, 2]; tris];
        let one = scene.instances[0].clone();
        let at = |scene: &Scene, t: &str, samples: u32| {
            let s = Settings { technique: t.parse().unwrap(), samples, ..Settings::default() };
            Plan::new("test", scene, &s)
        };
        let limit = crate::msaa::PEEL_KEY_PRIMITIVES as usize;
        scene.instances = vec![one.clone(); limit / tris];
        assert_eq!(scene.primitive_bases().1 as usize, limit);
        for t in ["dp", "ddp", "mlp:2"] {
            assert!(at(&scene, t, 4).unwrap().sample_peel, "{t}");
        }
        scene.instances = vec![one; limit / tris + 1];
        for t in ["dp", "ddp", "mlp:2"] {
            match at(&scene, t, 4) {
                Err(OitError::Unsupported { what, .. }) => {
                    assert!(what.contains("29 bits") && what.contains("--coverage fraction"), "{t}: {what}")
                }
                other => panic!("{t}: {:?}", other.map(|p| p.sample_peel)),
            }
            assert!(at(&scene, t, 1).is_ok(), "{t} at one sample");
        }
        assert!(at(&scene, "ll", 4).is_ok());
    }

    fn plan(technique: &str, f: impl FnOnce(&mut Settings)) -> Result<Plan, OitError> {
        let mut s = Settings { technique: technique.parse().unwrap(), ..Settings::default() };
        f(&mut s);
        Plan::new("test", &load_scene("planes:4").unwrap(), &s)
    }

    /// Every technique, the reference and kbuf included, has arrays and a schedule: the order-free
    /// sums through their one entry (`Technique::sums`: its array and passes), every other through
    /// its own arm (a technique in neither panics in `sums_of`). Fails when a sums technique's
    /// array or pass count stops being the entry's.
    #[test]
    fn every_technique_has_a_plan() {
        let mut all = Technique::all();
        all.extend([Technique::Reference, Technique::Kbuf { k: Some(4) }, Technique::Mboit { m: 6 }]);
        for t in all {
            let p = plan(&t.to_string(), |_| {}).unwrap_or_else(|e| panic!("{t}: {e}"));
            let arrays = p.arrays(Counted { deepest: 4, fragments: 100 });
            let schedule = p.schedule(4, 4);
            assert!(!arrays.is_empty() && !schedule.is_empty(), "{t}");
            if let Some(sums) = t.sums() {
                assert_eq!(arrays.len(), 1, "{t}: one array of sums");
                assert_eq!(
                    (arrays[0].name, arrays[0].element_bytes, arrays[0].per_pixel),
                    (sums.array, 8, sums.words)
                );
                assert_eq!(schedule, [(PassKind::Capture, sums.passes)], "{t}");
            }
        }
    }

    #[test]
    fn refusals_are_the_same_for_every_backend() {
        assert!(plan("mdts", |s| s.effect = Effect::Fresnel).is_err());
        assert!(plan("mdts64", |s| s.effect = Effect::Fresnel).is_ok());
        assert!(plan("plain", |s| s.effect = Effect::Translucency).is_err());
        assert!(plan("plain", |s| s.effect = Effect::Complexity).is_ok());
        assert!(plan("bdp2", |s| s.bdp_mode = crate::BdpMode::Color).is_err());
        assert!(plan("bdp", |s| s.bdp_mode = crate::BdpMode::Color).unwrap().bdp_color);
        assert!(!plan("bdp", |s| s.effect = Effect::Fresnel).unwrap().bdp_color);
    }

    #[test]
    fn image_atomics_apply_to_the_atomic_arrays_only() {
        let image = |s: &mut Settings| s.atomic_storage = crate::AtomicStorage::Image;
        for t in ["mdts", "mdts:4", "mdts64:2", "fabs", "fabs:8"] {
            let p = plan(t, image).unwrap();
            assert!(p.image_atomics, "{t}");
            let err = p.refuse_image_atomics("wgpu").unwrap_err().to_string();
            assert!(err.contains("wgpu") && err.contains("vulkan backend only"), "{t}: {err}");
            assert!(!plan(t, |_| {}).unwrap().image_atomics, "{t} on buffers");
        }
        // the reference a comparison renders beside them runs under the same settings
        for t in ["reference", "dp", "bdp", "dfb", "plain"] {
            let p = plan(t, image).unwrap();
            assert!(!p.image_atomics && p.refuse_image_atomics("cpu").is_ok(), "{t}");
        }
        assert_eq!("Image".parse::<crate::AtomicStorage>().unwrap(), crate::AtomicStorage::Image);
        assert_eq!(" buffer".parse::<crate::AtomicStorage>().unwrap(), crate::AtomicStorage::Buffer);
        assert!("texture".parse::<crate::AtomicStorage>().is_err());
    }

    /// `kbuf`: fabs's K and its storage without the counter, one capture pass, refused where there
    /// is no interlock (by every backend's call of the one rule) and with a tail.
    #[test]
    fn kbuf_plan() {
        let counted = Counted { deepest: 9, fragments: 25 };
        let fixed = plan("kbuf:4", |_| {}).unwrap();
        assert!(fixed.needs_interlock() && !fixed.count_ties && !fixed.needs_count());
        assert_eq!(fixed.sizing, Sizing::Fixed(4));
        assert_eq!(fixed.storage_bytes(10, counted), 10 * (48 + 92));
        assert_eq!(fixed.schedule(7, 7), vec![(PassKind::Capture, 1)]);
        let sized = plan("kbuf", |_| {}).unwrap();
        assert_eq!(sized.schedule(7, 7), vec![(PassKind::Count, 1), (PassKind::Capture, 1)]);
        assert_eq!(sized.storage_bytes(10, counted), 10 * (9 * 12 + 92));
        let e = fixed.refuse_interlock("cpu", "the CPU has no fragment stage").unwrap_err().to_string();
        assert!(
            e.contains("cpu") && e.contains("VK_EXT_fragment_shader_interlock") && e.contains("fabs:K"),
            "{e}"
        );
        assert!(plan("fabs:4", |_| {}).unwrap().refuse_interlock("cpu", "none").is_ok());
        let e = plan("kbuf:4", |s| s.overflow = crate::Overflow::Tail).unwrap_err().to_string();
        assert!(e.contains("--overflow tail"), "{e}");
        // without K nothing overflows: the setting is ignored, as for fabs
        assert!(!plan("kbuf", |s| s.overflow = crate::Overflow::Tail).unwrap().tail);
    }

    #[test]
    fn stop_rules() {
        let p = plan("bdp:5", |s| s.max_peels = Some(2)).unwrap();
        assert_eq!(p.bdp_capture_passes(), 2);
        assert!(p.may_peel(1) && !p.may_peel(2));
        assert_eq!(plan("bdp:5", |s| s.max_peels = Some(0)).unwrap().bdp_capture_passes(), 1);
        assert_eq!(plan("bdp:3", |_| {}).unwrap().bdp_capture_passes(), 3);
        assert!(plan("dp", |_| {}).unwrap().may_peel(u32::MAX - 1));
        let adp = plan("adp", |s| s.max_peels = Some(2)).unwrap();
        assert_eq!((adp.adp_batches(0), adp.adp_batches(33), adp.adp_batches(1000)), (0, 2, 2));
        assert_eq!(plan("adp", |_| {}).unwrap().adp_batches(65), 3);
    }

    /// Issue 13.9: storage over the budget is refused before anything is allocated.
    #[test]
    fn storage_budget() {
        let p = plan("bdp:1000", |_| {}).unwrap();
        let px = 512 * 512;
        let one = Counted { deepest: 1, fragments: px };
        assert!(p.storage_bytes(px, one) > 60 << 30);
        let e = p.check_budget(px, one, ("test budget", 24 << 30)).unwrap_err().to_string();
        assert!(e.contains("test budget") && e.contains("smaller --size"), "{e}");
        assert!(plan("bdp", |_| {}).unwrap().check_budget(px, one, ("test budget", 1 << 30)).is_ok());
        let fabs = plan("fabs:4", |_| {}).unwrap();
        let counted = Counted { deepest: 9, fragments: 25 };
        assert_eq!(fabs.storage_bytes(10, counted), 10 * (4 + 48 + 92));
        assert_eq!(plan("fabs", |_| {}).unwrap().storage_bytes(10, counted), 10 * (4 + 9 * 12 + 92));
        // exact allocation: per pixel, then per fragment, whatever the deepest pixel
        assert_eq!(plan("dfb", |_| {}).unwrap().storage_bytes(10, counted), 10 * (8 + 92) + 8 + 25 * 12);
        assert_eq!(plan("ll", |_| {}).unwrap().storage_bytes(10, counted), 10 * (4 + 92) + 4 + 25 * 16);
        assert_eq!(plan("dfb", |_| {}).unwrap().storage_bytes(10, Counted::default()), 10 * 100 + 8);
        assert_eq!(plan("ll", |_| {}).unwrap().check_fragments(7).unwrap(), 7);
        let e = plan("ll", |_| {}).unwrap().check_fragments(1 << 32).unwrap_err().to_string();
        assert!(e.contains("32-bit fragment indices") && e.contains("fabs:K"), "{e}");
        assert!(host_memory_budget().1 > 0);
    }

    /// `--overflow tail`: 5 sums of 8 bytes a pixel and one pass more where a pixel holds more than
    /// K, for the fixed-size techniques only; other effects refused; ignored elsewhere.
    #[test]
    fn overflow_tail() {
        let tail = |t: &str| plan(t, |s| s.overflow = crate::Overflow::Tail);
        let counted = Counted { deepest: 9, fragments: 25 };
        for t in ["fabs:4", "mdts:4", "mdts64:4"] {
            let (with, without) = (tail(t).unwrap(), plan(t, |_| {}).unwrap());
            assert!(with.tail && !without.tail, "{t}");
            assert_eq!(with.storage_bytes(10, counted), without.storage_bytes(10, counted) + 10 * 40, "{t}");
            assert_eq!(with.schedule(5, 5).last(), Some(&(PassKind::Tail, 1)), "{t}");
            assert!(!with.schedule(4, 4).iter().any(|(p, _)| *p == PassKind::Tail), "{t}");
            let e = plan(t, |s| {
                s.overflow = crate::Overflow::Tail;
                s.effect = Effect::Translucency;
            });
            assert!(matches!(e, Err(OitError::Unsupported { .. })), "{t}");
        }
        for t in ["fabs", "mdts64", "dp", "reference"] {
            assert!(!tail(t).unwrap().tail, "{t}: no K to overflow");
        }
        assert_eq!("TAIL".parse::<crate::Overflow>().unwrap(), crate::Overflow::Tail);
        assert!("merge".parse::<crate::Overflow>().is_err());
    }

    /// dp and ddp above one sample peel per sample (docs/msaa.md): one pass past their peels,
    /// 16 bytes a sample a half of accumulators; `--coverage fraction` and one sample keep the
    /// single-sample schedule and arrays. Mutation caught: the per-sample schedule without its
    /// fetching pass (the first assertion gives 5).
    #[test]
    fn peels_per_sample_plan() {
        let four = |t: &str, f: fn(&mut Settings)| {
            plan(t, |s| {
                s.samples = 4;
                f(s)
            })
            .unwrap()
        };
        let total = |p: &Plan, layers: u32| p.schedule(layers, layers).iter().map(|(_, n)| n).sum::<u32>();
        let dp = four("dp", |_| {});
        assert!(dp.sample_peel);
        assert_eq!(total(&dp, 5), 6);
        assert_eq!(total(&four("dp", |s| s.max_peels = Some(2)), 5), 3);
        assert_eq!(total(&four("ddp", |_| {}), 5), 4);
        assert_eq!(total(&four("ddp", |s| s.max_peels = Some(2)), 9), 3);
        let accumulators = |p: &Plan| {
            p.arrays(Counted::default())
                .iter()
                .find(|a| a.name.starts_with("sample accumulators"))
                .map(|a| a.element_bytes * a.per_pixel)
        };
        assert_eq!(accumulators(&dp), Some(64));
        assert_eq!(accumulators(&four("ddp", |_| {})), Some(128));
        for p in [four("dp", |s| s.fraction_coverage = true), plan("dp", |_| {}).unwrap()] {
            assert!(!p.sample_peel);
            assert_eq!(accumulators(&p), None);
            assert_eq!(total(&p, 5), 6);
            assert_eq!(total(&Plan { peel_limit: 2, ..p }, 5), 2);
        }
        assert!(!four("dp", |s| s.effect = Effect::Translucency).sample_peel);
    }

    /// `mlp:M` above one sample peels per sample (docs/msaa.md): ⌈layers / M⌉ passes and the one
    /// that fetches the last pass's layers; per pixel the M slots, the M keys the pass before
    /// kept, their M payloads and masks (8 bytes each) and 16 bytes a sample. `--coverage
    /// fraction` and one sample keep the single-sample schedule and arrays (8 bytes a slot and
    /// a count). Mutations caught: the per-sample schedule without its fetching pass (the first
    /// assertion gives 3), the previous pass's keys left out of the arrays (96 bytes, not 112).
    #[test]
    fn mlp_per_sample_plan() {
        let at = |t: &str, samples: u32, f: fn(&mut Settings)| {
            plan(t, |s| {
                s.samples = samples;
                f(s)
            })
            .unwrap()
        };
        let total = |p: &Plan, layers: u32| p.schedule(layers, layers).iter().map(|(_, n)| n).sum::<u32>();
        let per_pixel = |p: &Plan| {
            p.arrays(Counted::default()).iter().map(|a| a.element_bytes * a.per_pixel).sum::<u64>()
        };
        let mlp2 = at("mlp:2", 4, |_| {});
        assert!(mlp2.sample_peel);
        assert_eq!(total(&mlp2, 5), 4);
        assert_eq!(total(&mlp2, 4), 3);
        assert_eq!(total(&mlp2, 0), 1);
        assert_eq!(total(&at("mlp:2", 4, |s| s.max_peels = Some(2)), 9), 3);
        assert_eq!(total(&at("mlp:1", 8, |_| {}), 5), 6);
        // 3 × 8 bytes a slot, 16 a sample
        assert_eq!(per_pixel(&mlp2), 3 * 8 * 2 + 16 * 4);
        assert_eq!(per_pixel(&at("mlp:4", 8, |_| {})), 3 * 8 * 4 + 16 * 8);
        for p in [at("mlp:2", 4, |s| s.fraction_coverage = true), at("mlp:2", 1, |_| {})] {
            assert!(!p.sample_peel);
            assert_eq!(per_pixel(&p), 8 * 2 + 4);
            assert_eq!(total(&p, 5), 3);
            assert_eq!(total(&p, 0), 1);
        }
        assert!(!at("mlp:2", 4, |s| s.pixel_coverage = true).sample_peel);
        assert!(!at("mlp:2", 4, |s| s.effect = Effect::Translucency).sample_peel);
    }

    #[test]
    fn sizing_and_alpha() {
        assert_eq!(plan("fabs", |_| {}).unwrap().slots(0), 1);
        assert_eq!(plan("fabs", |_| {}).unwrap().slots(7), 7);
        assert_eq!(plan("fabs:3", |_| {}).unwrap().slots(7), 3);
        assert!(plan("mdts", |_| {}).unwrap().needs_count());
        assert!(plan("dfb", |_| {}).unwrap().needs_count() && plan("ll", |_| {}).unwrap().needs_count());
        assert!(!plan("fabs:3", |_| {}).unwrap().needs_count());
        assert!(!plan("dfb", |_| {}).unwrap().count_ties && !plan("ll", |_| {}).unwrap().count_ties);
        assert_eq!(plan("mdts", |s| s.alpha = Some(1.0)).unwrap().mdts_alpha8, 255);
        assert_eq!(plan("mdts", |s| s.alpha = Some(0.5)).unwrap().mdts_alpha8, 128);
        assert_eq!(plan("mdts", |s| s.alpha = Some(-3.0)).unwrap().mdts_alpha8, 0);
    }

    #[test]
    fn size_classes_hold_the_count_within_an_eighth() {
        for n in (0..5000).chain([u32::MAX / 2, u32::MAX / 2 + 1, 1 << 31]) {
            let c = size_class(n);
            assert!(c >= n && u64::from(c) * 8 <= u64::from(n) * 9, "{n} -> {c}");
        }
        assert_eq!(size_class(1000), 1024);
        assert_eq!(size_class(1025), 1152);
        // neighbours share a class
        assert_eq!(size_class(1_000_001), size_class(1_020_000));
    }

    /// mboit refuses a scene with more triangles than its moment sums hold fragments a pixel (one
    /// over the limit), and renders one at the limit. Fails when the check is dropped or moved by
    /// one.
    #[test]
    fn mboit_refuses_scenes_its_sums_cannot_hold() {
        let s = Settings { technique: "mboit".parse().unwrap(), ..Settings::default() };
        let scene = |n: u64| {
            let mesh = crate::Mesh::new(
                "many",
                vec![glam::Vec3::ZERO, glam::Vec3::X, glam::Vec3::Y],
                vec![[0, 1, 2]; n as usize],
            );
            crate::Scene::from_meshes("many", vec![mesh], glam::Vec4::ONE)
        };
        let e = Plan::new("test", &scene(crate::technique::mboit::MBOIT_MAX_TRIANGLES + 1), &s)
            .unwrap_err()
            .to_string();
        assert!(e.contains("per-pixel sums hold 4194304") && e.contains("4194305 triangles"), "{e}");
        assert!(Plan::new("test", &scene(crate::technique::mboit::MBOIT_MAX_TRIANGLES), &s).is_ok());
    }
}
