#!/usr/bin/env python3
"""GPU time by label (a row's `gpu_pass_ms`) of every wall pair of each `oit bench` report named:
the frame with the wall (wall:F:SCENE) beside its twin (nowall:F:SCENE), so a walled frame's time
can be told apart pass by pass (issue 38; `oit_gpu::geometry_label` gives the opaque pass its own
label).

    python3 bench/local/pass_split.py DIR [DIR ...]     # DIR holds report.json
"""
import json
import sys


def main(dirs):
    print("GPU ms by label (median frame): wall:F:SCENE against nowall:F:SCENE")
    for d in dirs:
        rows = json.load(open(f"{d}/report.json"))["rows"]
        by = {(r["backend"], r["raster"], r["technique"], r["scene"]): r for r in rows}
        print(d)
        for (backend, raster, technique, scene), r in sorted(by.items()):
            if not scene.startswith("wall:"):
                continue
            twin = by.get((backend, raster, technique, "nowall:" + scene[len("wall:"):]))
            if twin is None:
                continue
            line = lambda z: "  ".join(f"{label} {ms:.2f}" for label, ms in z.get("gpu_pass_ms") or [])
            print(f"  {backend}/{raster} {technique}")
            print("    wall:   ", line(r))
            print("    nowall: ", line(twin))


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])
