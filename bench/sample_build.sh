#!/bin/sh
# Sampling and octree-build timings of the bush (2000 leaves) at 128³ … 1024³, for the closing
# note of issue 4: wall time and peak memory (GNU time) of `vtex sample` and `vtex build`, stored
# nodes, compression 1 − stored/N³, and the growth of the stored nodes per doubling of N (it
# should track the surface, ×4, not the volume, ×8).
#   usage: bench/sample_build.sh [path/to/vtex] [resolutions...]
set -eu
VTEX=${1:-build/apps/vtex/vtex}
shift || true
RESOLUTIONS=${*:-128 256 512 1024}
DIR=$(mktemp -d)
trap 'rm -rf "$DIR"' EXIT
TIME=/usr/bin/time
"$VTEX" pattern bush -o "$DIR/bush.glb" -q
printf '%6s %10s %10s %10s %10s %12s %12s %8s\n' N sample_s sample_MiB build_s build_MiB stored compression growth
previous=""
for n in $RESOLUTIONS; do
    $TIME -f '%e %M' -o "$DIR/t1" "$VTEX" sample "$DIR/bush.glb" -o "$DIR/b.vtl" -r "$n" -q
    $TIME -f '%e %M' -o "$DIR/t2" "$VTEX" build "$DIR/b.vtl" -o "$DIR/b.vto" -q
    json=$("$VTEX" inspect "$DIR/b.vto" --json)
    stored=$(printf '%s' "$json" | sed -n 's/.*"stored_nodes": \([0-9]*\), "compression": \([0-9.e-]*\).*/\1/p' | head -1)
    compression=$(printf '%s' "$json" | sed -n 's/.*"stored_nodes": \([0-9]*\), "compression": \([0-9.e-]*\).*/\2/p' | head -1)
    growth="-"
    [ -n "$previous" ] && growth=$(awk "BEGIN{printf \"%.2f\", $stored/$previous}")
    read -r s1 m1 < "$DIR/t1"
    read -r s2 m2 < "$DIR/t2"
    printf '%6s %10s %10.0f %10s %10.0f %12s %12.4f %8s\n' "$n" "$s1" "$((m1 / 1024))" "$s2" "$((m2 / 1024))" "$stored" "$compression" "$growth"
    previous=$stored
done
