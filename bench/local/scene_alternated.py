#!/usr/bin/env python3
"""Before/after of alternated `oit bench` runs (before, after, before, after, ...) whose reports
hold several scenes: per scene, backend, raster path and technique, each run's steady wall ms
(median), and the after runs' sum over the before runs' for the wall time and the GPU time; the
geometric mean of the GPU ratios per scene. (bench/local/alternated.py keys rows without the
scene, for one-scene reports.)

    scene_alternated.py BEFORE1 AFTER1 BEFORE2 AFTER2 ...   (report folders)
"""
import json
import statistics
import sys

runs = [{(r["scene"], r["backend"], r["raster"], r["technique"]): r for r in json.load(open(d + "/report.json"))["rows"]}
        for d in sys.argv[1:]]
means = {}
for k in sorted(runs[0]):
    rows = [run[k] for run in runs]
    ms = [r["steady_wall_ms"]["median"] for r in rows]
    gpu = [r["gpu_ms"]["median"] for r in rows]
    wall = sum(ms[1::2]) / sum(ms[0::2])
    g = sum(gpu[1::2]) / sum(gpu[0::2])
    same = len({(r["fragments"], r["captured"], r["occluded"], r["epr"]) for r in rows}) == 1
    means.setdefault(k[0], []).append(g)
    print(f"{k[0]:24} {k[1]:7} {k[2]:8} {k[3]:6} wall {' '.join('%.2f' % m for m in ms)}  "
          f"after/before wall {wall:.3f} gpu {g:.3f}  same result: {'yes' if same else 'NO'}")
for scene, gs in means.items():
    print(f"{scene}: GPU after/before geometric mean {statistics.geometric_mean(gs):.3f} over {len(gs)} rows")
