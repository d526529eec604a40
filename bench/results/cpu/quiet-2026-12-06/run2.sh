cd "$(dirname "$0")"  # with oit-old and oit-new beside it
for r in 1 2 3; do for s in 1 4; do
  ./oit-new bench --backend cpu --scenes bunny --size 1024x1024 -t fabs,dfb,ll --samples $s --frames 20 --warmup 3 --no-curves --out long-s$s-r$r > long-s$s-r$r.log 2>&1
done; done
echo long done $(date)
