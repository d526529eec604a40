//! Every check family of the suite fails on a deliberately broken frame (issue 16's target): a
//! check that passes whatever the code does would hide the wrong answers it is there to catch.
//! Each test takes a real, correct frame (oit-cpu), shows the check holds on it, breaks the frame
//! one way (a dropped fragment, two layers swapped, a skewed colour, a loss moved or uncounted),
//! and shows the check fails.
//!
//! Families and where they guard: `accounting` (accounting.rs, every technique), `exact`
//! (exact techniques against the reference), `never_silent` (ties.rs), `errors_within_losses`
//! (buckets.rs), `same_fragments` and `off_edges_equal` (wgpu.rs, wgpu_hardware.rs), the metrics'
//! coverage (metrics.rs). The weighted bound and the closed-form composite carry their own
//! mutations in foundation.rs; the bench's cross-backend check in oit-bench's unit tests.
//!
//! The second half mutates production code, not frames (issue 41.10): a test hook
//! (`OIT_MUTATION`, [`oit_core::mutation`]) breaks one capture of oit-cpu or of oit-wgpu's compute
//! path (or the blender's count on its hardware path); each `body_*` test here holds its check on
//! correct code, and each `*_fails_*` test runs this binary again on one body under one mutation
//! and requires the named check to fail, with its message (as `hardware_covered.rs` does for the
//! hardware raster's `hardware-drop-third`).

use glam::{Mat4, Vec3, Vec4};
use oit_core::metrics::{accuracy, edge_mask};
use oit_core::{Backend, Frame, Mesh, Object, Scene, Settings, Shading, Technique};
use oit_tests::checks::*;
use oit_tests::*;

/// Frontal quads of the given depths and colours (the first in front of the camera at z = 0
/// nearest), one object each, overlapping over most of the image.
fn quads(layers: &[(f32, Vec4)]) -> Scene {
    let mut scene = Scene { name: "quads".into(), ..Default::default() };
    for (i, &(z, color)) in layers.iter().enumerate() {
        let p = vec![
            Vec3::new(-1.0, -1.0, z),
            Vec3::new(1.0, -1.0, z),
            Vec3::new(1.0, 1.0, z),
            Vec3::new(-1.0, 1.0, z),
        ];
        scene.meshes.push(Mesh::new(format!("q{i}"), p, vec![[0, 1, 2], [0, 2, 3]]));
        scene.objects.push(Object::new(format!("q{i}"), i, color));
        scene.instances.push(oit_core::Instance { object: i, transform: Mat4::IDENTITY });
    }
    scene
}

const RED: Vec4 = Vec4::new(0.9, 0.1, 0.1, 0.5);
const BLUE: Vec4 = Vec4::new(0.1, 0.2, 0.9, 0.5);

fn flat(size: u32, t: &str) -> Settings {
    Settings { shading: Shading::Flat, ..settings(size, t) }
}

fn cpu() -> oit_cpu::CpuBackend {
    oit_cpu::CpuBackend::default()
}

/// A covered pixel of `f` (the first whose reference layers hold `k`).
fn pixel_with(f: &Frame, k: u32) -> usize {
    f.layers.as_ref().unwrap().iter().position(|&l| l == k).expect("such a pixel")
}

/// `f` with one pixel's channel moved by `by` 8-bit steps.
fn skewed(f: &Frame, i: usize, by: i16) -> Frame {
    let mut g = f.clone();
    let c = &mut g.image.pixels[i][0];
    *c = (i16::from(*c) + if i16::from(*c) + by > 255 { -by } else { by }) as u8;
    g
}

#[test]
fn accounting_fails_on_an_uncounted_loss() {
    let scene = scene("planes:8");
    let s = settings(16, "fabs:4");
    let mut f = render(&cpu(), &scene, &camera(&scene, &s, FRONT), &s);
    accounting(&f).expect("fabs:4 on planes:8 accounts");
    assert!(f.stats.lost > 0);
    f.stats.captured -= 1;
    assert!(accounting(&f).is_err(), "one captured fragment dropped uncounted");
    f.stats.captured += 1;
    let px = f.lost_pixels.as_mut().expect("oit-cpu counts losses per pixel");
    let i = px.iter().position(|&l| l > 0).unwrap();
    px[i] -= 1;
    assert!(accounting(&f).is_err(), "a per-pixel count off by one");
}

/// Every backend's own guard (`Stats::check_accounting`, run on every frame whose losses are
/// counted): a frame a device cut short is refused, not shown.
#[test]
fn a_frame_cut_short_is_refused() {
    let scene = scene("planes:8");
    let s = settings(16, "fabs");
    let mut f = render(&cpu(), &scene, &camera(&scene, &s, FRONT), &s);
    f.stats.check_accounting("cpu").expect("a whole frame");
    f.stats.captured -= 3;
    let e = f.stats.check_accounting("test").unwrap_err().to_string();
    assert!(e.contains("refused"), "{e}");
}

#[test]
fn exact_fails_on_a_swap_a_drop_and_a_skew() {
    let b = cpu();
    let scene = quads(&[(0.0, RED), (-1.0, BLUE)]);
    let s = flat(16, "reference");
    let cam = camera(&scene, &s, FRONT);
    let r = render(&b, &scene, &cam, &s);
    let fabs = Settings { technique: Technique::Fabs { k: None }, ..s.clone() };
    let f = render(&b, &scene, &cam, &fabs);
    exact(&r, &f).expect("fabs is exact");
    // two layers swapped: the same quads, their depths exchanged
    let swapped = quads(&[(-1.0, RED), (0.0, BLUE)]);
    let g = render(&b, &swapped, &cam, &fabs);
    assert_eq!(g.stats.fragments, f.stats.fragments);
    assert!(exact(&r, &g).is_err(), "two layers swapped");
    // a fragment dropped (and counted: the accounting holds, exactness does not)
    let mut d = f.clone();
    d.stats.fragments -= 1;
    d.stats.captured -= 1;
    assert!(accounting(&d).is_ok() && exact(&r, &d).is_err(), "one fragment dropped");
    // a colour skewed by 2 steps on one pixel; by 1 is within EPR's rounding allowance
    let i = pixel_with(&r, 2);
    assert!(exact(&r, &skewed(&f, i, 2)).is_err(), "one channel 2 steps off");
    assert!(exact(&r, &skewed(&f, i, 1)).is_ok(), "1 step is rounding, by EPR's definition");
}

#[test]
fn never_silent_fails_when_a_loss_goes_uncounted() {
    let b = cpu();
    let scene = scene("planes:8");
    let s = settings(16, "reference");
    let cam = camera(&scene, &s, FRONT);
    let r = render(&b, &scene, &cam, &s);
    let f = render(&b, &scene, &cam, &Settings { technique: Technique::Mdts { k: Some(2) }, ..s.clone() });
    let a = accuracy(&r, &f.image).unwrap();
    assert!(a.error_pixels > 0, "mdts:2 on 8 layers is wrong somewhere");
    never_silent(&r, &f).expect("and says so");
    // the same frame, its losses taken back as captured: accounting holds, the silence shows
    let mut g = f.clone();
    g.stats.captured += g.stats.lost;
    g.stats.lost = 0;
    g.lost_pixels = None;
    assert!(accounting(&g).is_ok());
    assert!(never_silent(&r, &g).is_err(), "wrong and silent");
}

#[test]
fn errors_within_losses_fails_on_a_moved_loss_or_a_stray_error() {
    let b = cpu();
    // three quads 1/10,000 of the depth range apart share one of adp's 1,024 bins: the bin keeps
    // its nearest and farthest, the middle one is lost
    let scene = quads(&[(0.0, RED), (-1e-4, BLUE), (-2e-4, RED), (-1.0, RED)]);
    let s = flat(16, "reference");
    let cam = camera(&scene, &s, FRONT);
    let r = render(&b, &scene, &cam, &s);
    let f = render(&b, &scene, &cam, &Settings { technique: Technique::Adp, ..s.clone() });
    assert_eq!(errors_within_losses(&r, &f), Ok(true));
    let errors: Vec<usize> = error_pixels(&r.image, &f.image).collect();
    assert!(!errors.is_empty(), "adp loses the middle one of three quads sharing a bin");
    // the loss of an error pixel moved to another pixel
    let mut g = f.clone();
    let lost = g.lost_pixels.as_mut().unwrap();
    let i = errors[0];
    let j = (0..lost.len()).find(|&j| lost[j] == 0).unwrap();
    lost[j] = lost[i];
    lost[i] = 0;
    let pixels = lost.len();
    assert!(accounting(&g).is_ok(), "the count still sums");
    assert!(errors_within_losses(&r, &g).is_err(), "an error pixel with no loss");
    // an error drawn where nothing was lost
    let k =
        (0..pixels).find(|&k| f.lost_pixels.as_ref().unwrap()[k] == 0 && r.layers.as_ref().unwrap()[k] > 0);
    let k = k.expect("a covered pixel without loss");
    assert!(errors_within_losses(&r, &skewed(&f, k, 3)).is_err(), "a stray error");
}

#[test]
fn same_fragments_fails_on_a_dropped_fragment_or_a_skew() {
    let b = cpu();
    let scene = scene("spheres:3");
    let s = settings(32, "reference");
    let cam = camera(&scene, &s, oit_core::View::default());
    let f = render(&b, &scene, &cam, &s);
    same_fragments(&f, &f.clone()).expect("a frame equals itself");
    let i = pixel_with(&f, 2);
    let mut g = f.clone();
    g.layers.as_mut().unwrap()[i] -= 1;
    assert!(same_fragments(&f, &g).is_err(), "one pixel one fragment short");
    let mut g = f.clone();
    g.stats.lost += 1;
    assert!(same_fragments(&f, &g).is_err(), "one more lost");
    assert!(same_fragments(&f, &skewed(&f, i, 2)).is_err(), "a channel 2 steps off");
    assert!(same_fragments(&f, &skewed(&f, i, 1)).is_ok(), "1 step is float order");
}

#[test]
fn off_edges_equal_fails_off_the_edges_only() {
    let b = cpu();
    let scene = quads(&[(0.0, RED), (-1.0, BLUE)]);
    let s = flat(32, "reference");
    let cam = camera(&scene, &s, FRONT);
    let f = render(&b, &scene, &cam, &s);
    let mask = edge_mask(&scene, &cam, 32, 32, 1.0);
    let on = mask.iter().position(|&m| m).expect("the quads have edges in view");
    let off =
        (0..mask.len()).find(|&i| !mask[i] && f.layers.as_ref().unwrap()[i] == 2).expect("an inner pixel");
    // the quad's inner pixels are far from every edge; its border and diagonal are on them
    assert!(mask.iter().filter(|&&m| !m).count() > mask.len() / 4, "the mask leaves most pixels");
    off_edges_equal(&f.image, &f.image, &mask).expect("equal");
    assert!(off_edges_equal(&f.image, &skewed(&f, on, 50).image, &mask).is_ok(), "an edge pixel may differ");
    assert!(off_edges_equal(&f.image, &skewed(&f, off, 2).image, &mask).is_err(), "an inner pixel may not");
}

#[test]
fn metrics_count_what_is_drawn_outside_the_reference() {
    let b = cpu();
    let scene = quads(&[(0.0, RED)]);
    let s = Settings { width: 32, height: 32, ..flat(32, "reference") };
    let cam =
        oit_core::Camera::look_at(Vec3::new(3.0, 0.0, 3.0), Vec3::new(3.0, 0.0, 0.0), 45.0, 1.0, 0.1, 10.0);
    // the quad is out of view: nothing covered, nothing to measure (not a perfect score)
    let r = render(&b, &scene, &cam, &s);
    assert_eq!(r.stats.fragments, 0);
    let a = accuracy(&r, &r.image).unwrap();
    assert!(!a.is_measured() && a.epr.is_nan(), "zero coverage is unmeasured, not EPR 0");
    // garbage drawn where the reference is empty is an error pixel
    let g = skewed(&r, 5, 40);
    let a = accuracy(&r, &g.image).unwrap();
    assert_eq!((a.covered, a.error_pixels, a.covered_by_image_only), (1, 1, 1));
    assert_eq!(a.epr, 1.0);
}

// ---------------------------------------------------------------------------------------------
// Mutations of production code (issue 41.10)

/// The backends the bodies below run on: oit-cpu, and oit-wgpu where a device opens (its compute
/// path, or `path`), each with its label.
fn production(test: &str, path: oit_core::RasterPath) -> Vec<(String, Box<dyn Backend>, Settings)> {
    let mut out: Vec<(String, Box<dyn Backend>, Settings)> =
        vec![("cpu".into(), Box::new(cpu()), Settings::default())];
    if let Some(w) = oit_wgpu::backend_or_skip(test) {
        out.push((
            format!("wgpu/{path}"),
            Box::new(w),
            Settings { raster: Some(path), ..Settings::default() },
        ));
    }
    out
}

/// `settings` with the raster path of `on`'s.
fn on(on: &Settings, s: Settings) -> Settings {
    Settings { raster: on.raster, ..s }
}

/// `fabs:3` on `planes:8` overflows, and counts every fragment it drops: `checks::accounting`
/// (and the frame's own `Stats::check_accounting`, on every backend).
#[test]
fn body_fabs_overflow_accounts() {
    let scene = scene("planes:8");
    for (who, b, path) in production("body_fabs_overflow_accounts", oit_core::RasterPath::Compute) {
        let s = on(&path, settings(16, "fabs:3"));
        let f = b.render(&scene, &camera(&scene, &s, FRONT), &s).unwrap_or_else(|e| panic!("{who}: {e}"));
        accounting(&f).unwrap_or_else(|e| panic!("{who}: checks::accounting: {e}"));
        assert!(f.stats.lost > 0, "{who}: 8 layers in 3 slots");
    }
}

/// `fabs` orders equal depths by primitive id, as the reference does: `checks::exact` on
/// `ties:5` in both primitive orders.
#[test]
fn body_fabs_orders_ties_as_the_reference() {
    let tied = scene("ties:5");
    let mut reversed = tied.clone();
    reversed.instances.reverse();
    for (who, b, path) in production("body_fabs_orders_ties_as_the_reference", oit_core::RasterPath::Compute)
    {
        for scene in [&tied, &reversed] {
            let s = on(&path, flat(32, "reference"));
            let cam = camera(scene, &s, FRONT);
            let r = b.render(scene, &cam, &s).unwrap_or_else(|e| panic!("{who}: {e}"));
            let f = b.render(scene, &cam, &Settings { technique: Technique::Fabs { k: None }, ..s.clone() });
            let f = f.unwrap_or_else(|e| panic!("{who}: {e}"));
            exact(&r, &f).unwrap_or_else(|e| panic!("{who}: checks::exact: {e}"));
        }
    }
}

/// `fabs:3` on `planes:8` is wrong where a pixel holds more than 3 layers, and its error pixels
/// are those that lost a fragment: `checks::errors_within_losses` (oit-cpu: the mutation is of
/// the frame's per-pixel losses, `technique::frame`).
#[test]
fn body_losses_lie_where_the_errors_are() {
    let b = cpu();
    let scene = scene("planes:8");
    let s = settings(16, "reference");
    let cam = camera(&scene, &s, FRONT);
    let r = render(&b, &scene, &cam, &s);
    let f = render(&b, &scene, &cam, &Settings { technique: Technique::Fabs { k: Some(3) }, ..s.clone() });
    assert!(error_pixels(&r.image, &f.image).nth(1).is_some(), "fabs:3 is wrong at more than one pixel");
    assert_eq!(errors_within_losses(&r, &f), Ok(true), "cpu: checks::errors_within_losses");
}

/// `plain` on wgpu's hardware path (the blender) counts its fragments apart from what it
/// composites, and the two agree: `checks::accounting` (and the frame's `Stats::check_accounting`).
#[test]
fn body_blended_plain_accounts() {
    let scene = scene("planes:8");
    let Some(w) = oit_wgpu::backend_or_skip("body_blended_plain_accounts") else { return };
    let s = Settings { raster: Some(oit_core::RasterPath::Hardware), ..settings(16, "plain") };
    let f = w.render(&scene, &camera(&scene, &s, FRONT), &s).unwrap_or_else(|e| panic!("wgpu/hardware: {e}"));
    assert!(f.stats.fragments > 0 && f.stats.captured > 0, "wgpu/hardware: {:?}", f.stats);
    accounting(&f).unwrap_or_else(|e| panic!("wgpu/hardware: checks::accounting: {e}"));
}

/// `fabs` on `ties:5` is never wrong in silence: `checks::never_silent` (every error pixel a
/// counted loss, tail or tie; here none).
#[test]
fn body_fabs_is_never_silent_on_ties() {
    let b = cpu();
    let scene = scene("ties:5");
    let s = flat(32, "reference");
    let cam = camera(&scene, &s, FRONT);
    let r = render(&b, &scene, &cam, &s);
    let f = render(&b, &scene, &cam, &Settings { technique: Technique::Fabs { k: None }, ..s.clone() });
    never_silent(&r, &f).unwrap_or_else(|e| panic!("cpu: checks::never_silent: {e}"));
}

/// wgpu's compute path and oit-cpu run the same fixed-point rules: `fabs` on `ties:5` gives the
/// same fragments, counts and image on both (`checks::same_fragments_as_cpu`).
#[test]
fn body_compute_fabs_is_the_cpus() {
    let Some(w) = oit_wgpu::backend_or_skip("body_compute_fabs_is_the_cpus") else { return };
    let scene = scene("ties:5");
    let s = Settings { raster: Some(oit_core::RasterPath::Compute), ..flat(32, "fabs") };
    let cam = camera(&scene, &s, FRONT);
    let g = w.render(&scene, &cam, &s).unwrap_or_else(|e| panic!("wgpu/compute: {e}"));
    let c = render(&cpu(), &scene, &cam, &Settings { raster: None, ..s.clone() });
    same_fragments_as_cpu(&g, &c, Technique::Fabs { k: None })
        .unwrap_or_else(|e| panic!("wgpu/compute against cpu: checks::same_fragments_as_cpu: {e}"));
}

/// A prepared wgpu frame of `dfb` (compute path) reports storage that is the plan's arrays at a
/// capacity holding its fragments: `checks::one_shot_storage`.
#[test]
fn body_prepared_storage_is_the_plans() {
    let Some(w) = oit_wgpu::backend_or_skip("body_prepared_storage_is_the_plans") else { return };
    let scene = scene("planes:8");
    let s = Settings { raster: Some(oit_core::RasterPath::Compute), ..settings(16, "dfb") };
    let cam = camera(&scene, &s, FRONT);
    let mut prepared = w.prepare(&scene).unwrap_or_else(|e| panic!("wgpu/compute: {e}"));
    let f = prepared.frame(&cam, &s).unwrap_or_else(|e| panic!("wgpu/compute: {e}"));
    one_shot_storage("wgpu", &scene, &s, &f.stats)
        .unwrap_or_else(|e| panic!("wgpu/compute: checks::one_shot_storage: {e}"));
}

/// Runs `body` (a test of this binary) again in a child process under `OIT_MUTATION=mutation`
/// and requires it to fail with every one of `expect` in its output.
fn fails_under(mutation: &str, body: &str, expect: &[&str]) {
    let out = std::process::Command::new(std::env::current_exe().expect("this test binary"))
        .args([body, "--exact", "--nocapture", "--test-threads=1"])
        .env(oit_core::mutation::VAR, mutation)
        .output()
        .expect("the test binary runs");
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(!out.status.success(), "{body} passed under OIT_MUTATION={mutation}:\n{text}");
    for e in expect {
        assert!(text.contains(e), "{body} failed under OIT_MUTATION={mutation}, but not with '{e}':\n{text}");
    }
}

/// oit-cpu's fabs drops a fragment past K without counting it: the frame's own accounting check
/// (`Stats::check_accounting`, which oit-cpu makes at every frame's end as the GPUs do) refuses
/// the frame, before `checks::accounting` sees it.
#[test]
fn cpu_fabs_losing_uncounted_fails_accounting() {
    fails_under(
        "cpu-fabs-lose-uncounted",
        "body_fabs_overflow_accounts",
        &["cpu: device error: cpu: ", "counted lost", "refused"],
    );
}

/// oit-wgpu's fabs shader (compute path) drops a fragment past K without counting it: the
/// frame's own accounting check (`Stats::check_accounting`, the sum `checks::accounting` holds)
/// refuses the frame.
#[test]
fn wgpu_fabs_losing_uncounted_is_refused() {
    if oit_wgpu::backend_or_skip("wgpu_fabs_losing_uncounted_is_refused").is_none() {
        return;
    }
    fails_under("wgpu-fabs-lose-uncounted", "body_fabs_overflow_accounts", &["wgpu/compute: ", "refused"]);
}

/// oit-cpu's fabs orders equal depths by descending primitive id, counting no tie:
/// `checks::exact` fails on `ties:5`.
#[test]
fn cpu_fabs_ties_reversed_fails_exact() {
    fails_under(
        "cpu-fabs-ties-reversed",
        "body_fabs_orders_ties_as_the_reference",
        &["cpu: checks::exact: ", "error pixels"],
    );
}

/// The same in oit-wgpu's fabs shader (compute path): `checks::exact` fails on `ties:5`.
#[test]
fn wgpu_fabs_ties_reversed_fails_exact() {
    if oit_wgpu::backend_or_skip("wgpu_fabs_ties_reversed_fails_exact").is_none() {
        return;
    }
    fails_under(
        "wgpu-fabs-ties-reversed",
        "body_fabs_orders_ties_as_the_reference",
        &["wgpu/compute: checks::exact: ", "error pixels"],
    );
}

/// oit-cpu counts every loss at pixel 0 (the total still right): `checks::errors_within_losses`
/// fails.
#[test]
fn cpu_losses_at_one_pixel_fail_errors_within_losses() {
    fails_under(
        "cpu-losses-at-pixel-zero",
        "body_losses_lie_where_the_errors_are",
        &["checks::errors_within_losses", "where nothing was lost"],
    );
}

/// oit-wgpu's blender counts only every other primitive's fragments: with the frame's fragments
/// counted apart (no longer `fragments := captured`), the frame's accounting check refuses it.
#[test]
fn wgpu_blend_counting_half_is_refused() {
    if oit_wgpu::backend_or_skip("wgpu_blend_counting_half_is_refused").is_none() {
        return;
    }
    fails_under("wgpu-blend-count-half", "body_blended_plain_accounts", &["wgpu/hardware: ", "refused"]);
}

/// oit-cpu's fabs orders ties backwards and counts none: `checks::never_silent` fails.
#[test]
fn cpu_fabs_ties_reversed_fails_never_silent() {
    fails_under(
        "cpu-fabs-ties-reversed",
        "body_fabs_is_never_silent_on_ties",
        &["cpu: checks::never_silent: ", "wrong in silence"],
    );
}

/// oit-cpu's fabs orders ties backwards while wgpu's compute path does not: the two no longer
/// agree, and `checks::same_fragments_as_cpu` fails on the image.
#[test]
fn cpu_fabs_ties_reversed_fails_same_fragments_as_cpu() {
    if oit_wgpu::backend_or_skip("cpu_fabs_ties_reversed_fails_same_fragments_as_cpu").is_none() {
        return;
    }
    fails_under(
        "cpu-fabs-ties-reversed",
        "body_compute_fabs_is_the_cpus",
        &["checks::same_fragments_as_cpu: "],
    );
}

/// oit-wgpu reports a word less storage than it allocated: `checks::one_shot_storage` refuses it.
#[test]
fn wgpu_storage_short_fails_one_shot_storage() {
    if oit_wgpu::backend_or_skip("wgpu_storage_short_fails_one_shot_storage").is_none() {
        return;
    }
    fails_under(
        "wgpu-storage-short",
        "body_prepared_storage_is_the_plans",
        &["checks::one_shot_storage: ", "is not the plan's arrays"],
    );
}
