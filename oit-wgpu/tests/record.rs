//! `OitPass::record`: a frame recorded into the caller's encoder, submitted by the caller, with
//! nothing read back in between, against the same pass's `OitPass::frame` (which reads back).
//! Same device, same draws, same schedule: the images must be equal byte for byte and the stats
//! (read once, after the caller's submit) equal, fabs's gated overflow passes and the tails'
//! included; a technique that needs a round trip in mid-frame is refused, naming `frame`; a
//! second recorded frame creates no buffer.

use oit_core::{OitError, Overflow, Settings, Stats, Technique};

#[path = "../examples/embed.rs"]
#[expect(dead_code, reason = "the example's `main` is not called here")]
mod example;

/// What a recorded frame runs (the rest must be refused).
const RECORDABLE: &[&str] = &[
    "fabs:2",
    "fabs:16",
    "mdts64:2",
    "mdts64:16",
    "wavg",
    "wsum",
    "wboit",
    "mboit:4",
    "mboit:6",
    "bdp",
    "bdp:2",
    "bdp2",
];

/// The stats both ways must agree on (times aside; `lost_pixels` is not kept when recording).
fn key(s: &Stats) -> [u64; 8] {
    [
        s.fragments,
        s.captured,
        s.lost,
        s.merged,
        s.tied,
        u64::from(s.geometry_passes),
        u64::from(s.max_layers),
        s.storage_bytes,
    ]
}

fn record_once(
    user: &example::User,
    pass: &oit_wgpu::OitPass,
    view: &wgpu::TextureView,
) -> Result<oit_wgpu::Recorded, OitError> {
    let mut encoder = user.device.create_command_encoder(&Default::default());
    let recorded = pass.record(&mut encoder, view, |c| user.pipeline(c), |r, p| user.draw(r, p));
    // the caller submits, whether or not oit recorded anything
    user.queue.submit([encoder.finish()]);
    recorded
}

#[test]
fn a_recorded_frame_equals_the_read_back_frame() {
    if oit_wgpu::backend_or_skip("a_recorded_frame_equals_the_read_back_frame").is_none() {
        return;
    }
    let user = example::User::new(wgpu::TextureFormat::Rgba8Unorm).unwrap();
    let view = user.target.create_view(&Default::default());
    let mut all: Vec<String> = RECORDABLE.iter().map(ToString::to_string).collect();
    all.extend(Technique::all().iter().map(ToString::to_string));
    let mut overflowed = false;
    for t in &all {
        let technique: Technique = t.parse().unwrap();
        let fixed = matches!(technique, Technique::Fabs { k: Some(_) } | Technique::Mdts64 { k: Some(_) });
        let overflows: &[Overflow] =
            if fixed { &[Overflow::Drop, Overflow::Tail] } else { &[Overflow::Drop] };
        for &overflow in overflows {
            let mut pass = user.pass(technique, example::camera()).unwrap();
            let settings = Settings { overflow, ..pass.settings().clone() };
            pass.set_view(settings, example::camera()).unwrap();
            let frame = match pass.frame(None, |c| user.pipeline(c), |r, p| user.draw(r, p)) {
                Ok(f) => f,
                // refused by the embedded pass itself (mdts without an alpha): not this test's
                Err(OitError::Unsupported { .. }) => continue,
                Err(e) => panic!("{t}: {e}"),
            };
            let recorded = match record_once(&user, &pass, &view) {
                Err(OitError::Unsupported { what, .. }) => {
                    assert!(
                        !RECORDABLE.contains(&t.as_str()),
                        "{t} is listed as recordable but was refused: {what}"
                    );
                    assert!(what.contains("OitPass::frame"), "{t}: the refusal names the way out: {what}");
                    println!("{t}: refused ({what})");
                    continue;
                }
                r => {
                    assert!(RECORDABLE.contains(&t.as_str()), "{t} was recorded: add it to RECORDABLE");
                    r.unwrap()
                }
            };
            let image = user.read_target().unwrap();
            assert_eq!(image.pixels, frame.image.pixels, "{t} {overflow:?}: the recorded image");
            let stats = pass.read_stats().unwrap();
            println!(
                "{t} {overflow:?}: {} passes recorded ({} gated), {} ran; fragments {}, lost {}, merged {}",
                recorded.geometry_passes,
                recorded.gated_passes,
                stats.geometry_passes,
                stats.fragments,
                stats.lost,
                stats.merged
            );
            assert_eq!(key(&stats), key(&frame.stats), "{t} {overflow:?}: stats (recorded, read back)");
            assert!(stats.fragments > 0, "{t}: the scene is drawn");
            overflowed |= recorded.gated_passes > 0
                && stats.geometry_passes > recorded.geometry_passes - recorded.gated_passes;
            // a second frame of the same size and technique creates no buffer
            let before = pass.allocations();
            record_once(&user, &pass, &view).unwrap();
            assert_eq!(key(&pass.read_stats().unwrap()), key(&frame.stats), "{t}: the second recorded frame");
            assert_eq!(pass.allocations(), before, "{t} {overflow:?}: the second recorded frame allocated");
        }
    }
    // fabs:2 and mdts64:2 overflow on the quads (three layers): the gated passes ran somewhere
    assert!(overflowed, "no gated pass ran: the test did not exercise them");
}

/// The image drawn into sRGB and BGRA targets stores the same bytes as into an `Rgba8Unorm` one.
#[test]
fn a_recorded_frame_draws_into_srgb_and_bgra_targets() {
    if oit_wgpu::backend_or_skip("a_recorded_frame_draws_into_srgb_and_bgra_targets").is_none() {
        return;
    }
    let technique = Technique::Fabs { k: Some(4) };
    let reference = {
        let user = example::User::new(wgpu::TextureFormat::Rgba8Unorm).unwrap();
        let pass = user.pass(technique, example::camera()).unwrap();
        pass.frame(None, |c| user.pipeline(c), |r, p| user.draw(r, p)).unwrap().image
    };
    for format in [
        wgpu::TextureFormat::Rgba8UnormSrgb,
        wgpu::TextureFormat::Bgra8Unorm,
        wgpu::TextureFormat::Bgra8UnormSrgb,
    ] {
        let user = example::User::new(format).unwrap();
        let pass = user.pass(technique, example::camera()).unwrap();
        let view = user.target.create_view(&Default::default());
        record_once(&user, &pass, &view).unwrap();
        let image = user.read_target().unwrap();
        let worst = image
            .pixels
            .iter()
            .zip(&reference.pixels)
            .map(|(a, b)| (0..4).map(|i| a[i].abs_diff(b[i])).max().unwrap_or(0))
            .max()
            .unwrap_or(0);
        println!("{format:?}: worst byte difference {worst}");
        assert_eq!(worst, 0, "{format:?}: the target holds other bytes than the frame's image");
    }
}

/// The example's frame loop: a moving camera, recorded frames; the pass creates nothing after the
/// first frame.
#[test]
fn the_frame_loop_allocates_nothing_after_its_first_frame() {
    if oit_wgpu::backend_or_skip("the_frame_loop_allocates_nothing_after_its_first_frame").is_none() {
        return;
    }
    let (fps, warm, end) = example::frame_loop(Technique::Fabs { k: Some(8) }, 8).unwrap();
    println!("fabs:8 frame loop: {fps:.1} fps, buffers {warm} after the first frame, {end} at the end");
    assert!(fps > 0.0);
    assert_eq!(warm, end, "the loop created buffers after its first frame");
    // a technique with a mid-frame round trip is refused by the loop, not run wrong
    assert!(matches!(example::frame_loop(Technique::Dp, 2), Err(OitError::Unsupported { .. })));
}
