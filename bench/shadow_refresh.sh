#!/bin/sh
# How `--shadow-refresh` trades time for error against the reference, on the scenes of
# bench/error_vs_time.sh (run that first with the same WORKDIR: it leaves the three distances'
# scenes and their 1024-spp truths there). Texel renders at 1 spp, sggx, fast shading, lod-bias
# 0, for each refresh value; prints RMSE against the truth and render seconds. Single runs.
# Figures: docs/render.md, "Shadow refresh against the reference".
# Usage: bench/shadow_refresh.sh VTEX_BINARY WORKDIR [THREADS]
set -eu
VTEX=${1:?usage: shadow_refresh.sh VTEX_BINARY WORKDIR [THREADS]}
case $VTEX in /*) ;; *) VTEX=$(pwd)/$VTEX ;; esac
DIR=${2:?usage: shadow_refresh.sh VTEX_BINARY WORKDIR [THREADS]}
THREADS=${3:-2}
cd "$DIR"
echo "load: $(uptime)"
for distance in near middle far; do
  [ -f "truth_$distance.exr" ] || { echo "shadow_refresh.sh: run bench/error_vs_time.sh first" >&2; exit 2; }
  for refresh in 0.25 0.5 0.7 0.9 1; do
    "$VTEX" -q render "${distance}_sggx.toml" -o refresh.exr --stats refresh.json --threads "$THREADS" \
      --shadow-refresh "$refresh"
    "$VTEX" compare refresh.exr "truth_$distance.exr" --json > refresh_error.json
    python3 - "$distance" "$refresh" <<'PY'
import json, sys
stats, error = json.load(open('refresh.json')), json.load(open('refresh_error.json'))
print(f"{sys.argv[1]:6s} refresh {sys.argv[2]:>4s}: RMSE {error['rmse']:.4f}, {stats['wall_seconds']:.3f} s, "
      f"{stats['rays']['shadow']} shadow queries")
PY
  done
done
