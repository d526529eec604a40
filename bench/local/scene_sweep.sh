#!/bin/bash
O=${OIT:-oit}

for sc in "coplanar" "ties:5" "near:8" "fence" "wall:0.5:planes:8" "glass" "particles:16"; do
for s in 4; do
for t in reference ll dfb fabs:2 mlp:2 dp ddp mdts64 bdp adp wavg wboit mboit:4 plain; do
  for b in cpu "vulkan --raster compute" "wgpu --raster compute" vulkan; do
    r=$($O compare --backend $b --scene $sc --size 48x40 --samples $s -t $t --elevation 25 --azimuth 40 --json 2>&1 | python3 -c "
import json,sys; t=sys.stdin.read()
try:
  d=json.loads(t); d=d[0] if isinstance(d,list) else d
  r=d.get('results',[d])[0] if 'results' in d else d
  print(r.get('fragments'), r.get('captured'), r.get('lost'), r.get('merged'), r.get('occluded'), round(r.get('epr') or 0,5))
except Exception as e: print('ERR', t.replace(chr(10),' ')[:160])")
    echo "$sc | s$s | $t | $b | $r"
  done
done; done; done
