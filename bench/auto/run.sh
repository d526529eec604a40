#!/usr/bin/env bash
# auto's target (issue 11): `--technique auto --max-epr 0` is never slower than the fastest exact
# technique for the scene by more than 10 %. Per scene: the pick (`oit render -t auto --max-epr 0
# --json`, its counting pass included in nothing below), then `oit bench` of the pick beside every
# exact technique on the same backend, each on its default raster path, as auto assumes.
#   OUT=DIR BACKEND=cpu SIZE=512x512 SCENES=bunny,planes:64 bench/auto/run.sh
# On a GPU machine, after `cargo build --release -p oit-cli --features wgpu`:
#   BACKEND=wgpu SIZE=1024x1024 SCENES=bunny,armadillo,planes:64,grid:4x4:bunny \
#     OUT=$OUT bench/auto/run.sh
# (bunny and armadillo are built into oit: no file needed)
# Each scene leaves DIR/SLUG-auto.json (the choice) and DIR/SLUG/report.{md,json}; then
# bench/auto/summary.py DIR prints the table of the report.
set -u
OIT=${OIT:-target/release/oit}
OUT=${OUT:-bench/results/auto}
BACKEND=${BACKEND:-cpu}
SIZE=${SIZE:-512x512}
FRAMES=${FRAMES:-10}
SCENES=${SCENES:-bunny,planes:64}
EXACT=${EXACT:-dp,ddp,mlp:4,mdts64,fabs,dfb,ll}
mkdir -p "$OUT"
run() { echo "+ $*" >&2; "$@"; }
for scene in ${SCENES//,/ }; do
    # the scene expression with its folders dropped (grid:4x4:DIR/bunny.obj is grid-4x4-bunny,
    # not bunny: two scenes of one mesh must not share a slug)
    slug=$(echo "$scene" | sed -E 's#[^:,]*/##g; s#\.obj$##' | tr -c 'A-Za-z0-9_\n-' '-')
    run "$OIT" render --backend "$BACKEND" --size "$SIZE" --scene "$scene" -t auto --max-epr 0 --json \
        -o "$OUT/$slug.png" > "$OUT/$slug-auto.json" || continue
    pick=$(grep -o '"technique":"[^"]*"' "$OUT/$slug-auto.json" | head -1 | cut -d'"' -f4)
    techniques=$EXACT
    case ",$EXACT," in *",$pick,"*) ;; *) techniques="$EXACT,$pick" ;; esac
    run "$OIT" bench --backend "$BACKEND" --size "$SIZE" --scenes "$scene" --techniques "$techniques" \
        --frames "$FRAMES" --warmup 2 --no-curves --out "$OUT/$slug"
done
