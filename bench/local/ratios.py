#!/usr/bin/env python3
"""Prints how much longer each GPU backend on lavapipe takes than oit-cpu, per technique and
scene, from an `oit bench --backend all --raster all` report (or `--backend cpu,wgpu`): the
median wall time (with the image read back, `wall_ms`) of each GPU row over the cpu row of the
same scene and technique, both from the same run; then, per backend, min/median/max and how many
pairs reach 3x (issue 12's target is wgpu's); and the speedup model's measured/K per backend on
each scene.

    bench/local/ratios.py bench/results/cpu-lavapipe/bench-512

Rows are keyed by backend as well as raster path: `wgpu`, `wgpu+blend` and `vulkan` rows of one
path are different pairs (keyed by path alone, the last backend's row stood for all of them).
"""
import json
import statistics
import sys

report = json.load(open(sys.argv[1] + "/report.json"))
rows = {(r["scene"], r["technique"], r["backend"], r["raster"]): r for r in report["rows"]}
ratios = {}
for (scene, technique, backend, raster), row in sorted(rows.items()):
    if backend != "cpu":
        continue
    for (s, t, b, path), other in sorted(rows.items()):
        if (s, t) != (scene, technique) or b == "cpu":
            continue
        ratio = other["wall_ms"]["median"] / row["wall_ms"]["median"]
        ratios.setdefault(b, []).append(ratio)
        print(f"{scene.split('/')[-1]:>16} {technique:>8} {b:>11} {path:>8} {ratio:5.2f}x")
for backend, rs in sorted(ratios.items()):
    print(
        f"{backend} on lavapipe / oit-cpu: min {min(rs):.2f}x, median {statistics.median(rs):.2f}x, "
        f"max {max(rs):.2f}x; {sum(r >= 3 for r in rs)} of {len(rs)} pairs at 3x or more"
    )
model = {}
for m in report.get("model") or report.get("speedup_model") or []:
    if m["ratio"] is not None:
        model[(m["scene"].split("/")[-1], m["backend"])] = m["ratio"]
for (scene, backend), ratio in sorted(model.items()):
    print(f"speedup model, measured / K: {scene} {backend} {ratio:.2f}")
