set -x
cd "$(dirname "$0")"
for b in old new; do xz -d oit-$b.xz && chmod +x oit-$b; done
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader > $OUT/info.txt
O="--size 1024x1024 --frames 10 --warmup 2 --warmup-ms 200 --no-curves"
W="--backend wgpu,vulkan --raster compute --scenes wall:0.4:planes:64,nowall:0.4:planes:64 -t fabs,dfb,ll,dp,ddp,mdts,wavg,bdp,mlp:4"
mkdir -p $OUT/op
for r in 1 2; do for b in old new; do
  ./oit-$b bench $W $O --out $OUT/op/$b-$r > $OUT/op/$b-$r.log 2>&1
  rm -f $OUT/op/$b-$r/*.png $OUT/op/$b-$r/*.svg
done; done
(cd $OUT && tar czf op.tgz op info.txt && rm -rf op)
./oit-new bench --backend wgpu,vulkan --raster compute --scenes particles:256,untextured:particles:256,fence,untextured:fence \
  -t ll,dp,ddp,mlp:4,fabs,dfb --out $OUT/tex $O > $OUT/tex.log 2>&1
(cd $OUT && rm -f tex/*.png tex/*.svg && tar czf tex.tgz tex tex.log && rm -rf tex tex.log)
./oit-new bench --backend wgpu,vulkan --raster all --scenes wall:0.4:planes:64,nowall:0.4:planes:64 -t bdp --bounds exact $O --out $OUT/bdpx > $OUT/bdpx.log 2>&1
(cd $OUT && rm -f bdpx/*.png bdpx/*.svg && tar czf bdpx.tgz bdpx bdpx.log && rm -rf bdpx bdpx.log)
