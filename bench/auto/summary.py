#!/usr/bin/env python3
"""The table of bench/auto/run.sh's folder: per scene, auto's pick at --max-epr 0 against the
fastest technique measured exact there (EPR 0) on the same backend, in the bench's time (GPU
milliseconds where the device has timestamps, else the wall median) and in steady-state wall
milliseconds. Usage: bench/auto/summary.py DIR"""
import json
import os
import sys


def main(folder):
    print("| scene | pick (path) | pick ms | fastest exact other (path) | its ms | pick / fastest | pick steady wall ms | fastest steady wall ms |")
    print("|---|---|---|---|---|---|---|---|")
    for name in sorted(os.listdir(folder)):
        if not name.endswith("-auto.json"):
            continue
        slug = name[: -len("-auto.json")]
        with open(os.path.join(folder, name)) as f:
            choice = json.loads(f.readline())
        report_path = os.path.join(folder, slug, "report.json")
        if not os.path.exists(report_path):
            print(f"| {slug} | {choice['technique']} | no bench report | | | | | |")
            continue
        with open(report_path) as f:
            report = json.load(f)
        rows = [r for r in report["rows"] if r["technique"] != "reference"]
        pick = [r for r in rows if r["technique"] == choice["technique"]]
        # exact by what the technique is (bench/auto/run.sh's EXACT list, all exact at any depth),
        # not by a measured EPR of 0: with each technique on its default raster path the bench's
        # reference is the hardware path's, whose rasterizer may differ from the compute path's by
        # a fragment at an edge (the armadillo at 1024²: one pixel)
        exact_names = set(os.environ.get("EXACT", "dp,ddp,mlp:4,mdts64,fabs,dfb,ll").split(","))
        exact = [r for r in rows if r["technique"] != choice["technique"] and r["technique"] in exact_names]
        if not pick or not exact:
            print(f"| {slug} | {choice['technique']} | missing rows | | | | | |")
            continue
        p = min(pick, key=lambda r: r["time_ms"])
        e = min(exact, key=lambda r: r["time_ms"])
        sw = lambda r: (r.get("steady_wall_ms") or {}).get("median", float("nan"))
        print(
            f"| {slug} | {p['technique']} ({p['raster']}) | {p['time_ms']:.3f} | {e['technique']} ({e['raster']}) "
            f"| {e['time_ms']:.3f} | {p['time_ms'] / e['time_ms']:.3f} | {sw(p):.3f} | {sw(e):.3f} |"
        )


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "bench/results/auto")
