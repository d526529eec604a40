//! The effects against closed forms: translucency through nested spheres seen along their axis,
//! Fresnel through planes at known angles, complexity over nested quads. The reference (f64,
//! `oit-core`'s `*_f64` effects) and one technique through the f32 resolve (`fabs`) are each
//! held to the closed form, on the CPU backend; the expected colours are computed here from the
//! geometry, not through the code under test.
//!
//! Every check names mutations of the code it guards that make it fail; those marked (tried) were
//! made and seen to fail when the test was written.
//!
//! Tolerance: one 8-bit step per channel. The closed forms are exact; the renders carry f32 NDC
//! depths and 16-bit octahedral normals, whose error moves the linear colour by under 1e-4 here,
//! less than a step, so a step is allowed only for values that fall on a rounding boundary.

use glam::{DVec3, Mat4, Vec3, Vec4};
use oit_core::{Backend, Camera, Effect, Frame, Instance, Mesh, Object, Scene, Settings, Shading, Technique};
use oit_tests::scene;

/// Linear [0, 1] to 8-bit sRGB (IEC 61966-2-1), written out here rather than borrowed from the
/// code under test.
fn srgb8(x: f64) -> u8 {
    let x = x.clamp(0.0, 1.0);
    let s = if x <= 0.003_130_8 { 12.92 * x } else { 1.055 * x.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0 + 0.5).floor() as u8
}

/// Whether an sRGB8 pixel shows the linear colour `want`, within one step per channel.
fn shows(pixel: [u8; 4], want: DVec3) -> bool {
    want.to_array().iter().zip(pixel).all(|(&w, p)| (i32::from(srgb8(w)) - i32::from(p)).abs() <= 1)
}

fn expected_pixel(want: DVec3) -> [u8; 3] {
    want.to_array().map(srgb8)
}

/// The reference and `fabs` (a sorting technique through the f32 resolve), rendered on the CPU.
fn renders(scene: &Scene, camera: &Camera, settings: &Settings) -> Vec<(Technique, Frame)> {
    let cpu = oit_cpu::CpuBackend::default();
    [Technique::Reference, Technique::Fabs { k: None }]
        .into_iter()
        .map(|technique| {
            let s = Settings { technique, ..settings.clone() };
            let frame = cpu.render(scene, camera, &s).unwrap_or_else(|e| panic!("{technique}: {e}"));
            (technique, frame)
        })
        .collect()
}

fn centre(settings: &Settings) -> usize {
    // odd sizes: the centre pixel's sample point is the image's centre, on the viewing axis
    assert!(settings.width % 2 == 1 && settings.height % 2 == 1);
    (settings.height / 2 * settings.width + settings.width / 2) as usize
}

/// `spheres:N` (oit-core's procedural scenes): N UV spheres of radii (i+1)/N about the origin,
/// each with its poles on the y axis, every object's absorption set to `sigma`.
fn spheres(n: u32, sigma: f32) -> Scene {
    let mut scene = scene(&format!("spheres:{n}"));
    for o in &mut scene.objects {
        o.absorption = sigma;
    }
    scene
}

/// Translucency through nested spheres, along the axis through their poles (vertices on the
/// true sphere, so the tessellation does not move the surfaces there).
///
/// The definition (`oit-core/src/composite.rs`): sorted layers pair up, 0 entering and 1
/// leaving, 2 entering and 3 leaving, ...; each pair absorbs (1 − c)·k per unit of view-space
/// distance, c the entering layer's colour, k = σ / (R/8) with R the scene's bounding radius.
/// Along the axis the 2N layers lie at −r_{N−1}, ..., −r_0, r_0, ..., r_{N−1} from the centre, so
/// with radii r_i = (i+1)/N:
/// - N = 1: one medium, the chord 2·r_0 = 2, entered through sphere 0;
/// - N = 2: the shell of sphere 1 on either side, 1 − 1/2 each, entered through sphere 1 then
///   sphere 0 (the inner sphere's far side);
/// - N = 3: the front shell of sphere 2 (1/3), the chord of sphere 0 (2/3), the back shell of
///   sphere 2 (1/3), entered through spheres 2, 0 and 1.
///
/// Mutations caught: pairing from layer 1 (1–2, 3–4: N = 2 sees the inner chord, 1, entered
/// through sphere 0; N = 1 absorbs nothing) (tried); distances from NDC depth without
/// `linear_depth` (thickness of 0.1 NDC units) (tried); k without the 1/8 (8× thinner). Not
/// caught here: the leaving layer's colour for the entering one (nested spheres are symmetric
/// along the axis, so both give the same sum); `composite.rs`'s and `resolve.rs`'s unit tests
/// catch that.
#[test]
fn translucency_through_nested_spheres() {
    let settings = Settings {
        width: 33,
        height: 33,
        effect: Effect::Translucency,
        shading: Shading::Flat,
        background: Vec3::new(1.0, 0.8, 0.6),
        ..Settings::default()
    };
    // from +y, 3 from the centre: the outer sphere spans distances 2..4
    let camera = Camera::look_at(Vec3::new(0.0, 3.0, 0.0), Vec3::ZERO, 30.0, 1.0, 1.0, 5.0);
    let sigma = 0.15;
    // the UV spheres' bounds are the box [−1, 1]³: radius √3
    let k = f64::from(sigma) / (3f64.sqrt() / 8.0);
    for n in [1u32, 2, 3] {
        let scene = spheres(n, sigma);
        let c: Vec<DVec3> = scene.objects.iter().map(|o| o.color.truncate().as_dvec3()).collect();
        // (entering colour, thickness) of each medium along the axis
        let media: Vec<(DVec3, f64)> = match n {
            1 => vec![(c[0], 2.0)],
            2 => vec![(c[1], 0.5), (c[0], 0.5)],
            3 => vec![(c[2], 1.0 / 3.0), (c[0], 2.0 / 3.0), (c[1], 1.0 / 3.0)],
            _ => unreachable!(),
        };
        let mut want = settings.background.as_dvec3();
        for (c, thickness) in media {
            let tau = (DVec3::ONE - c) * k * thickness;
            want *= DVec3::new((-tau.x).exp(), (-tau.y).exp(), (-tau.z).exp());
        }
        // the test sees light absorbed, and not all of it
        assert!(want.min_element() > 0.1 && (want - settings.background.as_dvec3()).min_element() < -0.1);
        let px = centre(&settings);
        for (t, frame) in renders(&scene, &camera, &settings) {
            if let Some(layers) = &frame.layers {
                assert_eq!(layers[px], 2 * n, "spheres:{n}: the axis crosses every sphere twice");
            }
            let got = frame.image.pixels[px];
            assert!(shows(got, want), "{t} spheres:{n}: {got:?}, want {:?} ({want})", expected_pixel(want));
        }
    }
}

/// A quad in the plane through the origin whose normal makes `degrees` with +z (turned about the
/// x axis), moved `z` along the z axis. Its corners are off-centre, so the z axis crosses it
/// inside a triangle, away from every edge.
fn tilted_quad(degrees: f32, z: f32) -> Mesh {
    let turn = Mat4::from_translation(Vec3::new(0.0, 0.0, z)) * Mat4::from_rotation_x(degrees.to_radians());
    let corners = [(-1.0, -0.8), (1.5, -0.8), (1.5, 1.3), (-1.0, 1.3)];
    let positions = corners.map(|(x, y)| turn.transform_point3(Vec3::new(x, y, 0.0))).to_vec();
    Mesh::new(format!("quad at {degrees}°"), positions, vec![[0, 1, 2], [0, 2, 3]])
}

/// A scene of the given meshes, one object each, at identity.
fn scene_of(meshes: Vec<Mesh>) -> Scene {
    let objects = (0..meshes.len())
        .map(|i| Object::new(format!("object {i}"), i, Vec4::new(0.8, 0.5, 0.2, 0.5)))
        .collect();
    let instances = (0..meshes.len()).map(|object| Instance { object, transform: Mat4::IDENTITY }).collect();
    Scene { name: "effects".into(), meshes, objects, instances, ..Scene::default() }
}

/// Schlick's transmittance with F0 = 0 (the effect's definition: no index of refraction), in
/// closed form.
fn schlick(degrees: f64) -> f64 {
    1.0 - (1.0 - degrees.to_radians().cos().abs()).powi(5)
}

/// Fresnel through planes at known angles to the view, seen at the centre pixel: the background
/// times Π (1 − (1 − cos θ)⁵). Facing the camera a plane passes everything (F0 = 0); at 60° it
/// passes 31/32; towards grazing it tends to 0 (85°: 0.366, 89°: 0.084); a plane facing away
/// (120°) passes what one at 60° does.
///
/// Mutations caught: the power 5 → 4 (60°: 15/16, 85°: 0.306) (tried, f64); `abs` dropped
/// (facing: n·v = −1 gives 1 − 2⁵ < 0, black) (tried, f32); the product over layers replaced by
/// one layer's factor (the stacked case, 0.355).
#[test]
fn fresnel_at_normal_and_grazing_incidence() {
    let settings = Settings {
        width: 33,
        height: 33,
        effect: Effect::Fresnel,
        background: Vec3::new(1.0, 0.7, 0.4),
        ..Settings::default()
    };
    let camera = Camera::look_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, 40.0, 1.0, 0.5, 6.0);
    let cases: [(&[(f32, f32)], f64); 6] = [
        (&[(0.0, 0.0)], 1.0),
        (&[(60.0, 0.0)], 31.0 / 32.0),
        (&[(85.0, 0.0)], schlick(85.0)),
        (&[(89.0, 0.0)], schlick(89.0)),
        (&[(120.0, 0.0)], 31.0 / 32.0),
        (&[(60.0, 0.4), (85.0, 0.0), (0.0, -0.4)], 31.0 / 32.0 * schlick(85.0)),
    ];
    assert!(schlick(89.0) < 0.09 && (schlick(60.0) - 31.0 / 32.0).abs() < 1e-12);
    let px = centre(&settings);
    for (planes, t) in cases {
        let scene = scene_of(planes.iter().map(|&(deg, z)| tilted_quad(deg, z)).collect());
        let want = settings.background.as_dvec3() * t;
        for (tech, frame) in renders(&scene, &camera, &settings) {
            if let Some(layers) = &frame.layers {
                assert_eq!(layers[px] as usize, planes.len(), "{planes:?}: the axis crosses every plane");
            }
            let got = frame.image.pixels[px];
            assert!(shows(got, want), "{tech} {planes:?}: {got:?}, want {:?} ({want})", expected_pixel(want));
        }
    }
}

/// Complexity over N nested quads facing the camera (quad i: half-size 1 − 0.8·i/N at
/// z = −0.1·i): a pixel whose ray lies inside k of them shows heat(k/N), the deepest pixel
/// holding all N; the ramp's stops (oit-core's `HEAT_STOPS`) are black, (0.05, 0.1, 0.6),
/// (0.6, 0.05, 0.5), (1, 0.5, 0.05), white at k/N = 0, 1/4, 1/2, 3/4, 1, linear between. Which
/// quads hold a pixel's ray is worked out here from the camera (pixels within 0.75 px of an edge
/// are skipped).
///
/// Mutations caught: scaling by N + 1 (every pixel one step of the ramp down) (tried); the ramp
/// run backwards (tried); counting a pixel's layers from 1 (k/N shifts).
#[test]
fn complexity_is_heat_of_the_layer_count() {
    const STOPS: [[f64; 3]; 5] =
        [[0.0, 0.0, 0.0], [0.05, 0.1, 0.6], [0.6, 0.05, 0.5], [1.0, 0.5, 0.05], [1.0, 1.0, 1.0]];
    let settings = Settings {
        width: 65,
        height: 65,
        effect: Effect::Complexity,
        background: Vec3::new(0.2, 0.3, 0.4),
        ..Settings::default()
    };
    let (distance, fov) = (3.0, 40.0f64);
    let camera = Camera::look_at(Vec3::new(0.0, 0.0, distance as f32), Vec3::ZERO, fov as f32, 1.0, 0.5, 6.0);
    for n in [4u32, 8] {
        let quad = |i: u32| (1.0 - 0.8 * f64::from(i) / f64::from(n), -0.1 * f64::from(i));
        let meshes = (0..n)
            .map(|i| {
                let (s, z) = quad(i);
                let (s, z) = (s as f32, z as f32);
                let p = [(-s, -s), (s, -s), (s, s), (-s, s)].map(|(x, y)| Vec3::new(x, y, z)).to_vec();
                Mesh::new(format!("quad {i}"), p, vec![[0, 1, 2], [0, 2, 3]])
            })
            .collect();
        let scene = scene_of(meshes);
        // heat(k/n): on a stop, or (n = 8, k odd) midway between two
        let heat = |k: u32| {
            let at = |j: usize| DVec3::from_array(STOPS[j]);
            let j = (4 * k / n) as usize;
            if (4 * k).is_multiple_of(n) { at(j) } else { (at(j) + at(j + 1)) / 2.0 }
        };
        let tan = (fov.to_radians() / 2.0).tan();
        for (t, frame) in renders(&scene, &camera, &settings) {
            let mut seen = [0u32; 9];
            for (px, &got) in frame.image.pixels.iter().enumerate() {
                let (x, y) = (px as u32 % settings.width, px as u32 / settings.width);
                // the pixel centre in NDC; the quads are symmetric, so the image's y flip is moot
                let ndc = |v: u32, size: u32| ((f64::from(v) + 0.5) / f64::from(size) * 2.0 - 1.0).abs();
                let (nx, ny) = (ndc(x, settings.width), ndc(y, settings.height));
                let mut k = 0;
                let mut near_edge = false;
                for i in 0..n {
                    let (s, z) = quad(i);
                    // world units per pixel, and where the ray crosses the quad's plane
                    let d = distance - z;
                    let pixel = 2.0 * tan * d / f64::from(settings.width);
                    let (wx, wy) = (nx * tan * d, ny * tan * d);
                    near_edge |= (wx - s).abs() < 0.75 * pixel || (wy - s).abs() < 0.75 * pixel;
                    k += u32::from(wx < s && wy < s);
                }
                if near_edge {
                    continue;
                }
                let want = if k == 0 { settings.background.as_dvec3() } else { heat(k) };
                assert!(shows(got, want), "{t} n {n}, pixel ({x}, {y}), {k} layers: {got:?}, want {want}");
                if let Some(layers) = &frame.layers {
                    assert_eq!(layers[px], k, "{t} n {n}, pixel ({x}, {y})");
                }
                seen[k as usize] += 1;
            }
            // every count from 0 to n was checked somewhere
            assert!(seen[..=n as usize].iter().all(|&s| s > 0), "{t} n {n}: {seen:?}");
        }
    }
}
