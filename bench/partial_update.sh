#!/bin/sh
# The partial recompute (issue 13): the bush (2000 leaves) with 1 % of its leaves moved (the 20
# nearest to one point, bench/edit_leaves.py), re-sampled in full and with `vtex sample --update
# OLD.vtl --region R`, then built in full and with `vtex build --update OLD.vto --region R`, at
# each resolution: wall-clock medians over RUNS (GNU time, the whole command: reading the inputs,
# the work, writing), the region's share of the volume, and a check that the two .vtl files and
# the two .vto files are the same bytes.
#   usage: bench/partial_update.sh [path/to/vtex] [RUNS] [resolutions...]
set -eu
VTEX=${1:-build/apps/vtex/vtex}
shift || true
RUNS=${1:-3}
shift || true
RESOLUTIONS=${*:-256 512}
case $VTEX in /*) ;; *) VTEX=$(pwd)/$VTEX ;; esac
HERE=$(cd "$(dirname "$0")" && pwd)
DIR=$(mktemp -d)
trap 'rm -rf "$DIR"' EXIT
cd "$DIR"
"$VTEX" -q pattern bush -o bush.glb
median() { sort -n | awk '{v[NR] = $1} END {print v[int((NR + 1) / 2)]}'; }
seconds() { /usr/bin/time -f '%e' -o t "$@" && cat t; }
printf '%6s %12s %7s %9s %9s %6s %9s %9s %6s %s\n' N region share sample_s update_s saved build_s update_s saved identical
for n in $RESOLUTIONS; do
    region=$(python3 "$HERE/edit_leaves.py" bush.glb edited.glb 0.01 "$n")
    "$VTEX" -q sample bush.glb -o old.vtl -r "$n"
    "$VTEX" -q build old.vtl -o old.vto
    : > full.txt
    : > update.txt
    : > build.txt
    : > rebuild.txt
    for r in $(seq "$RUNS"); do
        seconds "$VTEX" -q sample edited.glb -o full.vtl -r "$n" >> full.txt
        seconds "$VTEX" -q sample edited.glb -o update.vtl --update old.vtl --region "$region" >> update.txt
        seconds "$VTEX" -q build full.vtl -o full.vto >> build.txt
        seconds "$VTEX" -q build update.vtl -o update.vto --update old.vto --region "$region" >> rebuild.txt
    done
    full=$(median < full.txt)
    update=$(median < update.txt)
    build=$(median < build.txt)
    rebuild=$(median < rebuild.txt)
    identical=no
    cmp -s full.vtl update.vtl && cmp -s full.vto update.vto && identical=yes
    share=$(echo "$region" | awk -F, -v n="$n" '{printf "%.2f%%", 100 * ($4 - $1) * ($5 - $2) * ($6 - $3) / (n * n * n)}')
    saved() { awk -v f="$1" -v u="$2" 'BEGIN {printf "%.0f%%", 100 * (1 - u / f)}'; }
    printf '%6s %12s %7s %9s %9s %6s %9s %9s %6s %s\n' "$n" "$(echo "$region" | tr , ' ' | awk '{print $4-$1 "x" $5-$2 "x" $6-$3}')" \
        "$share" "$full" "$update" "$(saved "$full" "$update")" "$build" "$rebuild" "$(saved "$build" "$rebuild")" "$identical"
done
