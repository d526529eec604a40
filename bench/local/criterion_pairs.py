#!/usr/bin/env python3
"""Criterion outputs of alternated runs (before-1 after-1 before-2 after-2 ...): each bench's
median time per run and after/before (geometric means of each side's runs), for the benches every
run finished.  usage: criterion_pairs.py before-1.txt after-1.txt before-2.txt after-2.txt"""
import importlib.util
import math
import pathlib
import sys

# the one parser of criterion's logs: bench/h200/criterion_ratios.py's
_spec = importlib.util.spec_from_file_location(
    "criterion_ratios", pathlib.Path(__file__).resolve().parents[1] / "h200" / "criterion_ratios.py")
_ratios = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_ratios)
parse = _ratios.parse


runs = [parse(p) for p in sys.argv[1:]]
before, after = runs[0::2], runs[1::2]
common = sorted(set.intersection(*(set(r) for r in runs)))
print("| bench | median ms, runs in order | after / before |")
print("|---|---|---|")
ratios = []
for b in common:
    gb = math.exp(sum(math.log(r[b]) for r in before) / len(before))
    ga = math.exp(sum(math.log(r[b]) for r in after) / len(after))
    ratios.append(ga / gb)
    print(f"| {b} | {' / '.join(f'{r[b]:.3f}' for r in runs)} | {ga / gb:.3f} |")
if ratios:
    g = math.exp(sum(map(math.log, ratios)) / len(ratios))
    print(f"\ngeometric mean after / before: {g:.3f} over {len(ratios)} benches")
