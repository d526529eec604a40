#!/usr/bin/env bash
# The H200 runs behind bench/results/h200/readme/ and the README's GPU tables: `oit bench` on
# both raster paths (median and min–max of 10 timed frames after 2 warm-up frames, GPU timestamps
# and wall time per frame). On the GPU machine, after `../shared/gpu/stage.sh` and a release build
# of `oit-cli --features wgpu` copied (stripped) to .gpubin/oit:
#   source .gpu/prelude.sh; OUT=$OUT bench/h200/run.sh
set -u
OIT=${OIT:-.gpubin/oit}
export OIT_MODELS=${OIT_MODELS:-.gpu/models}
OUT=${OUT:-bench/results/h200/readme}
mkdir -p "$OUT"
run() { echo "+ $*" >&2; "$@"; }
run "$OIT" info --json > "$OUT/info.json"
run "$OIT" bench --backend wgpu --raster all --size 1024x1024 --frames 10 --warmup 2 \
    --scenes "$OIT_MODELS/bunny.obj,planes:64,grid:4x4:bunny" --no-curves --out "$OUT/bench-1024"
