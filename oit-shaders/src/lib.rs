//! oit's GPU shader tree, and the one manifest of how its modules are put together.
//!
//! Every technique runs on the GPU as WGSL. Both GPU backends run the same text: oit-wgpu hands
//! it to wgpu at run time, oit-vulkan's build script compiles it to SPIR-V with naga. This crate
//! holds the tree (`wgsl/`) and says, once, what each module is made of:
//!
//! - `wgsl/core/`: what every module shares ([`COMMON`]: oit-core's rules and the fragment
//!   contract; [`PRELUDE`]: group 0's frame bindings and the resolve), the two rasterizers
//!   ([`COMPUTE_RASTER`], [`HARDWARE_RASTER`] over [`CAPTURE_RENDER`]), each starting with the
//!   texture sampler ([`TEXTURE`]), the compute path's setup ([`SETUP`]) and the small kernels of
//!   the frame (fill, finish, gate).
//! - `wgsl/technique/`: one file per technique, and the accessor files through which a
//!   technique reaches its atomic arrays. An accessor is one storage kind of an array: over a
//!   buffer (`fabs_counters.wgsl`, `mdts_words.wgsl`, `mdts_keys.wgsl`) or over a storage image
//!   (the same functions in `*_image.wgsl`). A module names the accessor its storage kind needs
//!   ([`Module::sources`]); the technique's own file is the same in both.
//! - `wgsl/vulkan/`: captures only raw Vulkan can run (adp's histogram by logic-op OR, the
//!   ordered k-buffer inside the fragment shader interlock).
//!
//! [`MODULES`] lists every module: its sources, in the order they are joined, and what follows
//! them ([`Tail`]). A module is declared once, by a line of the WGSL file it is about, which the
//! build script reads (`// module fabs (raster): technique/fabs_counters.wgsl technique/fabs.wgsl
//! ...`); [`FILES`] is every file of `wgsl/`. A new technique's WGSL file is thus its own entry:
//! nothing here is edited to add one. A module's full text is [`Module::compute_text`] (or, for its hardware-raster
//! twin, [`Module::hardware_text`]); oit-wgpu builds its pipelines from exactly these, and
//! oit-vulkan's build script compiles exactly these.
//!
//! ```
//! let fabs = oit_shaders::module("fabs").expect("a module of the manifest");
//! // the buffer accessor, the technique, its tail, the coverage masks of multisampled frames,
//! // the short lists' sort
//! assert_eq!(
//!     fabs.sources,
//!     [
//!         "technique/fabs_counters.wgsl",
//!         "technique/fabs.wgsl",
//!         "technique/tail.wgsl",
//!         "technique/coverage.wgsl",
//!         "technique/short_list.wgsl",
//!     ]
//! );
//! assert!(fabs.compute_text().contains("fn raster_main"));
//! ```
//!
//! The crate has no dependencies: oit-vulkan's build script depends on it, and a build
//! dependency is compiled a second time for the build.

/// The crate's README (what crates.io shows), whose example runs as a doc test with these.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

// `FILES` and `MODULES`, from the tree (the build script: every file of `wgsl/`, and every
// module its `// module NAME (TAIL): SOURCES` lines declare)
include!(concat!(env!("OUT_DIR"), "/tree.rs"));

/// The text of the tree's file at `path` (under `wgsl/`), if there is one.
pub fn file(path: &str) -> Option<&'static str> {
    FILES.iter().find(|(p, _)| *p == path).map(|(_, text)| *text)
}

/// The text of the tree's file at `path`, in a constant: a path not in the tree fails the build
/// that evaluates it.
pub const fn text(path: &str) -> &'static str {
    let mut i = 0;
    while i < FILES.len() {
        if same(FILES[i].0, path) {
            return FILES[i].1;
        }
        i += 1;
    }
    panic!("oit-shaders has no file of that path")
}

/// `a == b`, in a constant.
const fn same(a: &str, b: &str) -> bool {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

/// The text of the tree's file at `path`; for paths written in the code (a missing one is a bug,
/// which the manifest's test finds for every module).
fn known(path: &str) -> &'static str {
    file(path).unwrap_or_else(|| panic!("oit-shaders has no file {path}"))
}

/// What every module starts with: oit-core's rules (`common.wgsl`) and the fragment contract
/// (`fragment.wgsl`).
pub const COMMON: &str =
    concat!(include_str!("../wgsl/core/common.wgsl"), "\n", include_str!("../wgsl/core/fragment.wgsl"));

/// What a technique module has after [`COMMON`]: group 0's frame bindings (uniform, resolve
/// state, loss accounting) and the resolve's functions.
pub const PRELUDE: &str =
    concat!(include_str!("../wgsl/core/resolve.wgsl"), "\n", include_str!("../wgsl/core/prelude.wgsl"), "\n");

/// The sampler of base-colour textures (oit-core's, in WGSL), which both rasterizers start with.
pub const TEXTURE: &str = include_str!("../wgsl/core/texture.wgsl");

/// The compute rasterizer (the papers' "CUDA rasterizer"), appended to a technique module: the
/// integer f32 of `softfloat.wgsl` (a fragment's depth, as oit-core computes it), the sampler
/// ([`TEXTURE`]), then the rasterizer.
pub const COMPUTE_RASTER: &str = concat!(
    include_str!("../wgsl/core/softfloat.wgsl"),
    "\n",
    include_str!("../wgsl/core/texture.wgsl"),
    "\n",
    include_str!("../wgsl/core/raster_compute.wgsl")
);

/// The GPU's own rasterizer: the sampler ([`TEXTURE`]), the vertex stage over the pulled geometry
/// and the fragment stage that calls the technique's `capture` (entry points `hw_vs`, `hw_fs`).
pub const HARDWARE_RASTER: &str = concat!(
    include_str!("../wgsl/core/texture.wgsl"),
    "\n",
    include_str!("../wgsl/core/raster_hardware.wgsl")
);

/// The multisampled fragment entry point `hw_fs_masked`, after [`HARDWARE_RASTER`] and
/// [`CAPTURE_RENDER`] (it hands `capture` the fragment's `sample_mask`; docs/msaa.md).
pub const HARDWARE_RASTER_MASKED: &str = include_str!("../wgsl/core/raster_hardware_masked.wgsl");

/// The entry points over the opaque depth in the fixed-function depth test, `hw_fs_early`
/// (`@early_depth_test(force)`) and the count-only `hw_fs_count`, after [`HARDWARE_RASTER`] and
/// [`CAPTURE_RENDER`]: appended only where the device takes `@early_depth_test`.
pub const HARDWARE_RASTER_EARLY: &str = include_str!("../wgsl/core/raster_hardware_early.wgsl");

/// The fragment contract of a render pipeline's capture (what `hw_fs` hands `capture`).
pub const CAPTURE_RENDER: &str = include_str!("../wgsl/core/capture_render.wgsl");

/// The compute path's setup kernels: the integer f32 of `softfloat.wgsl`, then `setup.wgsl`.
/// They bind a group 0 of their own: nothing goes before them.
pub const SETUP: &str =
    concat!(include_str!("../wgsl/core/softfloat.wgsl"), "\n", include_str!("../wgsl/core/setup.wgsl"));

/// [`HARDWARE_RASTER`]'s vertex stage alone (up to its fragment entry point).
pub fn vertex_stage() -> &'static str {
    HARDWARE_RASTER.split_once("@fragment").map_or(HARDWARE_RASTER, |(vertex, _)| vertex)
}

/// What a blend capture's module has after its sources ([`Tail::Stage`]): [`vertex_stage`], then
/// `core/blend_stage.wgsl`, the test every blend capture's fragment stage makes first
/// (`hw_dropped`: a back face, or a fragment at or behind the opaque pass's depth). The blend
/// captures put their own fragment stages before it; both GPU backends build them from this.
pub fn blend_stage() -> &'static str {
    static TEXT: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    TEXT.get_or_init(|| format!("{}\n{}", vertex_stage(), text("core/blend_stage.wgsl")))
}

/// What follows a module's sources.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tail {
    /// Nothing: the module is kernels only.
    Kernels,
    /// The compute rasterizer; and, as the module's hardware-raster twin (`<name>_hw` in
    /// oit-vulkan), [`CAPTURE_RENDER`] and [`HARDWARE_RASTER`].
    Raster,
    /// Nothing, and nothing before: the sources alone, without [`COMMON`] (the setup kernels,
    /// which bind a group 0 of their own).
    Alone,
    /// [`blend_stage`] (the vertex stage and the blend captures' shared test): a blend capture's
    /// module, with fragment entry points of its own.
    Stage,
}

/// One module of the manifest.
#[derive(Clone, Copy, Debug)]
pub struct Module {
    /// The module's name, by which a technique asks for it.
    pub name: &'static str,
    /// Its sources under `wgsl/`, in the order they are joined (by a newline).
    pub sources: &'static [&'static str],
    /// What follows them.
    pub tail: Tail,
}

impl Module {
    /// The module's own sources, joined: what a technique's passes add after [`COMMON`] and
    /// [`PRELUDE`].
    pub fn source(&self) -> String {
        self.sources.iter().map(|p| known(p)).collect::<Vec<_>>().join("\n")
    }

    /// The module's text up to its tail: [`COMMON`], [`PRELUDE`] and [`Module::source`] (the
    /// sources alone for [`Tail::Alone`]).
    pub fn kernels_text(&self) -> String {
        match self.tail {
            Tail::Alone => self.source(),
            _ => format!("{COMMON}\n{PRELUDE}{}", self.source()),
        }
    }

    /// The module's full text for compute pipelines: [`Module::kernels_text`], then the compute
    /// rasterizer where its tail is [`Tail::Raster`], or [`blend_stage`] for [`Tail::Stage`].
    pub fn compute_text(&self) -> String {
        let text = self.kernels_text();
        match self.tail {
            Tail::Kernels | Tail::Alone => text,
            Tail::Raster => format!("{text}\n{COMPUTE_RASTER}"),
            Tail::Stage => format!("{text}\n{}", blend_stage()),
        }
    }

    /// The module's hardware-raster twin (for [`Tail::Raster`] modules): [`Module::kernels_text`],
    /// [`CAPTURE_RENDER`], [`HARDWARE_RASTER`], [`HARDWARE_RASTER_MASKED`] and
    /// [`HARDWARE_RASTER_EARLY`] (oit-vulkan's, whose devices all take `@early_depth_test`).
    pub fn hardware_text(&self) -> Option<String> {
        (self.tail == Tail::Raster).then(|| {
            format!(
                "{}\n{CAPTURE_RENDER}\n{HARDWARE_RASTER}\n{HARDWARE_RASTER_MASKED}\n{HARDWARE_RASTER_EARLY}",
                self.kernels_text()
            )
        })
    }
}

/// The module called `name`.
pub fn module(name: &str) -> Option<&'static Module> {
    MODULES.iter().find(|m| m.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every source a module names is a file of the tree, no module name repeats, every module
    /// is declared in one of its own sources (the file it is about: `fabs_image` in `fabs.wgsl`),
    /// and the modules the backends ask for by name are there. Fails when a declaration moves to
    /// an unrelated file, names a file twice over, or a module a backend needs is lost.
    #[test]
    fn manifest_names_the_tree() {
        for m in MODULES {
            for s in m.sources {
                assert!(file(s).is_some(), "module {} names {s}, which is not in FILES", m.name);
            }
            assert_eq!(MODULES.iter().filter(|n| n.name == m.name).count(), 1, "{} twice", m.name);
            let declaration = format!("// module {} (", m.name);
            let homes: Vec<&str> = FILES
                .iter()
                .filter(|(_, text)| text.lines().any(|l| l.starts_with(&declaration)))
                .map(|f| f.0)
                .collect();
            assert_eq!(homes.len(), 1, "{} declared in {homes:?}", m.name);
            assert!(
                m.sources.contains(&homes[0]),
                "{} declared in {}, not one of its sources",
                m.name,
                homes[0]
            );
            let mut sorted = m.sources.to_vec();
            sorted.sort_unstable();
            sorted.dedup();
            assert_eq!(sorted.len(), m.sources.len(), "{} names a source twice", m.name);
        }
        for name in [
            "fill", "finish", "gate", "opaque", "setup", "fabs", "wboit", "mboit", "weighted", "blend",
            "kbuf",
        ] {
            assert!(module(name).is_some(), "no module {name}");
        }
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("wgsl");
        for (path, text) in FILES {
            let on_disk = std::fs::read_to_string(root.join(path)).expect("a file of the tree");
            assert_eq!(&on_disk, text, "{path} changed since the build");
        }
    }

    /// The two storage kinds of an accessor define the same functions: every `fn` of the buffer
    /// file is a `fn` of its image twin. Fails when one side gains or renames a function.
    #[test]
    fn accessor_twins_define_the_same_functions() {
        let fns = |path: &str| -> Vec<String> {
            let mut names: Vec<String> = known(path)
                .lines()
                .filter_map(|l| l.trim_start().strip_prefix("fn "))
                .map(|rest| rest.split('(').next().unwrap_or("").trim().to_string())
                .collect();
            names.sort();
            names
        };
        for (buffer, image) in [
            ("technique/fabs_counters.wgsl", "technique/fabs_counters_image.wgsl"),
            ("technique/mdts_words.wgsl", "technique/mdts_words_image.wgsl"),
            ("technique/mdts_keys.wgsl", "technique/mdts_keys_image.wgsl"),
        ] {
            assert_eq!(fns(buffer), fns(image), "{buffer} and {image}");
            assert!(!fns(buffer).is_empty(), "{buffer} defines no function");
        }
    }

    /// The texts are assembled as documented: common, prelude, sources, tail. Fails when a tail
    /// is dropped or the order changes.
    #[test]
    fn texts_are_assembled_in_order() {
        let fabs = module("fabs").expect("fabs");
        let text = fabs.compute_text();
        let at = |needle: &str| text.find(needle).unwrap_or_else(|| panic!("{needle} missing"));
        assert!(at(COMMON) < at(PRELUDE));
        assert!(at(PRELUDE) < at(&fabs.source()));
        assert!(at(&fabs.source()) < at(COMPUTE_RASTER));
        let hw = fabs.hardware_text().expect("a raster module has a hardware twin");
        assert!(
            hw.ends_with(HARDWARE_RASTER_EARLY)
                && hw.contains(HARDWARE_RASTER_MASKED)
                && hw.contains(HARDWARE_RASTER)
                && hw.contains(CAPTURE_RENDER)
        );
        assert!(module("scan").and_then(Module::hardware_text).is_none());
        assert_eq!(module("setup").expect("setup").compute_text(), SETUP);
        // a blend capture's module ends with the vertex stage and the test its fragment stages make
        let dp = module("dp_depth").expect("dp_depth").compute_text();
        assert!(dp.ends_with(blend_stage()) && dp.contains("fn hw_vs") && dp.contains("fn hw_dropped"));
        assert!(!dp.contains("fn hw_fs"), "a blend capture has fragment stages of its own");
    }
}
