# Writes summary.txt: each row's steady wall median, per binary and round (python3 summary.py).
import glob
import json
import os

here = os.path.dirname(os.path.abspath(__file__))
for run in ["a", "b"]:
    print(f"run {run}: steady wall median, ms (each round alternates on demand, lanes)")
    rows = {}
    for f in sorted(glob.glob(f"{here}/{run}/*/report.json")):
        binary = os.path.basename(os.path.dirname(f)).split("-")[0]
        for x in json.load(open(f))["rows"]:
            rows.setdefault((x["scene"], x["technique"]), {}).setdefault(binary, []).append(x["steady_wall_ms"]["median"])
    for (s, t), d in sorted(rows.items()):
        ondemand = " ".join(f"{v:6.2f}" for v in d["ondemand"])
        lanes = " ".join(f"{v:6.2f}" for v in d["lanes"])
        print(f"  {s:22} {t:5} on demand {ondemand}   lanes {lanes}")
