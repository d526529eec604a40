//! The technique catalogue: every way oit captures and orders the fragments of a pixel, by the
//! names the papers and the project's design give them, parameters included (`bdp:3`, `fabs:16`, `mlp:4`).

use std::fmt;
use std::str::FromStr;

use serde::Serialize;

use crate::OitError;

pub mod mboit;
pub mod wboit;

/// A technique and its parameters.
///
/// Parameters left out (`fabs`, `mdts`, `mdts64`) are sized from the scene: a counting pass
/// measures the deepest pixel and the arrays get exactly that many slots. `dfb` and `ll` take no
/// parameter: a counting pass sizes their storage to exactly the frame's fragments.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Technique {
    /// Every fragment, sorted by (depth, primitive id), composited in f64: the ground truth.
    Reference,
    /// Plain alpha blending, unsorted: each fragment blended over what the pixel holds in
    /// submission order, as a GPU's blender composites one draw, with no attempt at depth order.
    /// What a renderer without OIT shows; the speed baseline of every other technique. Submission
    /// order is primitive order (the order a blender guarantees within one draw): a pixel's
    /// fragments are composited by ascending primitive id, the highest on top, on every backend
    /// and path, so backends agree. An approximation: equal to the reference only where a pixel's
    /// fragments in primitive order are farthest first.
    Plain,
    /// Classical depth peeling (Everitt 2001): one layer per geometry pass.
    Dp,
    /// Dual depth peeling (Bavoil & Myers 2008): the nearest and farthest layer per pass.
    Ddp,
    /// Weighted average (Bavoil & Myers 2008): one pass, order ignored.
    WeightedAverage,
    /// Weighted sum (Meshkin 2007, as reported by Bavoil & Myers 2008): one pass, order ignored.
    WeightedSum,
    /// Weighted blended OIT (McGuire & Bavoil, JCGT 2013): one pass, order ignored; each
    /// fragment's premultiplied colour weighted by a function of its depth and alpha (the paper's
    /// eq. 10, nearer counts more), the coverage exact (the product of the fragments' 1 − α).
    Wboit,
    /// Moment-based OIT (Münstermann et al., HPG 2018): a first pass sums each pixel's optical
    /// depth and `m` power moments of its warped depths weighted by it, a second pass weighs each
    /// fragment by the transmittance in front of it that those moments bound; order ignored.
    Mboit {
        /// Power moments a pixel: 4 or 6.
        m: u32,
    },
    /// Bucket depth peeling (Liu et al., HPG 2009) with `passes` capture passes (`bdp` = 1).
    Bdp {
        /// Capture passes (≥ 1).
        passes: u32,
    },
    /// Adaptive bucket depth peeling (Liu et al., HPG 2009, section 3.3).
    Adp,
    /// Multi-depth test with atomicMin on 32-bit words, colour in the 20+12-bit packing
    /// (Liu et al. 2009; Huang et al. 2011).
    Mdts {
        /// Words per pixel; `None` sizes them from the scene.
        k: Option<u32>,
    },
    /// The same with 64-bit words (depth bits above packed RGBA): exact for the first K layers.
    Mdts64 {
        /// Words per pixel; `None` sizes them from the scene.
        k: Option<u32>,
    },
    /// Fixed A-buffer: atomic counter + K slots per pixel, sorted after capture (Huang et al. 2011).
    Fabs {
        /// Slots per pixel; `None` sizes them from the scene.
        k: Option<u32>,
    },
    /// Extended multi-layer peeling: the M nearest remaining layers per pass (Huang et al. 2011).
    Mlp {
        /// Layers per pass (≥ 1).
        m: u32,
    },
    /// Dynamic fragment buffer (Maule et al. 2012): a counting pass, a prefix sum of the counts
    /// into per-pixel offsets, a fill pass into exactly the fragments' storage, a per-pixel sort.
    Dfb,
    /// Per-pixel linked lists (Yang et al. 2010): a head per pixel and a node pool sized from a
    /// counting pass, filled by atomic counter and exchange; each list sorted at resolve.
    Ll,
    /// The ordered k-buffer: K (depth, primitive id) slots per pixel kept sorted by a plain
    /// read-modify-write inside the fragment shader's ordered critical section
    /// (`VK_EXT_fragment_shader_interlock`). The k-buffer of Bavoil et al. 2007 without its
    /// read-modify-write hazards, which the HPG 2009 bucket paper compared against; it keeps a
    /// pixel's K nearest fragments, as `fabs:K` does, and counts the rest as lost. Runs only where
    /// the fragment stage has an ordered interlock (oit-vulkan's hardware path on such a device).
    Kbuf {
        /// Slots per pixel; `None` sizes them from the scene.
        k: Option<u32>,
    },
}

/// The kind of a technique, parameters dropped: what a backend's capabilities list.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
#[expect(missing_docs, reason = "the variants are the techniques' names")]
pub enum TechniqueKind {
    Reference,
    Plain,
    Dp,
    Ddp,
    Wavg,
    Wsum,
    Wboit,
    Mboit,
    Bdp,
    Adp,
    Mdts,
    Mdts64,
    Fabs,
    Mlp,
    Dfb,
    Ll,
    Kbuf,
}

impl TechniqueKind {
    /// Every kind, in catalogue order.
    pub const ALL: [TechniqueKind; 17] = [
        TechniqueKind::Reference,
        TechniqueKind::Plain,
        TechniqueKind::Dp,
        TechniqueKind::Ddp,
        TechniqueKind::Wavg,
        TechniqueKind::Wsum,
        TechniqueKind::Wboit,
        TechniqueKind::Mboit,
        TechniqueKind::Bdp,
        TechniqueKind::Adp,
        TechniqueKind::Mdts,
        TechniqueKind::Mdts64,
        TechniqueKind::Fabs,
        TechniqueKind::Mlp,
        TechniqueKind::Dfb,
        TechniqueKind::Ll,
        TechniqueKind::Kbuf,
    ];

    /// Whether the technique runs inside an ordered fragment-stage interlock
    /// (`VK_EXT_fragment_shader_interlock`): `kbuf`. A backend or device without one leaves it out
    /// of its capabilities and refuses it ([`crate::plan::Plan::refuse_interlock`]).
    pub fn needs_interlock(self) -> bool {
        self == TechniqueKind::Kbuf
    }
}

/// An order-free sum technique's frame ([`Technique::sums`]): one per-pixel array of `words` u64
/// sums, zeroed; `passes` geometry passes of `module`'s `capture` (pass index 0, 1, ...), each over
/// every fragment the frame keeps, adding into the sums with integer atomics, so that no sum
/// depends on the order fragments arrive in; then `module`'s `composite_main`, a pixel an
/// invocation, composites each pixel's sums over what lies behind it. Such a technique never
/// orders fragments: it is refused with the effects that need an order (translucency, Fresnel),
/// and it is exact only at a pixel of one fragment. oit-cpu runs the same sums in its capture
/// (`technique/<name>.rs`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sums {
    /// The array's name in [`Plan::arrays`](crate::plan::Plan::arrays).
    pub array: &'static str,
    /// u64 words a pixel.
    pub words: u64,
    /// Geometry passes a frame.
    pub passes: u32,
    /// The WGSL module of oit-shaders the passes and the composite run.
    pub module: &'static str,
    /// What the passes and the composite get as their parameter (`fu.param`).
    pub param: u32,
    /// The most triangles a scene may have for the sums not to wrap (a pixel takes at most a
    /// fragment a triangle); a larger scene is refused. `None`: any scene oit loads.
    pub max_triangles: Option<u64>,
}

/// The names `parse` accepts, for messages.
pub const KNOWN_TECHNIQUES: &str = "reference, plain, dp, ddp, wavg, wsum, wboit, mboit[:4|6], bdp, bdp:P, bdp2, adp, mdts[:K], mdts64[:K], fabs[:K], mlp:M, dfb, ll, kbuf[:K]";

/// Power moments `mboit` keeps a pixel unless told (`mboit:6` keeps six).
pub const MBOIT_MOMENTS: u32 = 4;

/// Largest K or M accepted (a pixel with this many layers is already far past any real scene).
pub const MAX_PARAMETER: u32 = 65_536;

impl Technique {
    /// The techniques `--techniques all` runs, reference excluded, in catalogue order. Not `kbuf`:
    /// it needs a fragment-stage interlock that most backends and devices lack, so it is asked for
    /// by name.
    pub fn all() -> Vec<Technique> {
        vec![
            Technique::Plain,
            Technique::Dp,
            Technique::Ddp,
            Technique::WeightedAverage,
            Technique::WeightedSum,
            Technique::Wboit,
            Technique::Mboit { m: 4 },
            Technique::Bdp { passes: 1 },
            Technique::Bdp { passes: 2 },
            Technique::Adp,
            Technique::Mdts { k: None },
            Technique::Mdts64 { k: None },
            Technique::Fabs { k: None },
            Technique::Mlp { m: 4 },
            Technique::Dfb,
            Technique::Ll,
        ]
    }

    /// Parses a comma-separated list; `all` expands to [`Technique::all`].
    pub fn parse_list(list: &str) -> Result<Vec<Technique>, OitError> {
        let mut out = Vec::new();
        for item in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            if item.eq_ignore_ascii_case("all") {
                out.extend(Technique::all());
            } else {
                out.push(item.parse()?);
            }
        }
        if out.is_empty() {
            return Err(OitError::UnknownTechnique {
                name: list.to_string(),
                reason: "the list is empty".into(),
                known: KNOWN_TECHNIQUES,
            });
        }
        Ok(out)
    }

    /// How the technique runs where it is an order-free sum ([`Sums`]): `wavg`, `wsum`, `wboit`
    /// and `mboit`; `None` for the others. What the plan allocates and schedules, the scenes it
    /// refuses, the error bound `--technique auto` gives it and both GPU backends' frame come from
    /// this one entry, so a technique of this family is registered here and nowhere else outside
    /// its own files (docs/architecture.md, "Adding a technique").
    pub fn sums(&self) -> Option<Sums> {
        let sums = |array, words, passes, module, param| Sums {
            array,
            words,
            passes,
            module,
            param,
            max_triangles: None,
        };
        match *self {
            // Σα·r, Σα·g, Σα·b, Σα and the count; param bit 0: average (1) or sum (0)
            Technique::WeightedAverage => Some(sums("weighted sums", 5, 1, "weighted", 1)),
            Technique::WeightedSum => Some(sums("weighted sums", 5, 1, "weighted", 0)),
            // Σ α·w·r, Σ α·w·g, Σ α·w·b, Σ α·w, Σ −ln(1 − α) and the count; no triangle limit:
            // α·w·c < 2³⁵ a fragment, so the u64 sums hold 2²⁹ fragments a pixel, above
            // `Scene::MAX_TRIANGLES`, which every scene is held to
            Technique::Wboit => Some(sums("weighted blended sums", 6, 1, "wboit", 0)),
            // the optical depth and m moments (first pass), Σ T·α·r, g, b, Σ T·α and the count
            // (second pass): m + 6 words; param: m
            Technique::Mboit { m } => Some(Sums {
                max_triangles: Some(mboit::MBOIT_MAX_TRIANGLES),
                ..sums("moments and transmittance-weighted sums", u64::from(m) + 6, 2, "mboit", m)
            }),
            _ => None,
        }
    }

    /// The kind, parameters dropped.
    pub fn kind(&self) -> TechniqueKind {
        match self {
            Technique::Reference => TechniqueKind::Reference,
            Technique::Plain => TechniqueKind::Plain,
            Technique::Dp => TechniqueKind::Dp,
            Technique::Ddp => TechniqueKind::Ddp,
            Technique::WeightedAverage => TechniqueKind::Wavg,
            Technique::WeightedSum => TechniqueKind::Wsum,
            Technique::Wboit => TechniqueKind::Wboit,
            Technique::Mboit { .. } => TechniqueKind::Mboit,
            Technique::Bdp { .. } => TechniqueKind::Bdp,
            Technique::Adp => TechniqueKind::Adp,
            Technique::Mdts { .. } => TechniqueKind::Mdts,
            Technique::Mdts64 { .. } => TechniqueKind::Mdts64,
            Technique::Fabs { .. } => TechniqueKind::Fabs,
            Technique::Mlp { .. } => TechniqueKind::Mlp,
            Technique::Dfb => TechniqueKind::Dfb,
            Technique::Ll => TechniqueKind::Ll,
            Technique::Kbuf { .. } => TechniqueKind::Kbuf,
        }
    }

    /// True for techniques that must equal the reference (up to coplanar ties and capacity).
    pub fn is_exact(&self) -> bool {
        matches!(
            self,
            Technique::Reference
                | Technique::Dp
                | Technique::Ddp
                | Technique::Mdts64 { .. }
                | Technique::Fabs { .. }
                | Technique::Mlp { .. }
                | Technique::Dfb
                | Technique::Ll
                | Technique::Kbuf { .. }
        )
    }
}

impl fmt::Display for Technique {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let opt = |f: &mut fmt::Formatter<'_>, name: &str, k: &Option<u32>| match k {
            Some(k) => write!(f, "{name}:{k}"),
            None => write!(f, "{name}"),
        };
        match self {
            Technique::Reference => write!(f, "reference"),
            Technique::Plain => write!(f, "plain"),
            Technique::Dp => write!(f, "dp"),
            Technique::Ddp => write!(f, "ddp"),
            Technique::WeightedAverage => write!(f, "wavg"),
            Technique::WeightedSum => write!(f, "wsum"),
            Technique::Wboit => write!(f, "wboit"),
            Technique::Mboit { m } => write!(f, "mboit:{m}"),
            Technique::Bdp { passes: 1 } => write!(f, "bdp"),
            Technique::Bdp { passes: 2 } => write!(f, "bdp2"),
            Technique::Bdp { passes } => write!(f, "bdp:{passes}"),
            Technique::Adp => write!(f, "adp"),
            Technique::Mdts { k } => opt(f, "mdts", k),
            Technique::Mdts64 { k } => opt(f, "mdts64", k),
            Technique::Fabs { k } => opt(f, "fabs", k),
            Technique::Mlp { m } => write!(f, "mlp:{m}"),
            Technique::Dfb => write!(f, "dfb"),
            Technique::Ll => write!(f, "ll"),
            Technique::Kbuf { k } => opt(f, "kbuf", k),
        }
    }
}

impl Serialize for Technique {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl FromStr for Technique {
    type Err = OitError;

    fn from_str(text: &str) -> Result<Technique, OitError> {
        let err = |reason: String| OitError::UnknownTechnique {
            name: text.to_string(),
            reason,
            known: KNOWN_TECHNIQUES,
        };
        let lower = text.trim().to_ascii_lowercase();
        let (name, param) = match lower.split_once(':') {
            Some((n, p)) => (n, Some(p)),
            None => (lower.as_str(), None),
        };
        let number = |p: &str| -> Result<u32, OitError> {
            match p.parse::<u32>() {
                Ok(v) if (1..=MAX_PARAMETER).contains(&v) => Ok(v),
                _ => Err(err(format!("parameter '{p}' must be a whole number from 1 to {MAX_PARAMETER}"))),
            }
        };
        let none = |t: Technique| match param {
            None => Ok(t),
            Some(_) => Err(err(format!("'{name}' takes no parameter"))),
        };
        match name {
            "reference" | "ref" => none(Technique::Reference),
            "plain" => none(Technique::Plain),
            "dp" => none(Technique::Dp),
            "ddp" => none(Technique::Ddp),
            "wavg" => none(Technique::WeightedAverage),
            "wsum" => none(Technique::WeightedSum),
            "wboit" => none(Technique::Wboit),
            "mboit" => match param.map(number).transpose()?.unwrap_or(MBOIT_MOMENTS) {
                m @ (4 | 6) => Ok(Technique::Mboit { m }),
                m => Err(err(format!("mboit takes 4 or 6 power moments (the paper's), not {m}"))),
            },
            "adp" => none(Technique::Adp),
            "bdp2" => none(Technique::Bdp { passes: 2 }),
            "bdp" => Ok(Technique::Bdp { passes: param.map(number).transpose()?.unwrap_or(1) }),
            "mdts" => Ok(Technique::Mdts { k: param.map(number).transpose()? }),
            "mdts64" => Ok(Technique::Mdts64 { k: param.map(number).transpose()? }),
            "fabs" => Ok(Technique::Fabs { k: param.map(number).transpose()? }),
            "mlp" => Ok(Technique::Mlp { m: param.map(number).transpose()?.unwrap_or(4) }),
            "dfb" => none(Technique::Dfb),
            "ll" => none(Technique::Ll),
            "kbuf" => Ok(Technique::Kbuf { k: param.map(number).transpose()? }),
            _ => Err(err("not in the catalogue".into())),
        }
    }
}

/// What is computed from each pixel's sorted fragments.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Effect {
    /// Alpha compositing in depth order.
    #[default]
    Transparency,
    /// Beer–Lambert absorption through the thickness between entry and exit layers.
    Translucency,
    /// Schlick Fresnel transmittance multiplied over the layers.
    Fresnel,
    /// A heat map of the fragments captured per pixel.
    Complexity,
}

impl FromStr for Effect {
    type Err = OitError;
    fn from_str(s: &str) -> Result<Effect, OitError> {
        match s.trim().to_ascii_lowercase().as_str() {
            "transparency" => Ok(Effect::Transparency),
            "translucency" => Ok(Effect::Translucency),
            "fresnel" => Ok(Effect::Fresnel),
            "complexity" => Ok(Effect::Complexity),
            other => Err(OitError::InvalidSettings(format!(
                "unknown effect '{other}': use transparency, translucency, fresnel or complexity"
            ))),
        }
    }
}

/// How the bucket techniques find each pixel's depth range.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BoundsMode {
    /// [`BoundsMode::Exact`] where the frame has an opaque part, else [`BoundsMode::Boxes`]
    /// ([`BoundsMode::resolve`]): the boxes' faces are not cut at the opaque depth, so behind an
    /// opaque surface their range runs on over what it hides (docs/opaque.md).
    #[default]
    Auto,
    /// The rendered depths of the instances' bounding boxes (the HPG 2009 paper's default).
    Boxes,
    /// The fragments' true min and max, from an extra geometry pass.
    Exact,
}

impl BoundsMode {
    /// The mode a frame runs: [`BoundsMode::Auto`] made [`BoundsMode::Exact`] where the frame has
    /// an opaque part (`opaque`), [`BoundsMode::Boxes`] elsewhere; the others as they are.
    ///
    /// ```
    /// use oit_core::BoundsMode;
    /// assert_eq!(BoundsMode::Auto.resolve(true), BoundsMode::Exact);
    /// assert_eq!(BoundsMode::Auto.resolve(false), BoundsMode::Boxes);
    /// assert_eq!(BoundsMode::Boxes.resolve(true), BoundsMode::Boxes);
    /// ```
    pub fn resolve(self, opaque: bool) -> BoundsMode {
        match self {
            BoundsMode::Auto if opaque => BoundsMode::Exact,
            BoundsMode::Auto => BoundsMode::Boxes,
            other => other,
        }
    }
}

impl FromStr for BoundsMode {
    type Err = OitError;
    fn from_str(s: &str) -> Result<BoundsMode, OitError> {
        match s.trim().to_ascii_lowercase().as_str() {
            "auto" => Ok(BoundsMode::Auto),
            "boxes" | "box" => Ok(BoundsMode::Boxes),
            "exact" => Ok(BoundsMode::Exact),
            other => {
                Err(OitError::InvalidSettings(format!("unknown bounds '{other}': use auto, boxes or exact")))
            }
        }
    }
}

/// Which rasterizer a GPU backend captures with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum RasterPath {
    /// The software rasterizer of oit-cpu.
    Cpu,
    /// The GPU's graphics pipeline.
    Hardware,
    /// A compute-shader rasterizer with oit-cpu's fixed-point rules.
    Compute,
}

impl fmt::Display for RasterPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            RasterPath::Cpu => "cpu",
            RasterPath::Hardware => "hardware",
            RasterPath::Compute => "compute",
        })
    }
}

impl FromStr for RasterPath {
    type Err = OitError;
    fn from_str(s: &str) -> Result<RasterPath, OitError> {
        match s.trim().to_ascii_lowercase().as_str() {
            "cpu" => Ok(RasterPath::Cpu),
            "hardware" | "hw" => Ok(RasterPath::Hardware),
            "compute" => Ok(RasterPath::Compute),
            other => Err(OitError::InvalidSettings(format!(
                "unknown raster path '{other}': use hardware or compute"
            ))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for name in [
            "reference",
            "plain",
            "dp",
            "ddp",
            "wavg",
            "wsum",
            "bdp",
            "bdp2",
            "bdp:3",
            "adp",
            "mdts",
            "mdts:4",
            "mdts64:8",
            "fabs",
            "fabs:16",
            "mlp:4",
            "dfb",
            "ll",
            "kbuf",
            "kbuf:8",
            "mboit:4",
            "mboit:6",
        ] {
            let t: Technique = name.parse().unwrap();
            assert_eq!(t.to_string(), name);
        }
        assert_eq!("bdp:2".parse::<Technique>().unwrap().to_string(), "bdp2");
        assert_eq!(Technique::parse_list("all").unwrap().len(), Technique::all().len());
    }

    #[test]
    fn bad_names_are_errors() {
        for bad in [
            "",
            "nope",
            "fabs:0",
            "fabs:x",
            "dp:3",
            "mlp:-1",
            "bdp:99999999",
            "mboit:5",
            "mboit:8",
            "dfb:4",
            "ll:2",
            "plain:2",
            "kbuf:0",
        ] {
            assert!(bad.parse::<Technique>().is_err(), "{bad}");
        }
    }
}
