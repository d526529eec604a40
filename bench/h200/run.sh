#!/usr/bin/env bash
# The H200 runs behind bench/results/h200/readme/ and the README's GPU tables: `oit bench` on
# both raster paths (median and min–max of 10 timed frames after 2 warm-up frames, GPU timestamps
# and wall time per frame). On a GPU machine with a Vulkan driver, after
# `cargo build --release -p oit-cli --features wgpu,vulkan`:
#   OUT=$OUT bench/h200/run.sh
# The meshes are oit's built-in `bunny` and `armadillo` (the committed results name them by the
# paths they were then read from).
#
# The cost model (issue 15), two more modes:
#   OUT=$OUT bench/h200/run.sh calibrate   # one command, one file: $OUT/calibrate/calibration.json
#                                          # (both raster paths, procedural scenes only, 1024²)
#   OUT=$OUT MODEL=$OUT/calibrate/calibration.json bench/h200/run.sh model
#                                          # the check: predictions on the unseen meshes
# Commit the calibration as bench/results/h200/calibration.json.
set -u
OIT=${OIT:-target/release/oit}
OUT=${OUT:-bench/results/h200/readme}
MODE=${1:-readme}
mkdir -p "$OUT"
run() { echo "+ $*" >&2; "$@"; }
# the commit measured, recorded in the calibration (the GPU machine may have no .git)
export OIT_COMMIT=${OIT_COMMIT:-$(git rev-parse HEAD 2>/dev/null || true)}
case "$MODE" in
readme)
    run "$OIT" info --json > "$OUT/info.json"
    run "$OIT" bench --backend wgpu --raster all --size 1024x1024 --frames 10 --warmup 2 \
        --scenes "bunny,planes:64,grid:4x4:bunny" --no-curves --out "$OUT/bench-1024"
    ;;
calibrate)
    run "$OIT" bench --calibrate --backend wgpu --raster all --size 1024x1024 --frames ${FRAMES:-10} --warmup 2 \
        --out "$OUT/calibrate"
    ;;
model)
    run "$OIT" bench --backend wgpu --raster all --size 1024x1024 --frames 10 --warmup 2 \
        --model "${MODEL:-$OUT/calibrate/calibration.json}" --no-curves \
        --scenes "bunny,armadillo,grid:4x4:bunny" --out "$OUT/model-1024"
    ;;
opaque)
    # issue 38: every technique with an opaque wall holding back part of the scene beside the
    # same frame with the wall masked away (bench/local/opaque_ratio.py reads the pairs), both
    # GPU backends and raster paths
    run "$OIT" info --json > "$OUT/info.json"
    run "$OIT" bench --backend wgpu,vulkan --raster "${PATHS:-all}" --size 1024x1024 --frames 10 --warmup 2 \
        --warmup-ms 200 --scenes "${SCENES:-wall:0.4:planes:64,nowall:0.4:planes:64,wall:0.4:default,nowall:0.4:default}" \
        --no-curves --out "$OUT/opaque-1024"
    ;;
vulkan)
    # issue 9: oit-vulkan beside wgpu, both raster paths, every technique, GPU timestamps on both
    # (bench/results/h200/vulkan-1024/); needs a build with --features wgpu,vulkan
    run "$OIT" info --json > "$OUT/info-vulkan.json"
    # PATHS=hardware (or compute) runs one path a report: the GPU clocks down while the host
    # works between passes (oit-vulkan's compute path sets triangles up on the host), and rows
    # of one path run next to rows of the other otherwise
    for scene in ${SCENES:-bunny armadillo grid:4x4:bunny planes:64}; do
        slug=$(echo "$scene" | sed 's#.*/##; s#\.obj$##; s#:#-#g')
        [ "${scene#grid:4x4}" != "$scene" ] && slug=grid-4x4-bunny
        for path in ${PATHS:-all}; do
            suffix=$([ "$path" = all ] && echo "" || echo "-$path")
            run "$OIT" bench --backend wgpu,vulkan --raster "$path" --size 1024x1024 --frames 10 --warmup 2 \
                --scenes "$scene" --no-curves --out "$OUT/vulkan-$slug$suffix"
        done
    done
    ;;
kbuf)
    # issue 9: the ordered k-buffer (fragment shader interlock) beside fabs on vulkan's hardware
    # path (every technique of the row on the same path), its error against the reference, and
    # the conformance test that holds it to fabs bit for bit (KBUF_TEST: the tests crate's kbuf
    # test binary, target/release/deps/kbuf-*)
    run "$OIT" info --json > "$OUT/info.json"
    if [ -n "${KBUF_TEST:-}" ]; then
        OIT_REQUIRE_GPU=1 run "$KBUF_TEST" --nocapture > "$OUT/kbuf-test.txt" 2>&1
        echo "kbuf test exit $?" >> "$OUT/kbuf-test.txt"
    fi
    for scene in planes:64 bunny armadillo grid:4x4:bunny; do
        slug=$(echo "$scene" | sed 's#.*/##; s#\.obj$##; s#:#-#g')
        [ "${scene#grid:4x4}" != "$scene" ] && slug=grid-4x4-bunny
        run "$OIT" compare --backend vulkan --raster hardware --size 1024x1024 --scene "$scene" \
            --techniques kbuf,fabs,kbuf:4,fabs:4,kbuf:8,fabs:8 --json > "$OUT/compare-$slug.json" 2> "$OUT/compare-$slug.txt"
        run "$OIT" bench --backend vulkan --raster hardware --size 1024x1024 --frames 10 --warmup 2 \
            --scenes "$scene" --techniques plain,fabs,kbuf,fabs:4,kbuf:4,fabs:8,kbuf:8,mdts64:8 \
            --no-curves --out "$OUT/bench-$slug"
    done
    ;;
vulkan-blend)
    # issue 9's raw operations: the graphics pipeline's own captures on both GPU backends (adp's
    # histogram by logic-op OR on vulkan only; wgpu keeps its atomics histogram), against the
    # atomics captures of the same run (the `vulkan` mode)
    for scene in bunny planes:64; do
        slug=$(echo "$scene" | sed 's#.*/##; s#\.obj$##; s#:#-#g')
        run "$OIT" bench --backend wgpu,vulkan --raster hardware --hardware-capture blend --size 1024x1024 \
            --frames 10 --warmup 2 --scenes "$scene" --techniques plain,dp,ddp,bdp,wavg,wsum,adp \
            --no-curves --out "$OUT/blend-$slug"
        run "$OIT" bench --backend vulkan --raster hardware --size 1024x1024 --frames 10 --warmup 2 \
            --scenes "$scene" --techniques plain,dp,ddp,bdp,wavg,wsum,adp --no-curves --out "$OUT/atomics-$slug"
    done
    ;;
grid)
    # issue 10's 10M-triangle frame: grid:12x12:bunny at 1024², fabs on the compute path (setup
    # on the GPU) and the hardware path, and plain as the baseline; steady-state wall beside GPU
    run "$OIT" bench --backend wgpu --raster all --size 1024x1024 --frames 5 --warmup 1 \
        --scenes grid:12x12:bunny --techniques plain,fabs,wavg --no-curves --out "$OUT/grid12-1024"
    # the GPU setup without its vertex cache (a transform per triangle corner), for the side by side
    OIT_SETUP_VERTS=0 run "$OIT" bench --backend wgpu --raster compute --size 1024x1024 --frames 5 --warmup 1 \
        --scenes grid:12x12:bunny --techniques plain,fabs,wavg --no-curves \
        --out "$OUT/grid12-1024-no-vertex-cache"
    ;;
before-after)
    # issue 10: a binary of an earlier commit ($BEFORE, stripped) and this one ($OIT) on the same
    # scenes, one after the other per scene (bench/results/h200/issue10/)
    for scene in ${SCENES:-bunny planes:64 grid:4x4:bunny}; do
        slug=$(echo "$scene" | sed 's#.*/##; s#\.obj$##; s#:#-#g')
        [ "${scene#grid:4x4}" != "$scene" ] && slug=grid-4x4-bunny
        for side in before after; do
            bin=$([ $side = before ] && echo "$BEFORE" || echo "$OIT")
            run "$bin" bench --backend wgpu --raster all --size 1024x1024 --frames 10 --warmup 2 \
                --scenes "$scene" --no-curves --out "$OUT/$side-$slug"
        done
    done
    ;;
alternated)
    # issue 37: the binaries of an earlier commit ($BEFORE, $BEFORE_BENCH: oit and the criterion
    # `techniques` bench, stripped) and of this one ($OIT, $AFTER_BENCH) in turn, twice (before-1,
    # after-1, before-2, after-2): `oit bench` on both GPU backends and raster paths, then the
    # criterion benches of the GPU backends on one scene (FILTER). Ratios by
    # bench/local/alternated.py; criterion's own "change" lines compare each run with the last.
    SCENE=${SCENE:-bunny}
    for round in 1 2; do
        for side in before after; do
            bin=$([ $side = before ] && echo "$BEFORE" || echo "$OIT")
            run "$bin" bench --backend wgpu,vulkan --raster all --size 1024x1024 --frames 10 --warmup 2 \
                --scenes "$SCENE" -t "${TECHNIQUES:-fabs,dfb,ll,adp,dp,ddp,wavg,bdp,bdp2,mdts,mdts64,mlp}" \
                --no-curves --out "$OUT/$side-$round"
        done
    done
    if [ -n "${BEFORE_BENCH:-}" ]; then
        for round in 1 2; do
            for side in before after; do
                bin=$([ $side = before ] && echo "$BEFORE_BENCH" || echo "$AFTER_BENCH")
                run "$bin" --bench "${FILTER:-^knot/(wgpu|vulkan)}" > "$OUT/criterion-$side-$round.txt" 2>&1
            done
        done
    fi
    ;;
embed)
    # issue 10 item 4: the embeddable pass recorded into the user's encoder, in the example's frame
    # loop (orbiting camera, 120 frames at 128², nothing read back): frames per second; needs
    # `cargo build --release -p oit-wgpu --example embed` (EMBED= another binary of it)
    for t in fabs:8 fabs:2 mdts64:8 wavg bdp; do
        run "${EMBED:-target/release/examples/embed}" "$t" "$OUT/embed-$t.png" | tee -a "$OUT/embed.txt"
    done
    ;;
big)
    # issue 11 item 2: frames bigger than the device's per-binding limit, run in screen tiles
    # within the default budget, exact techniques against the reference (EPR 0, lost 0 expected)
    for size in 4096 8192; do
        run "$OIT" compare --backend wgpu --raster compute --scene armadillo \
            --size ${size}x${size} --techniques fabs,dfb,ll,mdts64,bdp,adp --json > "$OUT/big-armadillo-$size.json"
    done
    for t in fabs dfb; do
        run "$OIT" render --backend wgpu --raster compute --scene armadillo \
            --size 16384x16384 --technique $t --json -o "$OUT/armadillo-16384-$t.png" > "$OUT/big-armadillo-16384-$t.json"
        rm -f "$OUT/armadillo-16384-$t.png"
    done
    ;;
exact)
    # the exact allocations beside fabs (issue 11's target: dfb at least as fast as fabs), both paths
    run "$OIT" bench --backend wgpu --raster all --size 1024x1024 --frames 10 --warmup 2 \
        --scenes "bunny,planes:64" --techniques fabs,dfb,ll --no-curves --out "$OUT/exact-1024"
    ;;
tail)
    # --overflow tail beside drop for the fixed-K techniques, and adp (its MIN beside the MAX)
    for overflow in drop tail; do
        run "$OIT" bench --backend wgpu --raster all --size 1024x1024 --frames 10 --warmup 2 --overflow $overflow \
            --scenes "bunny,armadillo" --techniques fabs:4,mdts64:4,adp \
            --no-curves --out "$OUT/tail-$overflow-1024"
    done
    ;;
auto)
    # issue 11's auto target on this device (bench/auto/run.sh; the H200 calibration ships)
    OIT="$OIT" BACKEND=wgpu SIZE=1024x1024 OUT="$OUT/auto-1024" \
        SCENES="bunny,armadillo,planes:64,grid:4x4:bunny" \
        bench/auto/run.sh
    python3 bench/auto/summary.py "$OUT/auto-1024" > "$OUT/auto-1024/summary.md" || true
    ;;
criterion)
    # issue 8 item 10: the criterion benches before the architecture work (bb02087) and now, one
    # after the other on this machine; BEFORE and AFTER are the two bench binaries
    # (`cargo bench -p oit-bench --no-run`, target/release/deps/techniques-*), FILTER a regex
    mkdir -p "$OUT/criterion"
    for side in before after; do
        bin=$([ $side = before ] && echo "$BEFORE" || echo "$AFTER")
        run "$bin" --bench "${FILTER:-.}" > "$OUT/criterion/$side.txt" 2>&1
    done
    ;;
*)
    echo "usage: $0 [readme|calibrate|model|vulkan|kbuf|grid|before-after|embed|big|exact|tail|auto|criterion]" >&2
    exit 2
    ;;
esac
