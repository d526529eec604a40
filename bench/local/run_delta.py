#!/usr/bin/env python3
"""Two `oit bench` runs of the same rows side by side (a binary before and after a change): for
each row, the GPU and steady-wall medians in each, their differences, the steady wall's gap over
the GPU time, and the GPU time of chosen pass labels (a row's `gpu_pass_ms`).

    python3 bench/local/run_delta.py BEFORE AFTER [LABEL ...]   # each DIR holds report.json
"""
import json
import sys


def rows(d):
    data = json.load(open(f"{d}/report.json"))["rows"]
    return {(r["scene"], f'{r["backend"]}/{r["raster"]}', r["technique"]): r for r in data}


def median(r, key):
    v = r.get(key) or {}
    return v.get("median")


def main(before, after, labels):
    a, b = rows(before), rows(after)
    head = f"{'scene':22} {'path':16} {'technique':10} {'gpu':>13} {'d':>6} {'steady':>13} {'d':>6} {'gap':>11}"
    print(head + "".join(f" {label:>14}" for label in labels))
    for key in sorted(set(a) & set(b)):
        ra, rb = a[key], b[key]
        ga, gb = median(ra, "gpu_ms"), median(rb, "gpu_ms")
        sa, sb = median(ra, "steady_wall_ms"), median(rb, "steady_wall_ms")
        if None in (ga, gb, sa, sb):
            continue
        passes = []
        for label in labels:
            pa = sum(ms for l, ms in ra.get("gpu_pass_ms") or [] if l == label)
            pb = sum(ms for l, ms in rb.get("gpu_pass_ms") or [] if l == label)
            passes.append(f" {pa:6.2f}>{pb:<6.2f}"[:15].rjust(15))
        print(
            f"{key[0]:22} {key[1]:16} {key[2]:10} {ga:6.2f}>{gb:<6.2f} {gb - ga:+6.2f} "
            f"{sa:6.2f}>{sb:<6.2f} {sb - sa:+6.2f} {sa - ga:5.2f}>{sb - gb:<5.2f}" + "".join(passes)
        )
    print("\ncells: before>after (ms, medians); d: after - before; gap: steady wall - GPU")


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2], sys.argv[3:])
