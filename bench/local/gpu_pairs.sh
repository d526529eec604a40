#!/usr/bin/env bash
# Issue 38's GPU pairs in one device session, each binary named on the command line run in turn,
# ROUNDS times (the binaries alternated, so a machine's drift falls on all of them alike):
#   - the compute path's wall pairs (wall:0.4:planes:64 over its twin without the wall), both
#     backends, with the Vulkan setup's kernels timed apart (OIT_SETUP_PASSES=1), and again with
#     no timestamps (OIT_GPU_TIMESTAMPS=0: the steady wall as a renderer that times nothing has it);
#   - the textured scenes over their untextured twins on the compute path, both backends.
#   - once, after the rounds, each binary's OIT_HOST_TIMES trace of the wall pair on Vulkan (where a
#     steady frame's wall goes: recording, the device's span and its idle time between frames).
# Then wall_pairs.py, twin_pairs.py and host_times.py over each binary's output.
#
#   bench/local/gpu_pairs.sh OUT BINARY...      (ROUNDS=2 by default; SIZE=1024x1024)
set -euo pipefail
out=$1
shift
here=$(cd "$(dirname "$0")" && pwd)
rounds=${ROUNDS:-2}
size=${SIZE:-1024x1024}
walls=wall:0.4:planes:64,nowall:0.4:planes:64
textured=foliage,untextured:foliage,particles,untextured:particles,particles:256,untextured:particles:256
mkdir -p "$out"
for r in $(seq "$rounds"); do
  for bin in "$@"; do
    b=$(basename "$bin")
    OIT_SETUP_PASSES=1 "$bin" bench --backend vulkan,wgpu --raster compute --scenes $walls \
      -t fabs,ll,dfb,wavg,bdp --size "$size" --frames 10 --warmup 2 --warmup-ms 500 --no-curves \
      --out "$out/walls-$b-$r" > "$out/walls-$b-$r.log" 2>&1
    OIT_GPU_TIMESTAMPS=0 "$bin" bench --backend vulkan,wgpu --raster compute --scenes $walls \
      -t fabs,ll,dfb,wavg,bdp --size "$size" --frames 10 --warmup 2 --warmup-ms 500 --no-curves \
      --out "$out/untimed-$b-$r" > "$out/untimed-$b-$r.log" 2>&1
    "$bin" bench --backend vulkan,wgpu --raster compute --scenes $textured \
      -t fabs,ll,dfb,wavg --size "$size" --frames 30 --warmup 2 --warmup-ms 500 --no-curves \
      --out "$out/tex-$b-$r" > "$out/tex-$b-$r.log" 2>&1
  done
done
for bin in "$@"; do
  b=$(basename "$bin")
  # one scene a run: the lines name the technique, not the scene
  for s in wall nowall; do
    OIT_HOST_TIMES=1 "$bin" bench --backend vulkan --raster compute --scenes $s:0.4:planes:64 \
      -t fabs,wavg,bdp --size "$size" --frames 30 --warmup 2 --warmup-ms 500 --no-curves \
      --out "$out/trace-$b-$s" > "$out/trace-$b-$s.log" 2> "$out/trace-$b-$s.txt"
  done
done
for bin in "$@"; do
  b=$(basename "$bin")
  python3 "$here/wall_pairs.py" $(ls -d "$out"/walls-"$b"-*/) > "$out/wall-pairs-$b.txt"
  python3 "$here/wall_pairs.py" $(ls -d "$out"/untimed-"$b"-*/) > "$out/untimed-pairs-$b.txt"
  python3 "$here/host_times.py" "$out/trace-$b-wall.txt" "$out/trace-$b-nowall.txt" > "$out/host-times-$b.txt"
  python3 "$here/twin_pairs.py" "$out" "tex-$b-" > "$out/tex-pairs-$b.txt"
done
