#!/usr/bin/env bash
# The H100 runs behind bench/results/h100/ (issues 4 and 5), as one script so they can be redone.
# On a GPU machine with a Vulkan driver, after `cargo build --release -p oit-cli --features wgpu`:
#   bench/h100/run.sh compare|bench-512|bench-1024|curves
# Writes into $OUT (default bench/results/h100). The meshes are oit's built-in `bunny` and
# `armadillo` (the committed results name them by the paths they were then read from).
set -u
OIT=${OIT:-./target/release/oit}
OUT=${OUT:-bench/results/h100}
mkdir -p "$OUT"
run() { echo "+ $*" >&2; "$@"; }
case "${1:-compare}" in
compare)
    run "$OIT" info --json > "$OUT/info.json"
    for m in bunny armadillo; do
        # the table, then the same runs as JSON (one process each: both print gpu_ms)
        run "$OIT" compare --backend wgpu --raster all --scene "$m" --size 1024x1024 \
            --techniques all > "$OUT/compare-$m-1024.txt"
        run "$OIT" compare --backend wgpu --raster all --scene "$m" --size 1024x1024 \
            --techniques all --json > "$OUT/compare-$m-1024.json"
        # the papers' graphics-pipeline capture (MAX blending, depth textures) against atomics
        run "$OIT" compare --backend wgpu --raster hardware --hardware-capture blend \
            --scene "$m" --size 1024x1024 --techniques dp,ddp,bdp --json \
            > "$OUT/compare-$m-1024-blend.json"
    done
    # the Gfrag/s target: a 1024² frame of >= 10M fragments (planes:64, 64 layers over ~30 %)
    run "$OIT" bench --backend wgpu --raster all --scenes planes:64 --size 1024x1024 \
        --techniques dp,bdp,adp,mdts64,fabs --frames 10 --warmup 1 --no-curves --out "$OUT/deep-1024"
    # the same with K given (no sizing pass): the exact techniques' best rate
    run "$OIT" bench --backend wgpu --raster compute --scenes planes:64 --size 1024x1024 \
        --techniques fabs:64,mdts64:64,fabs --frames 10 --warmup 1 --no-curves --out "$OUT/deep-1024-k64"
    ;;
bench-512 | bench-1024)
    size=${1#bench-}
    run "$OIT" bench --backend wgpu --raster all --size "${size}x${size}" --frames 10 --warmup 1 \
        --scenes "bunny,armadillo,grid:4x4:bunny" --no-curves \
        --out "$OUT/bench-$size"
    ;;
curves)
    run "$OIT" bench --backend wgpu --raster all --size 512x512 --frames 10 --warmup 1 \
        --scenes grid:4x4:bunny --curves bunny --curve-size 512x512 --out "$OUT/curves"
    ;;
*)
    echo "usage: $0 compare|bench-512|bench-1024|curves" >&2
    exit 2
    ;;
esac
