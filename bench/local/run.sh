#!/usr/bin/env bash
# The runs behind bench/results/cpu-lavapipe/ (issue 5): oit-cpu and wgpu on lavapipe (both raster
# paths) side by side, on this machine (2 cores, no GPU). Heavy: run outside CI.
#   cargo build --release -p oit-cli --features wgpu && bench/local/run.sh 512|1024|curves
set -u
OIT=${OIT:-./target/release/oit}
OUT=${OUT:-bench/results/cpu-lavapipe}
mkdir -p "$OUT"
case "${1:-512}" in
512 | 1024)
    "$OIT" bench --backend all --raster all --size "$1x$1" --frames 10 --warmup 1 \
        --scenes "bunny,armadillo,grid:4x4:bunny" --no-curves --out "$OUT/bench-$1"
    ;;
curves)
    "$OIT" bench --backend all --raster all --size 256x256 --frames 10 --warmup 1 --scenes knot \
        --curves bunny --curve-frames 3 --out "$OUT/curves"
    ;;
*)
    echo "usage: $0 512|1024|curves" >&2
    exit 2
    ;;
esac
