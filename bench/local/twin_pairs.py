#!/usr/bin/env python3
"""Textured frames against their `untextured:` twins in `oit bench` reports (FOLDER/*/report.json):
per backend, raster path, scene and technique, the least steady wall frame over every report of
the folder, textured over untextured, and the same for the least device time where the reports
have it (issue 38's texture target: at most 1.3 on the CPU and the compute paths).

    twin_pairs.py FOLDER [PREFIX]    (PREFIX: only the reports FOLDER/PREFIX*/report.json)
"""
import collections
import glob
import json
import sys

folder = sys.argv[1]
prefix = sys.argv[2] if len(sys.argv) > 2 else ""
wall = collections.defaultdict(lambda: float("inf"))
gpu = collections.defaultdict(lambda: float("inf"))
for path in sorted(glob.glob(f"{folder}/{prefix}*/report.json")):
    for row in json.load(open(path))["rows"]:
        key = (row["backend"], row.get("raster") or "-", row["scene"], row["technique"])
        wall[key] = min(wall[key], row["steady_wall_ms"]["min"])
        g = row.get("gpu_ms")
        if isinstance(g, dict) and g.get("min") is not None:
            gpu[key] = min(gpu[key], g["min"])
print(f"{'backend':13} {'raster':8} {'scene':14} {'technique':9} {'wall ms':>15} {'wall':>6} {'device ms':>15} {'device':>6}")
for key in sorted(wall):
    backend, raster, scene, technique = key
    twin = (backend, raster, "untextured:" + scene, technique)
    if scene.startswith("untextured:") or twin not in wall:
        continue
    line = f"{backend:13} {raster:8} {scene:14} {technique:9} {wall[key]:6.3f} / {wall[twin]:6.3f} {wall[key] / wall[twin]:6.3f}"
    if key in gpu and twin in gpu:
        line += f" {gpu[key]:6.3f} / {gpu[twin]:6.3f} {gpu[key] / gpu[twin]:6.3f}"
    print(line)
