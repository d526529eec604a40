set -x
cd "$(dirname "$0")"
for b in e1 e2; do xz -d oit-$b.xz && chmod +x oit-$b; done
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader > $OUT/info.txt
O="--size 1024x1024 --frames 10 --warmup 2 --warmup-ms 200 --no-curves"
mkdir -p $OUT/ab
for r in 1 2; do for b in e1 e2; do
  ./oit-$b bench --backend wgpu,vulkan --raster compute --scenes bunny,planes:16,particles:256,wall:0.4:planes:64 \
    -t dp,ddp,mlp:4,ll,dfb,fabs $O --out $OUT/ab/$b-$r > $OUT/ab/$b-$r.log 2>&1
  rm -f $OUT/ab/$b-$r/*.png $OUT/ab/$b-$r/*.svg
done; done
(cd $OUT && tar czf ab.tgz ab info.txt && rm -rf ab)
./oit-e2 bench --backend wgpu,vulkan --raster all --scenes wall:0.4:planes:64,nowall:0.4:planes:64 \
  -t fabs,dfb,ll,dp,ddp,mdts,wavg,bdp,mlp:4 $O --out $OUT/walls > $OUT/walls.log 2>&1
(cd $OUT && rm -f walls/*.png walls/*.svg && tar czf walls.tgz walls walls.log && rm -rf walls walls.log)
