#!/usr/bin/env python3
"""Issue 38's frame-time target: each technique's steady wall time per frame on wall:F:SCENE (an
opaque wall holding back part of SCENE's transparent fragments) over its time on nowall:F:SCENE
(the same frame with the wall masked away: same camera, same transparent fragments, same opaque
pass), from one `oit bench` report.json that ran both, side by side.

Usage: opaque_ratio.py REPORT.json [TARGET]   (TARGET: the largest ratio allowed, 0.6)
"""
import json
import math
import sys

rows = json.load(open(sys.argv[1]))
rows = rows["rows"] if isinstance(rows, dict) else rows
target = float(sys.argv[2]) if len(sys.argv) > 2 else 0.6
by = {(r["scene"], r["backend"], r["raster"], r["technique"]): r for r in rows}
ratios, missed = [], []
print(f"{'scene':24} {'path':14} {'technique':10} {'with':>9} {'without':>9} {'ratio':>6}  held back")
for (scene, backend, raster, technique), r in sorted(by.items()):
    if not scene.startswith("wall:"):
        continue
    other = by.get(("no" + scene, backend, raster, technique))
    if other is None or not r.get("steady_wall_ms") or not other.get("steady_wall_ms"):
        continue
    # medians of the steady-state frames
    w, wo = r["steady_wall_ms"]["median"], other["steady_wall_ms"]["median"]
    ratio = w / wo
    held = 1 - r["captured"] / r["fragments"] if r["fragments"] else 0
    ratios.append(ratio)
    flag = "" if ratio <= target else "  > target"
    if ratio > target:
        missed.append((scene, technique, ratio))
    print(f"{scene:24} {backend + '/' + raster:14} {technique:10} {w:9.2f} "
          f"{wo:9.2f} {ratio:6.3f}  {held:.0%}{flag}")
if ratios:
    gm = math.exp(sum(map(math.log, ratios)) / len(ratios))
    print(f"\n{len(ratios)} pairs, geometric mean {gm:.3f}, worst {max(ratios):.3f}; "
          f"{len(missed)} over {target}")
