#!/usr/bin/env python3
"""Frames in flight against one frame at a time, from one `oit bench` report.json (same run, same
GPU): per raster path and technique, GPU ms, the steady state's wall ms per frame (a frame loop
with frames in flight: `steady_wall_ms`) and the one-at-a-time frame (`latency_wall_ms`), each
over GPU ms (issue 10's target: steady/GPU <= 1.25).

    in_flight.py REPORT.json [SCENE]
"""
import json
import statistics
import sys


def main(path, scene=None):
    rows = [r for r in json.load(open(path))["rows"]
            if r.get("gpu_ms") and r.get("latency_wall_ms") and (scene is None or r["scene"] == scene)]
    for name in dict.fromkeys(r["scene"] for r in rows):
        print(f"\n### {name}\n")
        print("| backend | path | technique | GPU ms | steady ms | latency ms | steady/GPU | latency/GPU |")
        print("|---|---|---|---|---|---|---|---|")
        qs, ql = [], []
        for r in rows:
            if r["scene"] != name:
                continue
            g, s, l = r["gpu_ms"]["median"], r["steady_wall_ms"]["median"], r["latency_wall_ms"]["median"]
            qs.append(s / g)
            ql.append(l / g)
            print(f"| {r['backend']} | {r['raster']} | {r['technique']} | {g:.2f} | {s:.2f} | {l:.2f} | {s / g:.2f} | {l / g:.2f} |")
        n = len(qs)
        print(f"\nsteady/GPU median {statistics.median(qs):.2f}, max {max(qs):.2f}, within 1.25: {sum(q <= 1.25 for q in qs)}/{n}; "
              f"latency/GPU median {statistics.median(ql):.2f}, max {max(ql):.2f}, within 1.25: {sum(q <= 1.25 for q in ql)}/{n}")


if __name__ == "__main__":
    main(*sys.argv[1:3])
