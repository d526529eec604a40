#!/usr/bin/env bash
# issue 9: mdts, mdts64 and fabs on storage images (--atomic-storage image) beside the same on
# storage buffers, oit-vulkan, both raster paths, H200, 1024². Also runs oit-vulkan's
# image_atomics test binary there (mdts64's R64_UINT images run only where the device has
# VK_EXT_shader_image_atomic_int64; lavapipe, in CI, refuses them).
# On the GPU machine: source .gpu/prelude.sh; bash .gpubin/run.sh (binaries in .gpubin/)
set -u
export OIT=.gpubin/oit
M=.gpu/models
R=$OUT/r; mkdir -p $R
export OIT_COMMIT=$(cat .gpubin/commit)
OIT_REQUIRE_GPU=1 .gpubin/image_atomics --test-threads 1 > $R/test-image-atomics.txt 2>&1
echo "test exit $?" >> $R/test-image-atomics.txt
# a throwaway warm-up scene: the first scene after the GPU wakes runs slow
$OIT bench --backend vulkan --raster compute --techniques fabs,plain --size 1024x1024 --frames 5 --scenes planes:64 --no-curves --out $R/warm > $R/warm.log 2>&1
$OIT info > $R/info.txt 2>&1
T=mdts,mdts64,fabs,mdts:8,mdts64:8,fabs:8
for scene in planes:64 $M/bunny.obj $M/armadillo.obj; do
  slug=$(echo "$scene" | sed 's#.*/##; s#\.obj$##; s#:#-#g')
  for path in compute hardware; do
    # buffer, image, buffer again: the order's drift shows in the two buffer runs
    for storage in buffer image buffer2; do
      $OIT bench --backend vulkan --raster $path --atomic-storage ${storage%2} --techniques $T \
        --size 1024x1024 --frames 10 --warmup 2 --scenes "$scene" --no-curves \
        --out $R/$slug-$path-$storage > $R/log-$slug-$path-$storage.txt 2>&1
    done
    tar czf $OUT/r.tgz -C $OUT r
  done
done
tar czf $OUT/r.tgz -C $OUT r
