#!/usr/bin/env bash
# Issue 40: whether the techniques whose losses depend on depth bins (adp, bdp) count the same on
# a GPU's compute paths as on oit-cpu, at one and at four samples, with the default bounds (the
# instances' boxes) and with exact bounds; mdts and the weighted techniques beside them. The H200
# run of tests/tests/msaa.rs found adp on planes:6 at 4 samples losing 13 fragments on wgpu's
# compute path where oit-cpu lost 11 (bench/results/h200/msaa-tests-2026-12-06).
#
#   bench/h200/diag-bins.sh OIT_BINARY OUT_DIR
#
# Each render is written as OUT_DIR/<technique>[-exact]-s<samples>-<backend>-<rep>.json; compare
# the `lost`, `captured` and `tied` fields across backends (two repeats each, to see whether a GPU
# count is even repeatable).
set -u
oit=$1
out=$2
mkdir -p "$out"
for s in 1 4; do
  for t in adp bdp mdts mdts64 wavg wboit mboit; do
    for b in cpu wgpu vulkan; do
      r=()
      [ "$b" != cpu ] && r=(--raster compute)
      for rep in 1 2; do
        "$oit" render --backend "$b" "${r[@]}" --scene planes:6 --size 40x40 --samples "$s" -t "$t" \
          --json --no-output > "$out/$t-s$s-$b-$rep.json" 2>&1
      done
      case $t in
        adp|bdp)
          "$oit" render --backend "$b" "${r[@]}" --scene planes:6 --size 40x40 --samples "$s" -t "$t" \
            --bounds exact --json --no-output > "$out/$t-exact-s$s-$b-1.json" 2>&1 ;;
      esac
    done
  done
done
python3 - "$out" <<'PY'
import json, pathlib, sys
rows = {}
for f in sorted(pathlib.Path(sys.argv[1]).glob("*.json")):
    try:
        d = json.loads(f.read_text())
    except ValueError:
        print(f"{f.name}: not JSON (an error?)")
        continue
    key, backend = f.stem.rsplit("-", 2)[0], f.stem.rsplit("-", 2)[1]
    rows.setdefault(key, []).append((backend, d["lost"], d["captured"], d["tied"]))
for key, runs in rows.items():
    same = len({r[1:] for r in runs}) == 1
    print(f"{key:22} {'same' if same else 'DIFFER'} {runs}")
PY
