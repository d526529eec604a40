#!/usr/bin/env bash
# issue 9: oit-vulkan's compute path with the GPU setup beside wgpu's (H200, 1024²)
set -u
export OIT=.gpubin/oit
M=.gpu/models
R=$OUT/r; mkdir -p $R
git_commit=$(cat .gpubin/commit)
export OIT_COMMIT=$git_commit
# a throwaway warm-up scene: the first scene after the GPU wakes runs slow
$OIT bench --backend wgpu --raster compute --techniques fabs,plain --size 1024x1024 --frames 5 --scenes planes:64 --no-curves --out $R/warm > $R/warm.log 2>&1
$OIT info > $R/info.txt 2>&1
step=0
for scene in planes:64 $M/bunny.obj $M/armadillo.obj grid:4x4:$M/bunny.obj; do
  step=$((step+1))
  PATHS=compute SCENES="$scene" OUT=$R bench/h200/run.sh vulkan > $R/log-$step.txt 2>&1
  tar czf $OUT/r.tgz -C $OUT r
done
$OIT bench --backend wgpu,vulkan --raster compute --techniques fabs,plain --size 1024x1024 --frames 10 --warmup 2 \
   --scenes grid:12x12:$M/bunny.obj --no-curves --out $R/grid12 > $R/log-grid12.txt 2>&1
tar czf $OUT/r.tgz -C $OUT r
