//! Issue 16: `lost` is counted where each fragment is lost (bucket collisions, array overflow,
//! coplanar ties a peel skips, the tail behind the last peel `--max-peels` allows, adp's shared
//! bins), so `captured + lost == fragments` is a check, not an identity (`captured + merged + lost`
//! where `--overflow tail` merges what `fabs:K`, `mdts:K`, `mdts64:K` have no room for: run with
//! both overflows). Run for every technique on every backend × raster path, on scenes where each
//! kind of loss happens.

use oit_core::{BdpMode, Overflow, Settings, View};
use oit_tests::checks::accounting;
use oit_tests::*;

/// (scene, front view?, techniques, max peels, those that must lose there (`bdp`: colour mode)).
type Case = (&'static str, bool, &'static [&'static str], Option<u32>, &'static [&'static str]);

const CASES: &[Case] = &[
    (
        "knot",
        false,
        &[
            "reference",
            "plain",
            "wavg",
            "wsum",
            "wboit",
            "mboit",
            "mboit:6",
            "dp",
            "ddp",
            "bdp",
            "bdp2",
            "adp",
            "fabs:2",
            "mdts:2",
            "mdts64:2",
            "mlp:2",
            "dfb",
            "ll",
        ],
        None,
        &["bdp", "fabs:2", "mdts:2", "mdts64:2"],
    ),
    ("coplanar", true, &["dp", "ddp", "mlp:1", "mlp:2", "bdp2", "fabs:2", "dfb", "ll"], None, &["dp"]),
    (
        "ties:4",
        true,
        &["dp", "ddp", "mlp:1", "mlp:3", "bdp2", "mdts64:2", "fabs:2", "dfb", "ll"],
        None,
        &["dp", "ddp", "mlp:1"],
    ),
    (
        "planes:8",
        true,
        &["dp", "ddp", "mlp:1", "mlp:3", "adp", "bdp2"],
        Some(2),
        &["dp", "ddp", "mlp:1", "mlp:3"],
    ),
    (
        "planes:2000",
        true,
        &["adp", "fabs:4", "mdts64:4", "mlp:16", "dfb", "ll"],
        None,
        &["adp", "fabs:4", "mdts64:4"],
    ),
];

#[test]
fn captured_plus_lost_is_fragments() {
    for backend in backends_for("captured_plus_lost_is_fragments") {
        let b = backend.as_ref();
        eprintln!("on {}", label(b));
        for &(name, front, techniques, max_peels, must_lose) in CASES {
            let scene = scene(name);
            let size = if name == "planes:2000" { 8 } else { 48 };
            for &t in techniques {
                for (bdp_mode, overflow) in [
                    (BdpMode::Color, Overflow::Drop),
                    (BdpMode::Depth, Overflow::Drop),
                    (BdpMode::Depth, Overflow::Tail),
                ] {
                    if bdp_mode == BdpMode::Color && t != "bdp" {
                        continue;
                    }
                    let fixed = (t.starts_with("fabs:") || t.starts_with("mdts")) && t.contains(':');
                    if overflow == Overflow::Tail && !fixed {
                        continue;
                    }
                    let s = Settings { max_peels, bdp_mode, overflow, ..settings(size, t) };
                    let view = if front { FRONT } else { View::default() };
                    let f = render(b, &scene, &camera(&scene, &s, view), &s);
                    let what = format!(
                        "{} {t} ({bdp_mode:?}, {overflow:?}) on {name}, max peels {max_peels:?}",
                        label(b)
                    );
                    accounting(&f).unwrap_or_else(|e| panic!("{what}: {e}"));
                    if must_lose.contains(&t) && !(t == "bdp" && bdp_mode == BdpMode::Depth) {
                        let counted = if overflow == Overflow::Tail { f.stats.merged } else { f.stats.lost };
                        assert!(counted > 0, "{what}: the case is meant to lose (or merge) fragments");
                    }
                }
            }
        }
    }
}

// The check failing on an uncounted loss: `mutations.rs`.
