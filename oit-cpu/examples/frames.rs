//! Steady-state frames of one technique on one scene, for a profiler (`perf record`) or a quick
//! look at a frame's wall time: the scene prepared once, a few warm-up frames, then `N` timed
//! frames through [`Prepared::frame`], the median printed.
//!
//! `cargo run --release -p oit-cpu --example frames -- bunny ddp 512 50`

use std::time::Instant;

use oit_core::{Backend, Camera, Settings, Technique, View, load_scene};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scene_name = args.first().map_or("bunny", String::as_str);
    let technique: Technique = args.get(1).map_or("plain", String::as_str).parse()?;
    let size: u32 = args.get(2).map_or(Ok(512), |s| s.parse())?;
    let frames: usize = args.get(3).map_or(Ok(20), |s| s.parse())?;
    let scene = load_scene(scene_name)?;
    let camera = Camera::orbit_scene(&scene, View::default(), 1.0)?;
    let settings = Settings { width: size, height: size, technique, ..Settings::default() };
    let backend = oit_cpu::CpuBackend::default();
    let mut prepared = backend.prepare(&scene)?;
    for _ in 0..2 {
        prepared.frame(&camera, &settings)?;
    }
    let mut times = Vec::with_capacity(frames);
    let mut passes = 0;
    for _ in 0..frames {
        let start = Instant::now();
        let frame = prepared.frame(&camera, &settings)?;
        times.push(start.elapsed().as_secs_f64() * 1e3);
        passes = frame.stats.geometry_passes;
    }
    times.sort_by(f64::total_cmp);
    let median = times.get(times.len() / 2).copied().unwrap_or(f64::NAN);
    println!("{scene_name} {technique} {size}²: {passes} passes, median {median:.2} ms over {frames} frames");
    Ok(())
}
