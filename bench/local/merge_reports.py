#!/usr/bin/env python3
"""Puts several `oit bench` report.json files of one configuration (one scene each, the same
backends, size and frames) into one, so that a table over scenes (the readme_tables `picks` and
`scenes` kinds) can read them: rows, scenes, scene_stats and failures concatenated in the order
given, every other field from the first report.

Usage: merge_reports.py OUT.json REPORT.json...
"""
import json
import sys

out, paths = sys.argv[1], sys.argv[2:]
reports = [json.load(open(p)) for p in paths]
merged = dict(reports[0])
for key in ("rows", "scenes", "scene_stats", "failures"):
    merged[key] = [x for r in reports for x in r.get(key, [])]
merged["command_line"] = " ; ".join(r["command_line"] for r in reports)
merged["merged_from"] = paths
json.dump(merged, open(out, "w"), indent=1)
print(f"{out}: {len(merged['rows'])} rows over {len(merged['scenes'])} scenes")
