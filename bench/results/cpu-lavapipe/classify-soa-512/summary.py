# Writes summary.txt: each run's steady wall medians, ms (python3 summary.py > summary.txt).
import glob
import json
import os

here = os.path.dirname(os.path.abspath(__file__))
for f in sorted(glob.glob(here + "/*/report.json")):
    rows = json.load(open(f))["rows"]
    cells = " ".join(f"{x['scene']} {x['technique']} {x['steady_wall_ms']['median']:.1f}" for x in rows)
    print(os.path.basename(os.path.dirname(f)), cells)
