#!/usr/bin/env python3
"""The second run's table (run2.sh): mdts on pixel-major buffers (the binary before, `oit_old`),
slot-major buffers (after, `oit`) on wgpu and vulkan, and vulkan's storage images, GPU ms
(and images over vulkan's slot-major buffers)."""
import json
import sys
from pathlib import Path

root = Path(sys.argv[1] if len(sys.argv) > 1 else "r2")


def rows(name):
    report = json.loads((root / name / "report.json").read_text())
    return {(r["backend"], r["technique"]): r for r in report["rows"]}


print("| scene | path | technique | wgpu pixel-major → slot-major | vulkan pixel-major → slot-major "
      "| vulkan images (/ slot-major) | same fragments, lost, tied, EPR |")
print("|---|---|---|---|---|---|---|")
for scene in ["planes-64", "bunny", "armadillo"]:
    for path in ["compute", "hardware"]:
        old, new, img = (rows(f"{scene}-{path}-{s}") for s in ["oit_old", "oit", "image"])
        for (backend, t), i in img.items():
            if t == "reference":
                continue
            ms = lambda r: r["gpu_ms"]["median"]
            key = lambda r: (r["fragments"], r["lost"], r["tied"], r["epr"])
            w0, w1 = old[("wgpu", t)], new[("wgpu", t)]
            v0, v1 = old[("vulkan", t)], new[("vulkan", t)]
            same = key(v0) == key(v1) == key(i) and key(w0) == key(w1)
            print(f"| {scene} | {path} | {t} | {ms(w0):.2f} → {ms(w1):.2f} ({ms(w1) / ms(w0):.2f}×) "
                  f"| {ms(v0):.2f} → {ms(v1):.2f} ({ms(v1) / ms(v0):.2f}×) | {ms(i):.2f} ({ms(i) / ms(v1):.2f}×) "
                  f"| {'yes' if same else 'NO'} |")
