#!/usr/bin/env python3
"""Before/after table of two `oit bench` report.json files of one scene (same run, same GPU):
GPU ms, steady-state wall ms per frame, and the steady/GPU ratio (issue 10's target: 1.25), per
raster path and technique, with fragments, losses and passes compared.

    before_after.py BEFORE/report.json AFTER/report.json
"""
import json
import statistics
import sys


def rows(path):
    return {(r["raster"], r["technique"]): r for r in json.load(open(path))["rows"]}


def main(before_path, after_path):
    before, after = rows(before_path), rows(after_path)
    print("| path | technique | GPU ms before | after | steady ms before | after | steady/GPU before | after | same result |")
    print("|---|---|---|---|---|---|---|---|---|")
    qb, qa, wall = [], [], []
    for key in sorted(after):
        if key not in before:
            continue
        b, a = before[key], after[key]
        gb, ga = b["gpu_ms"]["median"], a["gpu_ms"]["median"]
        sb, sa = b["steady_wall_ms"]["median"], a["steady_wall_ms"]["median"]
        same = all(b[f] == a[f] for f in ("fragments", "captured", "lost", "merged", "passes"))
        qb.append(sb / gb)
        qa.append(sa / ga)
        wall.append(sa / sb)
        print(f"| {key[0]} | {key[1]} | {gb:.2f} | {ga:.2f} | {sb:.2f} | {sa:.2f} | {sb / gb:.2f} | {sa / ga:.2f} | {'yes' if same else 'NO'} |")
    n = len(qa)
    print()
    print(f"steady/GPU median {statistics.median(qb):.2f} -> {statistics.median(qa):.2f}; "
          f"rows within 1.25: {sum(q <= 1.25 for q in qb)}/{n} -> {sum(q <= 1.25 for q in qa)}/{n}; "
          f"steady wall after/before median {statistics.median(wall):.2f}")


if __name__ == "__main__":
    main(*sys.argv[1:3])
