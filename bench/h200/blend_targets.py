#!/usr/bin/env python3
"""Issue 10's rate targets from `oit bench ... --blend-targets f16,unorm8` report.json files (one
per backend, or one holding several): per scene and backend, GPU ms of plain blending into each
target, of wavg on the hardware path (atomics; blend into RGBA32F; blend into RGBA16F) and of the
exact techniques, and the ratios the targets name:

- exact rate / plain-blending rate = plain ms / exact ms (target >= 1.5), against the fastest plain
  blend measured (RGBA8), and against RGBA32F;
- wavg-on-hardware rate / plain rate = plain ms / wavg ms (target >= 0.8), RGBA16F blend against
  RGBA8 and RGBA16F plain.

    blend_targets.py REPORT.json [REPORT.json ...]
"""
import json
import re
import sys

EXACT = ["fabs", "ll", "dfb", "mdts"]


def scene_name(scene):
    """A scene expression without the folders and `.obj` of the paths older reports name meshes by
    (`grid:4x4:DIR/bunny.obj` is `grid:4x4:bunny`)."""
    return re.sub(r"[^:,]*/", "", scene).removesuffix(".obj")


def main(paths):
    rows = [r for p in paths for r in json.load(open(p))["rows"] if r.get("gpu_ms")]
    ms = {(r["scene"], r["backend"], r["raster"], r["technique"]): r["gpu_ms"]["median"] for r in rows}
    print("| scene | backend | plain f32 / f16 / unorm8 | wavg hw: atomics / blend f32 / blend f16 "
          "| exact (compute) | exact rate / plain unorm8 | / plain f32 | wavg f16 / plain unorm8 | / plain f16 |")
    print("|---|---|---|---|---|---|---|---|---|")
    for scene in dict.fromkeys(r["scene"] for r in rows):
        for be in dict.fromkeys(r["backend"].split("+")[0] for r in rows if r["scene"] == scene):
            g = lambda b, raster, t: ms.get((scene, b, raster, t))
            plain = [g(be, "hardware", "plain"), g(be + "+f16", "hardware", "plain"), g(be + "+unorm8", "hardware", "plain")]
            wavg = [g(be, "hardware", "wavg"), g(be + "+blend", "hardware", "wavg"), g(be + "+f16", "hardware", "wavg")]
            exact = [(t, g(be, "compute", t)) for t in EXACT if g(be, "compute", t)]
            if None in plain or None in wavg or not exact:
                continue
            t, e = min(exact, key=lambda x: x[1])
            f = lambda xs: " / ".join(f"{x:.2f}" for x in xs)
            print(f"| {scene_name(scene)} | {be} | {f(plain)} | {f(wavg)} | {t} {e:.2f} | **{plain[2] / e:.2f}** | {plain[0] / e:.2f} "
                  f"| **{plain[2] / wavg[2]:.2f}** | {plain[1] / wavg[2]:.2f} |")


if __name__ == "__main__":
    main(sys.argv[1:])
