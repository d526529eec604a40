#!/usr/bin/env python3
"""Alternated `oit bench` runs of two binaries (folders A1 B1 A2 B2 ... under one folder, each
with its report.json): per scene and technique, the least steady-state frame time over all of a
binary's runs (the frame least disturbed by the rest of a shared machine), B's over A's, and the
median of the runs' medians; then each binary's `wall:F:SCENE` / `nowall:F:SCENE` ratios and
SCENE / `untextured:SCENE` ratios (issue 38's wall and texture targets) by those least times.

    min_pairs.py FOLDER
"""
import collections
import glob
import json
import statistics
import sys

folder = sys.argv[1]
best = collections.defaultdict(lambda: float("inf"))
medians = collections.defaultdict(list)
for path in sorted(glob.glob(f"{folder}/*/report.json")):
    binary = path.split("/")[-2][0]
    for row in json.load(open(path))["rows"]:
        key = (row["scene"], row["technique"], binary)
        best[key] = min(best[key], row["steady_wall_ms"]["min"])
        medians[key].append(row["steady_wall_ms"]["median"])
scenes = sorted({k[0] for k in best})
techniques = sorted({k[1] for k in best})
print(f"{'scene':22} {'technique':9} {'least A':>8} {'least B':>8} {'B/A':>6}   median of medians A, B")
for scene in scenes:
    for t in techniques:
        a, b = best[(scene, t, "A")], best[(scene, t, "B")]
        ma, mb = statistics.median(medians[(scene, t, "A")]), statistics.median(medians[(scene, t, "B")])
        print(f"{scene:22} {t:9} {a:8.2f} {b:8.2f} {b / a:6.3f}   {ma:.2f}, {mb:.2f}")
for scene in scenes:
    if not scene.startswith("wall:"):
        continue
    twin = "nowall:" + scene[len("wall:"):]
    if twin not in scenes:
        continue
    for binary in "AB":
        ratios = " ".join(f"{t} {best[(scene, t, binary)] / best[(twin, t, binary)]:.3f}" for t in techniques)
        print(f"{binary}: {scene} / {twin}: {ratios}")
for scene in scenes:
    plain = "untextured:" + scene
    if scene.startswith("untextured:") or plain not in scenes:
        continue
    for binary in "AB":
        ratios = " ".join(f"{t} {best[(scene, t, binary)] / best[(plain, t, binary)]:.3f}" for t in techniques)
        print(f"{binary}: {scene} / {plain}: {ratios}")
