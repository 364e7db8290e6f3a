#!/bin/sh
# Sampling and octree-build timings of the bush (2000 leaves) at 128³ … 1024³, for issue 13's
# goals (256³ sample + build ≤ 1 s; 1024³ ≤ 15 s and ≤ 2 GiB; the build at most half the
# sampling's time; stored nodes growing ×4 per doubling, like a surface, not ×8): medians of
# RUNS interleaved runs of `vtex sample` and `vtex build` (wall time and peak memory from GNU
# time), their ratio, stored nodes, compression 1 − stored/N³ and the growth per doubling.
#   usage: RUNS=3 bench/sample_build.sh [path/to/vtex] [resolutions...]
set -eu
VTEX=${1:-build/apps/vtex/vtex}
shift || true
RESOLUTIONS=${*:-128 256 512 1024}
RUNS=${RUNS:-3}
DIR=$(mktemp -d)
trap 'rm -rf "$DIR"' EXIT
TIME=/usr/bin/time
"$VTEX" pattern bush -o "$DIR/bush.glb" -q
median() { sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }
printf '%6s %9s %10s %9s %10s %11s %10s %12s %8s\n' N sample_s sample_MiB build_s build_MiB build/sample stored compression growth
previous=""
for n in $RESOLUTIONS; do
    : > "$DIR/s" && : > "$DIR/b"
    run=0
    while [ "$run" -lt "$RUNS" ]; do
        $TIME -f '%e %M' -o "$DIR/t1" "$VTEX" sample "$DIR/bush.glb" -o "$DIR/b.vtl" -r "$n" -q
        $TIME -f '%e %M' -o "$DIR/t2" "$VTEX" build "$DIR/b.vtl" -o "$DIR/b.vto" -q
        cat "$DIR/t1" >> "$DIR/s"
        cat "$DIR/t2" >> "$DIR/b"
        run=$((run + 1))
    done
    s1=$(cut -d' ' -f1 "$DIR/s" | median); m1=$(cut -d' ' -f2 "$DIR/s" | median)
    s2=$(cut -d' ' -f1 "$DIR/b" | median); m2=$(cut -d' ' -f2 "$DIR/b" | median)
    read -r stored compression <<EOF
$("$VTEX" inspect "$DIR/b.vto" --json | python3 -c 'import json, sys; d = json.load(sys.stdin); print(d["stored_nodes"], d["compression"])')
EOF
    growth="-"
    [ -n "$previous" ] && growth=$(awk "BEGIN{printf \"%.2f\", $stored/$previous}")
    printf '%6s %9.2f %10.0f %9.2f %10.0f %11.2f %10s %12.4f %8s\n' "$n" "$s1" "$(awk "BEGIN{print $m1/1024}")" \
        "$s2" "$(awk "BEGIN{print $m2/1024}")" "$(awk "BEGIN{print $s2/$s1}")" "$stored" "$compression" "$growth"
    previous=$stored
done
