#!/usr/bin/env bash
# Cold release builds of the `oit` binary, one per feature set, each in a fresh target folder, and
# the binary's size: writes one JSON object a line to stdout (collected into builds.json, which
# tests/tests/readme_tables.rs turns into the build table of README.md and docs/backends.md).
#
#   bench/results/cpu/builds/measure.sh [NAME...] >> lines.jsonl
#
# NAME is one of cpu, default, vulkan, all (every build when none is named). Each build runs
# under `nice -n 19` in a target folder under $BUILD_ROOT (default: a temporary folder), deleted
# afterwards; the crates' sources are fetched before the clock starts (`cargo fetch`).
set -euo pipefail
cd "$(dirname "$0")/../../../.."
root="${BUILD_ROOT:-$(mktemp -d)}"
declare -A args=(
  [cpu]="--no-default-features --features cpu"
  [default]=""
  [vulkan]="--no-default-features --features cpu,vulkan"
  [all]="--features cpu,wgpu,vulkan,view"
)
names=("$@"); [ ${#names[@]} -eq 0 ] && names=(cpu default vulkan all)
cargo fetch --locked >/dev/null
for name in "${names[@]}"; do
  dir="$root/oit-build-$name"
  rm -rf "$dir"
  cmd=$(echo "cargo build --release --locked -p oit-cli ${args[$name]}" | sed 's/ *$//')
  load=$(cut -d' ' -f1 /proc/loadavg)
  commit=$(git rev-parse --short HEAD)
  start=$(date +%s.%N)
  CARGO_TARGET_DIR="$dir" nice -n 19 $cmd >/dev/null 2>&1
  end=$(date +%s.%N)
  bytes=$(stat -c %s "$dir/release/oit")
  load_after=$(cut -d' ' -f1 /proc/loadavg)
  printf '{"name":"%s","command":"%s","wall_s":%.1f,"binary_bytes":%s,"cores":%s,"cpu":"%s","load_before":%s,"load_after":%s,"rustc":"%s","commit":"%s","date":"%s"}\n' \
    "$name" "$cmd" "$(echo "$end - $start" | bc)" "$bytes" "$(nproc)" \
    "$(lscpu | sed -n 's/^Model name: *//p' | head -1)" "$load" "$load_after" "$(rustc --version)" \
    "$commit" "$(date -u +%Y-%m-%d)"
  rm -rf "$dir"
done
