#!/bin/bash
# all techniques x backends/paths at 4 and 8 samples, near and far planes cutting the scene
O=${OIT:-oit}

for cam in "--elevation 60 --far 4.0" "--elevation 10 --near 3.3"; do
for s in 4 8; do
for t in reference ll dfb fabs:4 mlp:2 dp ddp mdts mdts64 bdp adp wavg wsum wboit mboit plain; do
  for b in cpu "vulkan --raster compute" "wgpu --raster compute" vulkan wgpu; do
    r=$($O compare --backend $b --scene planes:4 --size 64x64 --samples $s -t $t $cam --json 2>&1 | python3 -c "
import json,sys; t=sys.stdin.read()
try:
  d=json.loads(t); d=d[0] if isinstance(d,list) else d
  r=d.get('results',[d])[0] if 'results' in d else d
  print(r.get('fragments'), r.get('captured'), r.get('lost'), r.get('merged'), round(r.get('epr') or 0,5))
except Exception as e: print('ERR', t.replace(chr(10),' ')[:140])")
    echo "$cam | s$s | $t | $b | $r"
  done
done; done; done
