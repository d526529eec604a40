#!/usr/bin/env python3
"""Summarizes `OIT_HOST_TIMES=1` output (stderr of `oit bench`/`oit render` on wgpu or Vulkan;
Vulkan's lines add the frame's span on the device, the device's idle time before it, its untimed
time within the span and its untimed gaps, by the command after each): per line
kind, the count, median and least milliseconds. A host setup is keyed by its triangle-word count
(one key a scene part). Reads plain or .xz files.

    python3 bench/local/host_times.py trace-T.txt.xz [trace-J.txt.xz ...]
"""
import lzma
import re
import statistics
import sys
from collections import defaultdict

SETUP = re.compile(r"oit host times: host setup ([\d.]+) ms \((\d+) triangle words, (\d+) items\), upload ([\d.]+) ms")
RECORD = re.compile(r"oit host times: (\S+) record\+submit ([\d.]+) ms, end readback ([\d.]+) ms"
                    r"(?:, (\d+) barriers, (\d+) transfers, (\d+) submissions)?(?:, device span ([\d.]+) ms)?(?:, device idle before ([\d.]+) ms)?"
                    r"(?:, untimed in span ([\d.]+) ms)?")
# the untimed gaps of a Vulkan line, each named by the timed command after it
GAP = re.compile(r", before (.+?) ([\d.]+) ms")

for path in sys.argv[1:]:
    opener = lzma.open if path.endswith(".xz") else open
    rows = defaultdict(list)
    with opener(path, "rt") as f:
        for line in f:
            m = SETUP.match(line)
            if m:
                rows[f"host setup, {m.group(2):>7} words {m.group(3):>7} items"].append(float(m.group(1)))
                rows["upload"].append(float(m.group(4)))
                continue
            m = RECORD.match(line)
            if m:
                # Vulkan's lines carry the counts or the span (with timestamps), wgpu's neither
                who = "vulkan" if m.group(4) or m.group(7) else "wgpu"
                rows[f"record+submit, {m.group(1)} ({who})"].append(float(m.group(2)))
                rows[f"end readback wait, {m.group(1)} ({who})"].append(float(m.group(3)))
                for k, name in [(4, "barriers"), (5, "transfers"), (6, "submissions"), (7, "device span"),
                                 (8, "device idle before"), (9, "untimed in span")]:
                    if m.group(k):
                        rows[f"{name}, {m.group(1)}"].append(float(m.group(k)))
                for label, ms in GAP.findall(line[m.end():]):
                    rows[f"untimed before {label}, {m.group(1)}"].append(float(ms))
    print(path)
    for key in sorted(rows):
        v = rows[key]
        if len(v) < 5:
            continue
        unit = "" if key.split(",")[0] in ("barriers", "transfers", "submissions") else " ms"
        print(f"  {key:<48} {len(v):>5}  median {statistics.median(v):7.3f}  least {min(v):7.3f}{unit}")
