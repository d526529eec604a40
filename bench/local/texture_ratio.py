#!/usr/bin/env python3
"""Issue 38's texture target: each technique's steady wall time per frame on a textured SCENE over
its time on untextured:SCENE (the same geometry, camera and primitive order, each object in its
factor's colour), from one `oit bench` report.json that ran both, side by side.

Usage: texture_ratio.py REPORT.json [TARGET]   (TARGET: the largest ratio allowed, 1.3)
"""
import json
import math
import sys

rows = json.load(open(sys.argv[1]))
rows = rows["rows"] if isinstance(rows, dict) else rows
target = float(sys.argv[2]) if len(sys.argv) > 2 else 1.3
by = {(r["scene"], r["backend"], r["raster"], r["technique"]): r for r in rows}
ratios, missed = [], []
print(f"{'scene':24} {'path':14} {'technique':10} {'textured':>9} {'plain':>9} {'ratio':>6}")
for (scene, backend, raster, technique), r in sorted(by.items()):
    if scene.startswith("untextured:"):
        continue
    other = by.get(("untextured:" + scene, backend, raster, technique))
    if other is None or not r.get("steady_wall_ms") or not other.get("steady_wall_ms"):
        continue
    t, p = r["steady_wall_ms"]["median"], other["steady_wall_ms"]["median"]
    ratio = t / p
    ratios.append(ratio)
    flag = "" if ratio <= target else "  > target"
    if ratio > target:
        missed.append((scene, technique, ratio))
    print(f"{scene:24} {backend + '/' + raster:14} {technique:10} {t:9.2f} {p:9.2f} {ratio:6.3f}{flag}")
if ratios:
    gm = math.exp(sum(map(math.log, ratios)) / len(ratios))
    print(f"\n{len(ratios)} pairs, geometric mean {gm:.3f}, worst {max(ratios):.3f}; "
          f"{len(missed)} over {target}")
