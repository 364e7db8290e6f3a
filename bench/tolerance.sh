#!/bin/sh
# Compression against --tolerance (issue 13): the five patterns sampled at RESOLUTION (64), built
# with tolerances 0 … 2, stored nodes of each (`vtex inspect --json`). The tolerance bounds the
# change of transmittance along any chord of a merged node (per unit τ) and of its ellipsoid and
# albedo entries (docs/formats.md, "Compression").
# Usage: bench/tolerance.sh VTEX_BINARY [DIR]   (environment: RESOLUTION)
set -eu
VTEX=${1:?usage: tolerance.sh VTEX_BINARY [DIR]}
DIR=${2:-/tmp/vtex-tolerance}
RESOLUTION=${RESOLUTION:-64}
TOLERANCES="0 0.01 0.05 0.1 0.5 1 2"
mkdir -p "$DIR"
printf '| pattern |'
for e in $TOLERANCES; do printf ' %s |' "$e"; done
printf '\n| --- |'
for e in $TOLERANCES; do printf ' ---: |'; done
printf '\n'
for p in grass bush fur brushed blocks; do
  "$VTEX" -q pattern "$p" -o "$DIR/$p.glb"
  cyclic=""
  case $p in grass | fur) cyclic=--cyclic ;; esac
  "$VTEX" -q sample "$DIR/$p.glb" -o "$DIR/$p.vtl" -r "$RESOLUTION" $cyclic
  printf '| %s |' "$p"
  for e in $TOLERANCES; do
    "$VTEX" -q build "$DIR/$p.vtl" -o "$DIR/$p.vto" --tolerance "$e"
    n=$("$VTEX" inspect "$DIR/$p.vto" --json | python3 -c "import json, sys; print(json.load(sys.stdin)['stored_nodes'])")
    printf ' %s |' "$n"
  done
  printf '\n'
done
