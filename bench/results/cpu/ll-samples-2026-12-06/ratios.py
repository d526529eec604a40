#!/usr/bin/env python3
"""4-sample over 1-sample steady wall per frame (median) of ll and dfb, per round and binary,
from this folder's report.json files (run.sh writes them)."""
import json
import os

here = os.path.dirname(os.path.abspath(__file__))
for r in range(1, 5):
    row = []
    for b in ("old", "new"):
        v = {}
        for s in (1, 4):
            rep = json.load(open(os.path.join(here, f"{b}-s{s}-r{r}", "report.json")))
            for x in rep["rows"]:
                v[(x["technique"], s)] = (x["steady_wall_ms"]["median"], x["lost"], x["epr"])
        for t in ("ll", "dfb"):
            a, c = v[(t, 1)][0], v[(t, 4)][0]
            row.append(f"{b} {t} {a:.1f} -> {c:.1f} ms {c / a:.2f}x (lost {v[(t, 4)][1]}, EPR {v[(t, 4)][2]})")
    print(f"round {r}: " + " | ".join(row))
