//! What each backend × raster path is expected to do differently, in one table, so that no test
//! body special-cases a backend. A row names the test body, the backend and path, and why the
//! body cannot hold there; [`crate::backends_for`] leaves that backend out of that body with one
//! printed line. A row is a known, explained difference, not a tolerance: every body still runs on
//! the CPU backend and on every other path.

use oit_core::RasterPath;

/// One expected difference.
#[derive(Clone, Copy, Debug)]
pub struct Expected {
    /// The test body (its function name).
    pub test: &'static str,
    /// The backend's name.
    pub backend: &'static str,
    /// The raster path.
    pub path: RasterPath,
    /// Why the body does not hold there.
    pub why: &'static str,
}

/// Every expected difference of the suite.
pub const EXPECTED: &[Expected] = &[
    Expected {
        test: "effects_run_on_sorting_techniques",
        backend: "wgpu",
        path: RasterPath::Hardware,
        why: "wgpu's ddp refuses translucency (its resolve keeps no per-pixel stack to replay the back \
              layers nearest first); the refusal itself is tested in wgpu_ported_a, the other effects \
              against oit-cpu in wgpu_ported_a/b",
    },
    Expected {
        test: "effects_run_on_sorting_techniques",
        backend: "wgpu",
        path: RasterPath::Compute,
        why: "as on the hardware path: wgpu's ddp refuses translucency",
    },
    Expected {
        test: "effects_run_on_sorting_techniques",
        backend: "vulkan",
        path: RasterPath::Compute,
        why: "oit-vulkan runs oit-wgpu's ddp resolve, which refuses translucency (no per-pixel stack \
              to replay the back layers nearest first); the other effects and techniques are held \
              to oit-cpu in vulkan.rs",
    },
    Expected {
        test: "exact_schemes_on_separated_layers",
        backend: "wgpu",
        path: RasterPath::Hardware,
        why: "adp on spheres:16 at 64²: the GPU's rasterizer interpolates depth its own way, and on \
              lavapipe 3 fragments that fall in neighbouring 1/1024 bins of the histogram on the \
              fixed-point paths share a bin there: they are counted in `lost` (3) and account for \
              the 0.1 % EPR (never_silent holds; `oit compare --backend wgpu --raster hardware \
              --scene spheres:16 --size 64x64 --shading flat --techniques adp`). The body asserts \
              lost 0, which only oit's fixed-point depths guarantee",
    },
    Expected {
        test: "a_thousand_layers",
        backend: "wgpu",
        path: RasterPath::Compute,
        why: "KNOWN BUG, not a tolerance: on lavapipe the compute path's reference with 1,000 layers \
              per pixel sometimes composites only part of the deepest pixels (planes:1000 at 8x8, \
              default view: 1,552 of 17,347 fragments about one run in five, the per-pixel counts \
              and offsets correct; also on the commit before the conformance suite ran on wgpu). \
              The loss is reported in `lost`, not hidden; the cause is open (the architecture \
              issue's closing note)",
    },
    Expected {
        test: "four_thousand_layers",
        backend: "wgpu",
        path: RasterPath::Compute,
        why: LAVAPIPE_LOOP_LIMIT,
    },
    Expected {
        test: "alpha_extremes_over_a_thousand_layers",
        backend: "wgpu",
        path: RasterPath::Compute,
        why: LAVAPIPE_LOOP_LIMIT,
    },
];

/// Why the compute path cannot composite a thousand layers per pixel on lavapipe (found with
/// `planes:4096` at 8×8, where it happens every run: each of the 24 pixels of the rows that hold
/// a 4,096-layer pixel ends with 1 fragment captured).
const LAVAPIPE_LOOP_LIMIT: &str = "KNOWN BUG, not a tolerance: llvmpipe (lavapipe) ends a shader \
    invocation's loops after 65,535 iterations in all (LP_MAX_TGSI_LOOP_ITERATIONS, shared by every \
    loop of the shader and counted per SIMD row of pixels). The compute path fills a pixel's list out \
    of primitive order, so the reference's and fabs's per-pixel insertion sorts of 1,000+ fragments \
    pass that limit and the resolve stops after the first fragment, and `lost` does not count the rest \
    (captured + lost < fragments). The hardware path fills in primitive order (already sorted). Also \
    the cause of a_thousand_layers' row above; a fix is a resolve that stays under the limit";

/// The reason `test` does not run on `backend`/`path`, if the table has one.
pub fn expected(test: &str, backend: &str, path: RasterPath) -> Option<&'static str> {
    EXPECTED.iter().find(|e| e.test == test && e.backend == backend && e.path == path).map(|e| e.why)
}
