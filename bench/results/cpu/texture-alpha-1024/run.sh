#!/bin/sh
# Issue 38: the opaque pass's alpha test without shading (oit-old: 98ce204, oit-new: the commit
# after it; both `cargo build --release -p oit-cli --features wgpu,vulkan`), beside this script.
cd "$(dirname "$0")"
# 1. CPU time and steady wall time of the textured fence, alternated
for r in 1 2 3; do for v in old new; do
  perf stat -x, -e task-clock ./oit-$v bench --backend cpu --scenes fence -t ll,dp --size 1024x1024 \
    --frames 30 --warmup 2 --no-curves --out ps-$v > /dev/null 2> ps.txt
  echo "$v $(grep task-clock ps.txt | cut -d, -f1) $(python3 -c "
import json;r=json.load(open('ps-$v/report.json'));print(' '.join('%s=%.1f'%(x['technique'],x['steady_wall_ms']['median']) for x in r['rows']))")"
done; done > cpu-time.txt
# 2. textured against untextured, alternated (issue 38's 1.3x)
for r in 1 2 3; do for v in old new; do
  ./oit-$v bench --backend cpu --scenes fence,untextured:fence,particles:256,untextured:particles:256 \
    -t dfb,ll,fabs,dp --size 1024x1024 --frames 20 --warmup 3 --no-curves --out alt/$v-r$r > /dev/null 2>&1
  python3 ../../../local/texture_ratio.py alt/$v-r$r/report.json > alt/$v-r$r/ratios.txt
done; done
