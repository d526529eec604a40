//! The suite's checks, one function per family, each returning what is wrong (or `Ok`), so the
//! conformance bodies assert them and `tests/tests/mutations.rs` shows each one failing on a
//! deliberately broken frame (a dropped fragment, two layers swapped, a skewed colour, a loss
//! moved or uncounted). A check that no mutation can fail would not be a check.

use oit_core::metrics::{accuracy, differ_off_mask};
use oit_core::{Frame, Image};

/// Pixels whose 8-bit colour differs by more than 1 in a channel (EPR's error pixels).
pub fn error_pixels<'a>(a: &'a Image, b: &'a Image) -> impl Iterator<Item = usize> + 'a {
    a.pixels
        .iter()
        .zip(&b.pixels)
        .enumerate()
        .filter(|(_, (p, q))| (0..3).any(|c| p[c].abs_diff(q[c]) > 1))
        .map(|(i, _)| i)
}

/// Losses are counted where they happen: `captured + merged + lost + occluded == fragments`
/// (`merged`: the fragments `--overflow tail` merged into a pixel's tail, 0 elsewhere;
/// `occluded`: those behind the opaque depth, 0 without opaque parts), and the per-pixel losses
/// (where the backend reports them) sum to `lost`.
pub fn accounting(f: &Frame) -> Result<(), String> {
    let s = &f.stats;
    if s.captured + s.merged + s.lost + s.occluded != s.fragments {
        return Err(format!(
            "captured {} + merged {} + lost {} + occluded {} != fragments {}",
            s.captured, s.merged, s.lost, s.occluded, s.fragments
        ));
    }
    if let Some(px) = &f.lost_pixels {
        let sum: u64 = px.iter().map(|&l| u64::from(l)).sum();
        if sum != s.lost {
            return Err(format!("per-pixel lost sums to {sum}, stats.lost is {}", s.lost));
        }
    }
    Ok(())
}

/// A GPU hardware path's `occluded` against oit-cpu's: within 1 % of the frame's fragments (the
/// device's rasterizer places fragments where a surface meets the opaque depth a little
/// differently from oit-cpu's fixed-point rule).
pub fn occluded_near(gpu: &Frame, cpu: &Frame) -> Result<(), String> {
    let slack = cpu.stats.fragments / 100;
    if gpu.stats.occluded.abs_diff(cpu.stats.occluded) <= slack {
        return Ok(());
    }
    Err(format!("occluded {} vs the CPU's {} (slack {slack})", gpu.stats.occluded, cpu.stats.occluded))
}

/// An exact technique's frame against the reference of the same backend: the same fragments,
/// none lost or tied, and not one error pixel over a measured (covered) frame.
pub fn exact(reference: &Frame, f: &Frame) -> Result<(), String> {
    accounting(f)?;
    let a = accuracy(reference, &f.image).map_err(|e| e.to_string())?;
    let s = &f.stats;
    if !a.is_measured() {
        return Err("nothing covered: no accuracy to hold".into());
    }
    if s.fragments != reference.stats.fragments {
        return Err(format!("{} fragments, the reference {}", s.fragments, reference.stats.fragments));
    }
    if (a.error_pixels, s.lost, s.tied) != (0, 0, 0) {
        return Err(format!("{} error pixels, lost {}, tied {}", a.error_pixels, s.lost, s.tied));
    }
    Ok(())
}

/// Never wrong in silence: where a frame differs from the reference, it counted at least as many
/// lost, merged or tied fragments as it has error pixels (each error pixel holds a loss, a tail or
/// a tie).
pub fn never_silent(reference: &Frame, f: &Frame) -> Result<(), String> {
    accounting(f)?;
    let a = accuracy(reference, &f.image).map_err(|e| e.to_string())?;
    let counted = f.stats.tied + f.stats.lost + f.stats.merged;
    if a.error_pixels > counted {
        return Err(format!(
            "{} error pixels but only {} tied + {} lost + {} merged: wrong in silence",
            a.error_pixels, f.stats.tied, f.stats.lost, f.stats.merged
        ));
    }
    Ok(())
}

/// For techniques whose only error is loss (bdp's depth mode, adp): every error pixel lost a
/// fragment, per the frame's loss mask. `Ok(false)` where the backend reports no per-pixel
/// losses (nothing to hold), `Ok(true)` where it held.
pub fn errors_within_losses(reference: &Frame, f: &Frame) -> Result<bool, String> {
    let Some(lost) = &f.lost_pixels else { return Ok(false) };
    let stray: Vec<usize> = error_pixels(&reference.image, &f.image).filter(|&i| lost[i] == 0).collect();
    if !stray.is_empty() {
        return Err(format!("{} error pixels where nothing was lost (first {:?})", stray.len(), &stray[..1]));
    }
    Ok(true)
}

/// A GPU backend's storage (`gpu`, from the backend named `backend`) against oit-cpu's (`cpu`)
/// for the same frame (`scene`, `settings`): the same arrays, the per-fragment ones (`dfb`, `ll`,
/// the reference) allocated by the GPU at the plan's capacity of the count
/// ([`oit_core::plan::Plan::fragment_capacity`]), by oit-cpu at the count itself. The difference
/// is computed by the plan (its figure for the GPU less its figure at the exact count), not
/// assumed: a GPU array allocated past its capacity, or reported as the count, fails.
pub fn same_storage_as_cpu(
    backend: &str,
    gpu: &Frame,
    cpu: &Frame,
    scene: &oit_core::Scene,
    settings: &oit_core::Settings,
) -> Result<(), String> {
    use oit_core::plan::{Counted, Plan};
    let plan = Plan::new(backend, scene, settings).map_err(|e| e.to_string())?;
    let exact = Plan { pooled: false, ..plan.clone() };
    let pixels = u64::from(settings.width) * u64::from(settings.height);
    // the count oit-cpu allocated its per-fragment arrays for, from its storage and the plan
    let (base, per_fragment) = fragment_arrays(&plan, pixels);
    let n = cpu.stats.storage_bytes.saturating_sub(base).checked_div(per_fragment).unwrap_or(0);
    let counted = Counted { deepest: 0, fragments: n };
    let slack = plan.storage_bytes(pixels, counted) - exact.storage_bytes(pixels, counted);
    if gpu.stats.storage_bytes != cpu.stats.storage_bytes + slack {
        return Err(format!(
            "storage: {} on {backend}, {} on cpu + {slack} of size-class capacity",
            gpu.stats.storage_bytes, cpu.stats.storage_bytes
        ));
    }
    Ok(())
}

/// The bytes of `plan`'s arrays at no fragment (as `Stats::storage_bytes` counts them: without
/// the resolve state) and the bytes its per-fragment arrays take a fragment (0 where it has none).
fn fragment_arrays(plan: &oit_core::plan::Plan, pixels: u64) -> (u64, u64) {
    use oit_core::plan::{Counted, RESOLVE_STATE_BYTES};
    let base = plan.storage_bytes(pixels, Counted::default()) - pixels * RESOLVE_STATE_BYTES;
    let per_fragment = plan.arrays(Counted::default()).iter().map(|a| a.per_fragment * a.element_bytes).sum();
    (base, per_fragment)
}

/// The storage a one-shot frame of the same view reports, from a prepared scene's frame `stats`
/// (backend `backend`, `scene`, `settings`): the frame's own where the plan sizes nothing by the
/// fragment total; for `dfb`, `ll` and the reference, whose frame may keep the capacity an earlier
/// frame of another view took (the GPU backends' speculation, `Plan::fragment_capacity`), the
/// frame's storage with its capacity replaced by its own count's, after checking that the
/// capacity it allocated holds its count (an error where it does not, or where the storage is
/// not the plan's arrays at some capacity). For comparing frames of different histories.
pub fn one_shot_storage(
    backend: &str,
    scene: &oit_core::Scene,
    settings: &oit_core::Settings,
    stats: &oit_core::Stats,
) -> Result<u64, String> {
    let plan = oit_core::plan::Plan::new(backend, scene, settings).map_err(|e| e.to_string())?;
    let pixels = u64::from(settings.width) * u64::from(settings.height);
    let (base, per_fragment) = fragment_arrays(&plan, pixels);
    if per_fragment == 0 {
        return Ok(stats.storage_bytes);
    }
    let held = stats.storage_bytes.checked_sub(base).ok_or("storage under the plan's per-pixel arrays")?;
    let capacity = held / per_fragment;
    if !held.is_multiple_of(per_fragment) || capacity < stats.fragments {
        return Err(format!(
            "storage {} is not the plan's arrays at a capacity holding {} fragments ({} per fragment over {base})",
            stats.storage_bytes, stats.fragments, per_fragment
        ));
    }
    Ok(base + per_fragment * plan.fragment_capacity(stats.fragments))
}

/// Two backends/paths with the same fixed-point rules (oit-cpu and a compute path): the same
/// fragments, losses, ties and passes, the same per-pixel counts where both report them, and no
/// channel off by more than 1 (the order of float operations may differ).
pub fn same_fragments(a: &Frame, b: &Frame) -> Result<(), String> {
    same_fragments_but_passes(a, b, 0)
}

/// A compute path's frame `gpu` against oit-cpu's `cpu` of `technique`: [`same_fragments`], but
/// for `plain`, which oit-cpu composites as each pixel's fragments come, in order (the plan's
/// `in_order`: one pass), where a compute path counts first, then keeps and sorts them (two).
pub fn same_fragments_as_cpu(gpu: &Frame, cpu: &Frame, technique: oit_core::Technique) -> Result<(), String> {
    same_fragments_but_passes(gpu, cpu, u32::from(technique == oit_core::Technique::Plain))
}

/// [`same_fragments_as_cpu`] on `scene`, whose opaque pass oit-cpu may run as one geometry pass
/// where the GPU paths run two ([`oit_cpu::CpuBackend::opaque_passes`]: a textured mask's depth
/// test shades every fragment ahead, so keeps the winners' colours without a second pass).
#[cfg(feature = "cpu")]
pub fn same_fragments_as_cpu_on(
    scene: &oit_core::Scene,
    gpu: &Frame,
    cpu: &Frame,
    technique: oit_core::Technique,
) -> Result<(), String> {
    let opaque_fewer = match oit_cpu::CpuBackend::opaque_passes(scene) {
        0 => 0,
        n => 2 - n,
    };
    let plain = u32::from(technique == oit_core::Technique::Plain);
    same_fragments_but_passes(gpu, cpu, plain + opaque_fewer * cpu.stats.tiles.max(1))
}

/// [`same_fragments`] where `b` runs `fewer` geometry passes than `a`.
pub fn same_fragments_but_passes(a: &Frame, b: &Frame, fewer: u32) -> Result<(), String> {
    let (x, y) = (&a.stats, &b.stats);
    let pairs = [
        ("fragments", x.fragments, y.fragments),
        ("lost", x.lost, y.lost),
        ("merged", x.merged, y.merged),
        ("tied", x.tied, y.tied),
        ("quantized", x.quantized, y.quantized),
        ("passes", u64::from(x.geometry_passes), u64::from(y.geometry_passes) + u64::from(fewer)),
    ];
    for (what, p, q) in pairs {
        if p != q {
            return Err(format!("{what}: {p} vs {q}"));
        }
    }
    if let (Some(p), Some(q)) = (&a.layers, &b.layers)
        && let Some(i) = p.iter().zip(q).position(|(m, n)| m != n)
    {
        return Err(format!("pixel {i}: {} vs {} fragments", p[i], q[i]));
    }
    off_edges_equal(&a.image, &b.image, &vec![false; a.image.pixels.len()])
}

/// A hardware path against a path with oit's rules: equal (within 1 of 8 bits) on every pixel
/// `edges` leaves out (pixels more than a pixel from every projected triangle edge).
pub fn off_edges_equal(a: &Image, b: &Image, edges: &[bool]) -> Result<(), String> {
    if a.pixels.len() != b.pixels.len() || edges.len() != a.pixels.len() {
        return Err("image sizes differ".into());
    }
    let (worst, differ) = differ_off_mask(a, b, edges);
    if worst > 1 {
        return Err(format!("{differ} pixels off the edges differ, by up to {worst}"));
    }
    Ok(())
}

/// How far from a projected triangle edge, in pixels, two rasterizers may disagree on a pixel's
/// coverage: Vulkan's rasterizers snap vertices to at least 4 sub-pixel bits (1/16 pixel; oit's
/// rules and the GPUs measured here snap to 1/256), so a pixel centre farther than 1/16 pixel
/// from every edge is covered by the same triangles on both.
pub const COVERAGE_SNAP: f32 = 1.0 / 16.0;

/// A hardware path against a path with oit's rules on the pixels they cover alike: `a_layers`
/// and `b_layers` are each path's per-pixel fragment counts (the reference's `layers`), `near`
/// the pixels whose centre lies within [`COVERAGE_SNAP`] of a projected edge. Every pixel whose
/// counts differ must be one of `near` (the rasterizers may disagree there and nowhere else), and
/// every other pixel, covered by the same fragments on both paths, must have the same colour
/// within 1 of 8 bits. A pixel of `near` whose counts agree is not compared: on an edge two
/// triangles share, one rasterizer may give the pixel to either, the same count from another
/// triangle. Unlike [`off_edges_equal`], whose one-pixel mask leaves out nearly every pixel of a
/// mesh of small triangles (the bunny at 64²), this compares every pixel but those within a snap
/// of an edge. Returns (pixels compared, pixels whose counts differ).
pub fn covered_alike_equal(
    a: &Image,
    b: &Image,
    a_layers: &[u32],
    b_layers: &[u32],
    near: &[bool],
) -> Result<(usize, usize), String> {
    let n = a.pixels.len();
    if b.pixels.len() != n || a_layers.len() != n || b_layers.len() != n || near.len() != n {
        return Err("image sizes differ".into());
    }
    let moved: Vec<usize> = (0..n).filter(|&i| a_layers[i] != b_layers[i]).collect();
    if let Some(&far) = moved.iter().find(|&&i| !near[i]) {
        return Err(format!(
            "{} pixels' fragment counts differ, pixel {far} ({} against {}) farther than {COVERAGE_SNAP} pixel from every edge",
            moved.len(),
            a_layers[far],
            b_layers[far]
        ));
    }
    let (worst, differ) = differ_off_mask(a, b, near);
    if worst > 1 {
        return Err(format!("{differ} pixels covered alike differ in colour, by up to {worst}"));
    }
    Ok((near.iter().filter(|&&m| !m).count(), moved.len()))
}
