//! The scene, camera, shading and backend options `render`, `compare` and `sweep` share, and
//! their checking: everything is validated here, before any rendering starts.

use std::path::Path;

use clap::Args;
use oit_bench::backends::{BackendOptions, RasterChoice, select, with_paths};
use oit_core::{
    Backend, BdpMode, BoundsMode, Camera, Effect, HardwareCapture, OitError, Overflow, Scene, Settings,
    Shading, Technique, View, load_scene_with, parse_memory, parse_rgb, parse_size,
};

/// Options shared by `render`, `compare` and `sweep`.
#[derive(Args, Clone, Debug)]
#[command(next_help_heading = "Scene, camera and shading")]
pub struct SceneArgs {
    /// The scene: a built-in name (default, bunny, armadillo, the scene set particles, foliage,
    /// glass and cad, planes:N, spheres:N, cluster:N, knot, coplanar, ties:N, near:N, particles:N,
    /// fence, grid:RxC:MESH, scale:S:SCENE for SCENE with every coordinate times S, wall:F:SCENE
    /// and nowall:F:SCENE for SCENE with an opaque wall, untextured:SCENE; `oit info` lists them)
    /// or a path to a Wavefront .obj file or a glTF 2.0 file, .gltf or .glb (at most 1 GiB;
    /// OIT_MAX_MODEL_BYTES raises the limit).
    #[arg(long, value_name = "NAME|FILE", default_value = oit_core::DEFAULT_SCENE)]
    pub scene: String,

    /// The scene of a glTF file to draw (--scene FILE.gltf or FILE.glb), numbered from 0 as in
    /// the file's `scenes` [default: the file's default scene, else its first]. Refused with a
    /// scene that is not a glTF file's path.
    #[arg(long, value_name = "N")]
    pub gltf_scene: Option<usize>,

    /// Image size in pixels, WIDTHxHEIGHT (each from 1 to 16384).
    #[arg(long, value_name = "WxH", default_value = "512x512")]
    pub size: String,

    /// Camera angle around the vertical axis in degrees; 0 looks at the scene from +z.
    #[arg(long, value_name = "DEG", default_value_t = 30.0, allow_negative_numbers = true)]
    pub azimuth: f32,

    /// Camera angle above the horizontal plane in degrees (clamped to ±89).
    #[arg(long, value_name = "DEG", default_value_t = 20.0, allow_negative_numbers = true)]
    pub elevation: f32,

    /// Vertical field of view in degrees (0.5 to 179). The camera is placed so the whole scene
    /// fits.
    #[arg(long, value_name = "DEG", default_value_t = 45.0, allow_negative_numbers = true)]
    pub fov: f32,

    /// Distance from the eye to the near clipping plane, in scene units: above 0 and below the far
    /// plane (`render --json` reports the fitted camera's near and far) [default: fitted to the
    /// scene].
    #[arg(long, value_name = "DIST", allow_negative_numbers = true)]
    pub near: Option<f32>,

    /// Distance from the eye to the far clipping plane, in scene units: beyond the near plane
    /// [default: fitted to the scene].
    #[arg(long, value_name = "DIST", allow_negative_numbers = true)]
    pub far: Option<f32>,

    /// Opacity in [0, 1] given to every object instead of its own [default: each object's own].
    #[arg(long, value_name = "A", allow_negative_numbers = true)]
    pub alpha: Option<f32>,

    /// How fragments are coloured: headlight (colour × (0.3 + 0.7·|n·l|), light from the eye),
    /// flat (the object's colour), vertex (per-vertex colours; a mesh without them gets its
    /// object's colour, as flat, and a warning naming it) or normal (the normal as colour).
    #[arg(long, value_name = "MODE", default_value = "headlight")]
    pub shading: String,

    /// Background colour as linear R,G,B, each in [0, 1].
    #[arg(long, value_name = "R,G,B", default_value = "0.06,0.07,0.09")]
    pub background: String,

    /// What is made of each pixel's sorted fragments: transparency (alpha compositing),
    /// translucency (Beer–Lambert absorption through the thickness), fresnel (Schlick
    /// transmittance per layer) or complexity (a heat map of fragments per pixel).
    #[arg(long, value_name = "EFFECT", default_value = "transparency")]
    pub effect: String,

    /// How bucket techniques (bdp, adp) find each pixel's depth range: boxes (the rendered depths
    /// of the objects' bounding boxes), exact (the fragments' own min and max, one more geometry
    /// pass), or auto (exact where the scene has an opaque part, whose depth the boxes are not cut
    /// at; boxes elsewhere).
    #[arg(long, value_name = "MODE", default_value = "auto")]
    pub bounds: String,

    /// What single-pass bdp stores: color (32 packed colours), depth (16 min/max pairs) or auto
    /// (color for transparency with one pass, depth otherwise).
    #[arg(long, value_name = "MODE", default_value = "auto")]
    pub bdp_mode: String,

    /// How bdp, dp, ddp, wavg/wsum (and adp on vulkan) capture on the hardware raster path of GPU
    /// backends: atomics (fragment-stage storage-buffer atomics, the same capture as the compute
    /// path; faster on the GPUs measured) or blend (the papers' graphics pipeline: MAX blending
    /// into 8 RGBA32F targets for bdp's colour mode, depth textures and occlusion queries for dp,
    /// MAX blending of (-d, d) into an RG32F target for ddp, additive float blending for
    /// wavg/wsum; on vulkan, adp's histogram by logic-op OR into 8 RGBA32UI targets).
    #[arg(long, value_name = "atomics|blend", default_value = "atomics")]
    pub hardware_capture: String,

    /// Where mdts, mdts64 and fabs keep their atomic words: buffer (storage buffers, every
    /// backend) or image (storage images by imageAtomicMin / imageAtomicAdd, as the papers'
    /// OpenGL ports did; vulkan only, mdts64 where the device has 64-bit image atomics). Other
    /// techniques ignore it.
    #[arg(long, value_name = "buffer|image", default_value = "buffer")]
    pub atomic_storage: String,

    /// The blender's colour target on the hardware path, for plain and (with
    /// --hardware-capture blend) wavg/wsum: f32 (exact), f16 (what weighted blended OIT uses),
    /// unorm8 (an 8-bit colour buffer: plain only; wavg/wsum blending refuse it, their sums leave
    /// [0, 1]). The compute path, --hardware-capture atomics and cpu ignore it, and take any.
    #[arg(long, value_name = "f32|f16|unorm8", default_value = "f32")]
    pub blend_target: String,

    /// Stops the peeling techniques (dp, ddp, mlp, adp batches) after N capture passes; deeper
    /// layers count as lost [default: peel until no layer is left].
    #[arg(long, value_name = "N")]
    pub max_peels: Option<u32>,

    /// Memory budget of a frame's per-pixel storage, in bytes with an optional K, M, G or T
    /// (binary: 512M, 2G). A frame that needs more runs in screen tiles that each fit, with the
    /// same image and counts (`tiles` in --json says how many) [default: what the device allows;
    /// a frame the device refuses as too large is tiled the same way].
    #[arg(long, value_name = "BYTES")]
    pub memory: Option<String>,

    /// What fabs:K, mdts:K and mdts64:K make of a pixel's fragments beyond its K nearest: drop
    /// (counted in `lost`) or tail (merged into a weighted-average tail behind the K, multi-layer
    /// alpha blending after Salvi & Vaidyanathan 2014; one more geometry pass where a pixel
    /// overflows; counted in `merged`; transparency only). Other techniques ignore it.
    #[arg(long, value_name = "drop|tail", default_value = "drop")]
    pub overflow: String,

    /// Samples a pixel: 1, 4 or 8 (the standard patterns of Vulkan and D3D). Above 1 a fragment
    /// covers a pixel where its triangle covers any sample, carries its coverage mask, and is
    /// composited per sample (MSAA: one shading a fragment); on every backend and raster path
    /// (the GPU backends' default at several samples: compute): per sample with reference, dfb,
    /// ll, fabs, the peels (dp, ddp, mlp) and kbuf (where it runs); every other technique
    /// composites each fragment over its pixel with its alpha weighted by its coverage fraction
    /// (the report's `coverage`; docs/msaa.md).
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub samples: u32,

    /// With --samples 4 or 8: the reference becomes the supersampled reference (every sample
    /// rasterized and shaded as a pixel of its own), so that `oit compare` reports MSAA's own
    /// error against supersampling (its `msaa-ref` row) beside each technique's error against
    /// both references (cpu, and both raster paths of the GPU backends). Other techniques ignore it.
    #[arg(long)]
    pub supersample: bool,

    /// With --samples 4 or 8: sample (each fragment composited only at the samples it covers) or
    /// pixel (at every sample of its pixel, the per-pixel capture baseline that shows the seams
    /// along shared edges; the reference stays per sample). The techniques that keep no mask
    /// weigh alpha by coverage under `sample` (bdp's colour mode: whole, its measured choice),
    /// whole under `pixel`, and by coverage under `fraction`.
    #[arg(long, value_name = "sample|pixel|fraction", default_value = "sample")]
    pub coverage: String,

    /// Backend to render with: a name (cpu; wgpu, vulkan when compiled in), a comma-separated
    /// list, or all (every backend compiled in whose device is present).
    #[arg(long, value_name = "NAME|all", default_value = "cpu")]
    pub backend: String,

    /// Worker threads of the cpu backend [default: one per core].
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,

    /// Capture path of the GPU backends: hardware (the graphics pipeline), compute (a compute-shader
    /// rasterizer with oit-cpu's rules), or all (one row per path). The cpu backend has one path,
    /// cpu [default: the backend's choice per technique; all when --backend all].
    #[arg(long, value_name = "PATH")]
    pub raster: Option<String>,

    /// GPU adapter to use: a substring of its name (see `oit info`); also read from OIT_ADAPTER
    /// [default: the first discrete GPU, else any].
    #[arg(long, value_name = "NAME")]
    pub adapter: Option<String>,
}

/// Everything a command needs to render, checked.
pub struct Prepared {
    /// The loaded, validated scene.
    pub scene: Scene,
    /// The settings, technique still the default (`reference`).
    pub settings: Settings,
    /// The camera's angles; [`Prepared::camera`] turns them into a camera.
    pub view: View,
    /// The backends selected.
    pub backends: Vec<Box<dyn Backend>>,
}

impl Prepared {
    /// The camera at `view` (the scene's bounds framed at the image's aspect).
    pub fn camera(&self, view: View) -> Result<Camera, OitError> {
        Camera::orbit_scene(&self.scene, view, self.settings.width as f32 / self.settings.height as f32)
    }

    /// `settings` with `technique`.
    pub fn with_technique(&self, technique: Technique) -> Settings {
        Settings { technique, ..self.settings.clone() }
    }
}

impl SceneArgs {
    /// Parses and checks every option, loads the scene and builds the backends, cheapest checks
    /// first so a typo fails before a large scene is read.
    pub fn prepare(&self) -> Result<Prepared, OitError> {
        let (width, height) = parse_size(&self.size)?;
        check_gltf_scene(&self.scene, self.gltf_scene)?;
        if let Some(n) = self.threads {
            oit_core::check_threads(n)?;
        }
        let settings = Settings {
            width,
            height,
            technique: Technique::Reference,
            background: parse_rgb(&self.background)?,
            alpha: self.alpha,
            max_peels: self.max_peels,
            shading: self.shading.parse::<Shading>()?,
            effect: self.effect.parse::<Effect>()?,
            bounds: self.bounds.parse::<BoundsMode>()?,
            raster: None,
            bdp_mode: self.bdp_mode.parse::<BdpMode>()?,
            hardware_capture: self.hardware_capture.parse::<HardwareCapture>()?,
            region: None,
            memory: self.memory.as_deref().map(parse_memory).transpose()?,
            overflow: self.overflow.parse::<Overflow>()?,
            atomic_storage: self.atomic_storage.parse::<oit_core::AtomicStorage>()?,
            blend_target: self.blend_target.parse::<oit_core::BlendTarget>()?,
            samples: self.samples,
            supersample: self.supersample,
            pixel_coverage: parse_coverage(&self.coverage)? == Some(true),
            fraction_coverage: parse_coverage(&self.coverage)?.is_none(),
        };
        settings.validate()?;
        check_planes(self.near, self.far)?;
        let view = View {
            azimuth: self.azimuth,
            elevation: self.elevation,
            fov: self.fov,
            near: self.near,
            far: self.far,
        };
        // Checks the angles before the scene is loaded (the unit box stands in for its bounds; a
        // plane set against one fitted to the scene is checked once the scene is loaded).
        let unit = oit_core::Aabb { min: oit_core::glam::Vec3::ZERO, max: oit_core::glam::Vec3::ONE };
        Camera::orbit(&unit, View { near: None, far: None, ..view }, width as f32 / height as f32)?;
        let raster = RasterChoice::parse(self.raster.as_deref(), &self.backend)?;
        let options = BackendOptions { threads: self.threads, adapter: self.adapter.clone() };
        let backends = with_paths(select(&self.backend, &options)?, raster)?;
        let scene = load_scene_with(&self.scene, self.gltf_scene)?;
        for warning in &scene.warnings {
            eprintln!("warning: {warning}");
        }
        scene.validate()?;
        if let Some(warning) = shading_warning(&scene, settings.shading) {
            eprintln!("warning: {warning}");
        }
        let prepared = Prepared { scene, settings, view, backends };
        prepared.camera(view)?;
        Ok(prepared)
    }
}

/// Most mesh names [`shading_warning`] lists before it counts the rest.
const LISTED_MESHES: usize = 3;

/// The one warning `--shading vertex` gets when meshes the scene draws have no vertex colours:
/// those are shaded with their object's colour, unlit, exactly as `--shading flat` would (see
/// [`Shading::Vertex`]). Names up to [`LISTED_MESHES`] such meshes, each once, and counts the
/// rest; `None` for other shadings or when every drawn mesh has colours.
pub fn shading_warning(scene: &Scene, shading: Shading) -> Option<String> {
    if shading != Shading::Vertex {
        return None;
    }
    // in the order first drawn, each once (a flag per mesh: an OBJ may hold many thousands)
    let mut seen = vec![false; scene.meshes.len()];
    let mut bare: Vec<usize> = Vec::new();
    for instance in &scene.instances {
        let mesh = scene.objects.get(instance.object).map(|o| o.mesh);
        if let Some(m) = mesh.filter(|&m| scene.meshes.get(m).is_some_and(|m| m.colors.is_none()))
            && !std::mem::replace(&mut seen[m], true)
        {
            bare.push(m);
        }
    }
    if bare.is_empty() {
        return None;
    }
    let mut names: Vec<String> =
        bare.iter().take(LISTED_MESHES).map(|&m| format!("'{}'", scene.meshes[m].name)).collect();
    if bare.len() > LISTED_MESHES {
        names.push(format!("{} more", bare.len() - LISTED_MESHES));
    }
    let (noun, verb) = if bare.len() == 1 { ("mesh", "has") } else { ("meshes", "have") };
    Some(format!(
        "--shading vertex: {noun} {} of scene '{}' {verb} no vertex colours; drawn with the object \
         colour, unlit, as --shading flat (vertex colours come from OBJ lines `v x y z r g b`)",
        names.join(", "),
        scene.name
    ))
}

/// Checks before the scene is read that `--gltf-scene` comes with a glTF file's path (which scene
/// of the file exists is checked when it is read).
pub fn check_gltf_scene(scene: &str, gltf_scene: Option<usize>) -> Result<(), OitError> {
    match gltf_scene {
        Some(n) if !oit_core::is_gltf_path(scene) => Err(OitError::InvalidSettings(format!(
            "--gltf-scene {n} picks a scene of a glTF file, and scene '{scene}' is not one: give \
             --scene the path of a .gltf or .glb file, or leave --gltf-scene out"
        ))),
        _ => Ok(()),
    }
}

/// Checks `--near` and `--far` on their own and against each other (against a plane fitted to the
/// scene, the camera checks them once the scene is loaded).
fn check_planes(near: Option<f32>, far: Option<f32>) -> Result<(), OitError> {
    for (flag, value) in [("--near", near), ("--far", far)] {
        if let Some(d) = value
            && !(d.is_finite() && d > 0.0)
        {
            return Err(OitError::InvalidSettings(format!(
                "{flag} {d} is not a distance: use a finite number above 0 (in scene units, from the eye)"
            )));
        }
    }
    if let (Some(n), Some(f)) = (near, far)
        && n >= f
    {
        return Err(OitError::InvalidSettings(format!(
            "--near {n} must be less than --far {f}: the near plane lies between the eye and the far plane"
        )));
    }
    Ok(())
}

/// Checks before any work that `path` can be written: its folder exists, it is not a folder, and
/// its extension is `extension`.
pub fn check_output(path: &Path, extension: &str, option: &str) -> Result<(), OitError> {
    let bad = |message: String| OitError::Write { path: path.to_path_buf(), message };
    if !path.extension().is_some_and(|e| e.eq_ignore_ascii_case(extension)) {
        return Err(bad(format!("{option} must name a .{extension} file")));
    }
    if path.is_dir() {
        return Err(bad("it is a folder".into()));
    }
    let parent = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    if !parent.is_dir() {
        return Err(bad(format!("folder {} does not exist", parent.display())));
    }
    Ok(())
}

/// `--coverage`: `sample` (per-sample composite, or each technique's own choice where it keeps
/// no mask: `Some(false)`), `pixel` (the per-pixel capture baseline: `Some(true)`) or `fraction`
/// (alpha weighted by coverage in every technique that keeps no mask: `None`).
fn parse_coverage(value: &str) -> Result<Option<bool>, OitError> {
    match value {
        "sample" => Ok(Some(false)),
        "pixel" => Ok(Some(true)),
        "fraction" => Ok(None),
        other => {
            Err(OitError::InvalidSettings(format!("--coverage {other:?}: use sample, pixel or fraction")))
        }
    }
}

#[cfg(test)]
mod tests {
    use oit_core::glam::{Mat4, Vec3, Vec4};
    use oit_core::{Instance, Mesh, Object, Scene, Shading};

    use super::shading_warning;

    /// `n` meshes, each drawn twice; the first `coloured` of them with vertex colours.
    fn scene(n: usize, coloured: usize) -> Scene {
        let mut scene = Scene { name: "s".into(), ..Scene::default() };
        for i in 0..n {
            let mut mesh = Mesh::new(format!("m{i}"), vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]);
            if i < coloured {
                mesh.colors = Some(vec![Vec3::ONE; 3]);
            }
            scene.meshes.push(mesh);
            scene.objects.push(Object::new(format!("o{i}"), i, Vec4::ONE));
            for _ in 0..2 {
                scene.instances.push(Instance { object: i, transform: Mat4::IDENTITY });
            }
        }
        scene
    }

    #[test]
    fn vertex_shading_names_the_meshes_without_colours() {
        assert_eq!(shading_warning(&scene(5, 0), Shading::Flat), None);
        assert_eq!(shading_warning(&scene(3, 3), Shading::Vertex), None);
        let one = shading_warning(&scene(2, 1), Shading::Vertex).expect("m1 has no colours");
        assert!(
            one.contains("mesh 'm1' of scene 's' has no vertex colours") && one.contains("flat"),
            "{one}"
        );
        let many = shading_warning(&scene(6, 1), Shading::Vertex).expect("five have none");
        assert!(many.contains("meshes 'm1', 'm2', 'm3', 2 more of scene 's' have"), "{many}");
        assert_eq!(many.matches("'m1'").count(), 1, "each mesh once: {many}");
    }
}
