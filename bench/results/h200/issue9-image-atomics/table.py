#!/usr/bin/env python3
"""The image-vs-buffer atomics table of README.md from the reports under r/ (run.sh's output):
per scene, path and technique, GPU ms on buffers (two runs, before and after the image run),
on images, their ratio (images / mean of the buffer runs), the capture pass's GPU ms
("geometry") on each, and whether the two give the same fragments, losses, ties and EPR."""
import json
import sys
from pathlib import Path

root = Path(sys.argv[1] if len(sys.argv) > 1 else "r")


def rows(name):
    report = json.loads((root / name / "report.json").read_text())
    return {r["technique"]: r for r in report["rows"]}


def geometry(r):
    return sum(ms for label, ms in r["gpu_pass_ms"] if label == "geometry")


print("| scene | path | technique | buffer GPU ms (run 1 / run 2) | image GPU ms | image / buffer "
      "| capture pass: buffer → image ms | same fragments, lost, tied, EPR |")
print("|---|---|---|---|---|---|---|---|")
for scene in ["planes-64", "bunny", "armadillo"]:
    for path in ["compute", "hardware"]:
        try:
            b1, img, b2 = (rows(f"{scene}-{path}-{s}") for s in ["buffer", "image", "buffer2"])
        except FileNotFoundError:
            continue
        for t, i in img.items():
            if t == "reference" or t not in b1:
                continue
            g1, g2, gi = (x[t]["gpu_ms"]["median"] for x in (b1, b2, img))
            key = lambda r: (r["fragments"], r["lost"], r["tied"], r["epr"])
            same = "yes" if key(i) == key(b1[t]) == key(b2[t]) else f"no: {key(b1[t])} vs {key(i)}"
            print(f"| {scene} | {path} | {t} | {g1:.2f} / {g2:.2f} | {gi:.2f} | {gi / ((g1 + g2) / 2):.2f} "
                  f"| {(geometry(b1[t]) + geometry(b2[t])) / 2:.2f} → {geometry(i):.2f} | {same} |")
