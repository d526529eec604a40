#!/usr/bin/env bash
# issue 9, second run: mdts's buffers made slot-major (as fabs's) after the first run showed the
# image layout's gain; old (pixel-major) and new binaries side by side, wgpu and vulkan, and the
# images beside them.
set -u
M=.gpu/models
R=$OUT/r2; mkdir -p $R
OIT_REQUIRE_GPU=1 .gpubin/image_atomics --test-threads 1 > $R/test-image-atomics.txt 2>&1
echo "test exit $?" >> $R/test-image-atomics.txt
.gpubin/oit bench --backend vulkan --raster compute --techniques fabs,plain --size 1024x1024 --frames 5 --scenes planes:64 --no-curves --out $R/warm > $R/warm.log 2>&1
T=mdts,mdts64,mdts:8,mdts64:8
for scene in planes:64 $M/bunny.obj $M/armadillo.obj; do
  slug=$(echo "$scene" | sed 's#.*/##; s#\.obj$##; s#:#-#g')
  for path in compute hardware; do
    for bin in oit_old oit; do
      .gpubin/$bin bench --backend wgpu,vulkan --raster $path --techniques $T --size 1024x1024 --frames 10 --warmup 2 \
        --scenes "$scene" --no-curves --out $R/$slug-$path-$bin > $R/log-$slug-$path-$bin.txt 2>&1
    done
    .gpubin/oit bench --backend vulkan --raster $path --atomic-storage image --techniques $T --size 1024x1024 --frames 10 --warmup 2 \
        --scenes "$scene" --no-curves --out $R/$slug-$path-image > $R/log-$slug-$path-image.txt 2>&1
    tar czf $OUT/r2.tgz -C $OUT r2
  done
done
tar czf $OUT/r2.tgz -C $OUT r2
