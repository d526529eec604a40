#!/usr/bin/env python3
"""One timed label's GPU milliseconds (a row's `gpu_pass_ms`: the run's last timed frame's) beside
the frame's median GPU time, for every row of each `oit bench` report named, one column a report: the
same pass before and after a change, runs alternated.

    python3 bench/local/pass_ms.py LABEL DIR [DIR ...]     # DIR holds report.json
"""
import json
import sys


def main(label, dirs):
    table = {}
    for d in dirs:
        for r in json.load(open(f"{d}/report.json"))["rows"]:
            passes = dict(r.get("gpu_pass_ms") or {})
            key = (r["scene"], f'{r["backend"]}/{r["raster"]}', r["technique"])
            gpu = (r.get("gpu_ms") or {}).get("median")
            table.setdefault(key, {})[d] = (passes.get(label), gpu)
    print(f"{'scene':<24} {'path':<16} {'technique':<10} " + " ".join(f"{d:>18}" for d in dirs))
    for key in sorted(table):
        cells = []
        for d in dirs:
            ms, gpu = table[key].get(d, (None, None))
            cells.append(f"{ms:8.2f} {gpu:8.1f} " if ms is not None and gpu is not None else f"{'-':>18}")
        print(f"{key[0]:<24} {key[1]:<16} {key[2]:<10} " + " ".join(cells))
    print(f"\ncells: '{label}' ms (the last timed frame's), frame GPU ms (median)")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2:])
