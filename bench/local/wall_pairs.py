#!/usr/bin/env python3
"""Issue 38's wall pairs of several `oit bench` runs side by side (alternated binaries, rounds):
for each pair, in each run, the ratio (steady wall median with the wall over without it, as
opaque_ratio.py) and the walled frame's steady wall and GPU medians (ms).

Usage: wall_pairs.py DIR... (each DIR holding a report.json of oit bench)"""
import json
import sys

def pairs(d):
    rows = json.load(open(f"{d}/report.json"))
    rows = rows["rows"] if isinstance(rows, dict) else rows
    by = {(r["scene"], r["backend"], r["raster"], r["technique"]): r for r in rows}
    out = {}
    for (scene, b, raster, t), r in by.items():
        if scene.startswith("wall:") and ("no" + scene, b, raster, t) in by:
            o = by[("no" + scene, b, raster, t)]
            w, wo = r["steady_wall_ms"]["median"], o["steady_wall_ms"]["median"]
            g = (r.get("gpu_ms") or {}).get("median")
            out[(f"{b}/{raster}", t)] = (w / wo, w, g)
    return out

dirs = sys.argv[1:]
data = [pairs(d) for d in dirs]
keys = sorted(set().union(*data))
print(f"{'path':22} {'technique':10}" + "".join(f" {d:>22}" for d in dirs))
for k in keys:
    cells = []
    for p in data:
        if k in p:
            ratio, w, g = p[k]
            gpu = "-" if g is None else f"{g:.2f}"
            cells.append(f"{ratio:6.3f} {w:6.2f} {gpu:>7}")
        else:
            cells.append(" " * 22)
    print(f"{k[0]:22} {k[1]:10}" + "".join(f" {c:>22}" for c in cells))
print("\ncells: ratio, walled steady wall ms, walled GPU ms (medians)")
