set -e
cd /tmp/llbench
for r in 1 2 3 4; do
 for b in old new; do
  for s in 1 4; do
   ./oit-$b bench --backend cpu --scenes bunny --size 1024x1024 -t ll,dfb --samples $s --frames 10 --warmup 2 --no-curves --out $b-s$s-r$r > $b-s$s-r$r.log 2>&1
  done
 done
done
echo done
