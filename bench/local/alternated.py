#!/usr/bin/env python3
"""Before/after of alternated `oit bench` runs of two binaries on one machine (before, after,
before, after, ...): per backend, raster path and technique, each run's steady-state wall ms
(median), the ratio of the after runs' sum to the before runs', and whether fragments, losses,
EPR, storage and passes are the same in every run.

    alternated.py BEFORE1/report.json AFTER1/report.json BEFORE2/report.json AFTER2/report.json ...
"""
import json
import statistics
import sys


def main(paths):
    runs = [json.load(open(p))["rows"] for p in paths]
    key = lambda r: (r["backend"], r["raster"], r["technique"])
    print("| backend | raster | technique | steady wall ms, runs in order | after / before | same result |")
    print("|---|---|---|---|---|---|")
    ratios = []
    for k in [key(r) for r in runs[0]]:
        rows = [next(r for r in run if key(r) == k) for run in runs]
        ms = [r["steady_wall_ms"]["median"] for r in rows]
        ratio = sum(ms[1::2]) / sum(ms[0::2])
        ratios.append(ratio)
        sig = {(r["fragments"], r["lost"], r["epr"], r["storage_bytes"], r["passes"]) for r in rows}
        print(f"| {k[0]} | {k[1]} | {k[2]} | {' / '.join('%.2f' % m for m in ms)} | {ratio:.3f} | "
              f"{'yes' if len(sig) == 1 else 'NO'} |")
    print(f"\ngeometric mean after / before: {statistics.geometric_mean(ratios):.3f} over {len(ratios)} rows")


if __name__ == "__main__":
    main(sys.argv[1:])
