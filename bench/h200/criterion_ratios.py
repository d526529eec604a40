#!/usr/bin/env python3
"""Criterion before/after ratios: `criterion_ratios.py BEFORE.txt AFTER.txt` (the two logs of
`bench/h200/run.sh criterion`). Prints the median after/before over the benches both ran, per
backend/path group with its range, and every bench that is slower after (point estimates,
criterion's middle figure)."""
import re
import statistics
import sys

UNITS = {'ns': 1e-6, 'µs': 1e-3, 'us': 1e-3, 'ms': 1.0, 's': 1e3}


def parse(path):
    """Bench name -> median ms; a long name is printed on its own line before `time:`."""
    out, last = {}, None
    for line in open(path, encoding='utf-8'):
        m = re.match(r'^(\S+)?\s+time:\s+\[(\S+) (\S+) (\S+) (\S+) (\S+) (\S+)\]', line)
        if m:
            out[m.group(1) or last] = float(m.group(4)) * UNITS[m.group(5)]
        elif re.match(r'^[A-Za-z0-9].*/\S+\s*$', line) and not line.startswith('Benchmarking'):
            last = line.strip()
    return out


def main():
    before, after = parse(sys.argv[1]), parse(sys.argv[2])
    common = sorted(set(before) & set(after))
    print(f'benches: before {len(before)}, after {len(after)}, both {len(common)}')
    ratios = {n: after[n] / before[n] for n in common}
    print(f'median after/before: {statistics.median(ratios.values()):.3f}')
    groups = {}
    for n, r in ratios.items():
        groups.setdefault('/'.join(n.split('/')[1:-1]), []).append(r)
    for g, rs in groups.items():
        print(f'  {g}: {len(rs)} benches, median {statistics.median(rs):.3f}, range {min(rs):.2f}-{max(rs):.2f}')
    slower = sorted((n for n in common if ratios[n] > 1), key=ratios.get)
    print(f'slower after: {len(slower)} of {len(common)}')
    for n in slower:
        print(f'  {n}: {before[n]:.3f} -> {after[n]:.3f} ms ({ratios[n]:.2f}x)')


if __name__ == '__main__':
    main()
