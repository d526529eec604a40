#!/usr/bin/env python3
"""Side-by-side tables of oit-vulkan and oit-wgpu from `oit bench --backend wgpu,vulkan` reports.

    bench/h200/vulkan_table.py DIR/report.json [DIR2/report.json ...]

One table per scene and raster path: each technique's GPU ms on wgpu and vulkan and their ratio
(vulkan / wgpu: below 1 raw Vulkan is faster), with steady-state wall ms beside; then the median
ratio per path and how many techniques are within 1.1x (issue 9's target)."""
import json
import re
import statistics
import sys


def med(row, key):
    v = row.get(key)
    return v["median"] if isinstance(v, dict) else None


def main(paths):
    for path in paths:
        report = json.load(open(path))
        rows = report["rows"]
        scenes = sorted({r["scene"] for r in rows}, key=lambda s: [r["scene"] for r in rows].index(s))
        for scene in scenes:
            for raster in ("hardware", "compute"):
                by = {}
                for r in rows:
                    if r["scene"] == scene and r["raster"] == raster:
                        by.setdefault(r["technique"], {})[r["backend"]] = r
                pairs = [(t, b) for t, b in by.items() if "wgpu" in b and "vulkan" in b]
                if not pairs:
                    continue
                name = re.sub(r"[^:,]*/", "", scene).removesuffix(".obj")
                print(f"\n### {name}, {raster} path ({report['width']}x{report['height']})\n")
                print("| technique | wgpu GPU ms | vulkan GPU ms | vulkan/wgpu | wgpu steady ms | vulkan steady ms |")
                print("|---|---|---|---|---|---|")
                ratios = []
                for t, b in pairs:
                    w, v = med(b["wgpu"], "gpu_ms"), med(b["vulkan"], "gpu_ms")
                    ws, vs = med(b["wgpu"], "steady_wall_ms"), med(b["vulkan"], "steady_wall_ms")
                    ratio = v / w if w and v else None
                    if ratio:
                        ratios.append(ratio)
                    fmt = lambda x: f"{x:.2f}" if x is not None else "-"
                    print(f"| {t} | {fmt(w)} | {fmt(v)} | {fmt(ratio)} | {fmt(ws)} | {fmt(vs)} |")
                if ratios:
                    within = sum(1 for r in ratios if r <= 1.1)
                    print(f"\nmedian vulkan/wgpu {statistics.median(ratios):.2f}; within 1.1x (or faster): {within} of {len(ratios)}")


if __name__ == "__main__":
    main(sys.argv[1:])
