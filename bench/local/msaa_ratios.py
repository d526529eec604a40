#!/usr/bin/env python3
"""Issue 40's frame-time pairs: each row's steady wall time per frame (and GPU time) at 4 samples
over its time at 1 sample, matched by scene, backend, raster path and technique, from two
`oit bench` reports of the same options but --samples; with the pass counts (peels grow where
edge fragments add layers) and the EPR at 4 samples against the per-sample reference.

Usage: msaa_ratios.py ONE_SAMPLE_DIR FOUR_SAMPLES_DIR [...more pairs]
"""
import json
import sys


def load(d):
    return {(r["scene"], r["backend"], r["raster"], r["technique"]): r for r in json.load(open(d + "/report.json"))["rows"]}


args = sys.argv[1:]
print(f"{'scene':20} {'backend':12} {'path':9} {'technique':10} {'wall 1':>7} {'wall 4':>7} {'ratio':>6} "
      f"{'gpu 1':>7} {'gpu 4':>7} {'ratio':>6} {'passes':>7} {'EPR 4 (%)':>9}")
for one, four in zip(args[0::2], args[1::2]):
    a, b = load(one), load(four)
    for k in sorted(a):
        if k not in b:
            print(f"{k}: no row at 4 samples")
            continue
        r1, r4 = a[k], b[k]
        w1, w4 = r1["steady_wall_ms"]["median"], r4["steady_wall_ms"]["median"]
        g1, g4 = (r1.get("gpu_ms") or {}).get("median"), (r4.get("gpu_ms") or {}).get("median")
        gpu = f"{g1:7.2f} {g4:7.2f} {g4 / g1:5.2f}x" if g1 and g4 else f"{'':7} {'':7} {'':6}"
        print(f"{k[0]:20} {k[1]:12} {k[2]:9} {k[3]:10} {w1:7.2f} {w4:7.2f} {w4 / w1:5.2f}x {gpu} "
              f"{r1['passes']:>3}->{r4['passes']:<3} {100 * r4['epr']:9.3f}")
