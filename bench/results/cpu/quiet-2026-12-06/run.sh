cd "$(dirname "$0")"  # with oit-old and oit-new beside it
for r in 1 2; do for v in old new; do for s in 1 4; do
  ./oit-$v bench --backend cpu --scenes bunny --size 1024x1024 -t fabs,fabs:4,dfb,ll --samples $s --frames 5 --warmup 1 --no-curves --out msaa-$v-s$s-r$r > msaa-$v-s$s-r$r.log 2>&1
done; done; done
echo msaa done $(date)
for r in 1 2; do for v in old new; do
  ./oit-$v bench --scenes particles:256,untextured:particles:256,fence,untextured:fence --backend cpu -t dfb,ll,fabs,dp --no-curves --size 512x512 --frames 10 --out tex-$v-r$r > tex-$v-r$r.log 2>&1
done; done
echo tex done $(date)
for r in 1; do for v in old new; do
  ./oit-$v bench --backend cpu --scenes wall:0.4:planes:64,nowall:0.4:planes:64 --size 1024x1024 -t fabs,dfb,ll,dp,ddp,mdts,wavg,bdp --frames 3 --warmup 1 --no-curves --out opaque-$v-r$r > opaque-$v-r$r.log 2>&1
done; done
echo opaque done $(date)
