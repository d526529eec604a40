#!/usr/bin/env python3
"""The README's H200 tables (hardware beside compute, one row per technique) from an `oit bench`
report.json: python3 bench/h200/readme_tables.py REPORT.json SCENE"""
import json
import sys


def spread(v):
    fmt = lambda y: ("%.0f" % y) if y >= 100 else ("%.2f" % y)
    return f"{fmt(v['median'])} ({fmt(v['min'])}–{fmt(v['max'])})"


def main(path, scene):
    rows = [r for r in json.load(open(path))['rows'] if r['scene'] == scene and r['backend'] == 'wgpu']
    print("| technique | lost | EPR (%) | GPU ms, hardware | GPU ms, compute | steady wall ms, hardware | steady wall ms, compute | faster (GPU) |")
    print("|---|---|---|---|---|---|---|---|")
    seen = []
    for r in rows:
        if r['technique'] not in seen:
            seen.append(r['technique'])
    for t in seen:
        h = next((r for r in rows if r['technique'] == t and r['raster'] == 'hardware'), None)
        c = next((r for r in rows if r['technique'] == t and r['raster'] == 'compute'), None)
        if not h or not c:
            continue
        epr = h['epr'] * 100
        faster = ("compute" if c['gpu_ms']['max'] < h['gpu_ms']['min']
                  else "hardware" if h['gpu_ms']['max'] < c['gpu_ms']['min'] else "overlap")
        print(f"| {t} | {h['lost']:,} | {'0' if epr == 0 else '%.3g' % epr} | {spread(h['gpu_ms'])} | "
              f"{spread(c['gpu_ms'])} | {spread(h['steady_wall_ms'])} | {spread(c['steady_wall_ms'])} | {faster} |")


if __name__ == '__main__':
    main(sys.argv[1], sys.argv[2])
