#!/usr/bin/env python3
"""Prints how much longer wgpu on lavapipe takes than oit-cpu, per technique and scene, from an
`oit bench --backend all --raster all` report: the median wall time of each wgpu row over the
cpu row of the same scene and technique (both from the same run), then min/median/max and how
many pairs reach 3x; and the speedup model's measured/K per backend on each scene.

    bench/local/ratios.py bench/results/cpu-lavapipe/bench-512
"""
import json
import statistics
import sys

report = json.load(open(sys.argv[1] + "/report.json"))
rows = {(r["scene"], r["technique"], r["raster"]): r for r in report["rows"]}
ratios = []
for (scene, technique, raster), row in sorted(rows.items()):
    if raster != "cpu":
        continue
    for path in ("hardware", "compute"):
        other = rows.get((scene, technique, path))
        if other:
            ratio = other["wall_ms"]["median"] / row["wall_ms"]["median"]
            ratios.append(ratio)
            print(f"{scene.split('/')[-1]:>16} {technique:>8} {path:>8} {ratio:5.2f}x")
print(
    f"lavapipe / oit-cpu: min {min(ratios):.2f}x, median {statistics.median(ratios):.2f}x, "
    f"max {max(ratios):.2f}x; {sum(r >= 3 for r in ratios)} of {len(ratios)} pairs at 3x or more"
)
model = {}
for m in report["model"]:
    if m["ratio"] is not None:
        model[(m["scene"].split("/")[-1], m["backend"])] = m["ratio"]
for (scene, backend), ratio in sorted(model.items()):
    print(f"speedup model, measured / K: {scene} {backend} {ratio:.2f}")
