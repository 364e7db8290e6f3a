#!/bin/sh
# The reference renderer on the forest of bench/render_forest.sh (run that first with the same
# DIR: it makes the hill, the bush and forest_bush.toml): `vtex reference` in both modes at 1 and
# 16 spp, 768×576, with render and load time and peak memory, and the two modes' difference at
# 16 spp (their samples share positions, so it is geometry alone: what the straight segment
# inside curved cells loses). Prints one line per render. Figures: docs/reference.md.
# Usage: bench/reference_forest.sh VTEX_BINARY DIR [THREADS]
set -eu
VTEX=${1:?usage: reference_forest.sh VTEX_BINARY DIR [THREADS]}
case $VTEX in /*) ;; *) VTEX=$(pwd)/$VTEX ;; esac
DIR=${2:?usage: reference_forest.sh VTEX_BINARY DIR [THREADS]}
THREADS=${3:-2}
cd "$DIR"
[ -f forest_bush.toml ] || { echo "reference_forest.sh: run bench/render_forest.sh $VTEX $DIR first" >&2; exit 2; }
sed 's|^volume = "bush.vto"|volume = "bush.vto"\nsource = "bush.glb"|' forest_bush.toml > forest_reference.toml
echo "load: $(uptime)"
for mode in embedded deformed; do
  for spp in 1 16; do
    /usr/bin/time -f "%M" -o mem.txt "$VTEX" -q reference forest_reference.toml -o "ref_${mode}_$spp.exr" \
      --mode "$mode" --spp "$spp" --threads "$THREADS" --stats "ref_${mode}_$spp.json"
    python3 - "$mode" "$spp" "ref_${mode}_$spp.json" <<'PY'
import json, sys
mode, spp, stats = sys.argv[1], sys.argv[2], json.load(open(sys.argv[3]))
peak = int(open('mem.txt').read().split()[-1]) / 1024
print(f"{mode:9s} {spp:>3s} spp: render {stats['wall_seconds']:.2f} s, load {stats['load_seconds']:.2f} s, "
      f"{stats['reference_triangles']} triangles, peak {peak:.0f} MiB")
PY
  done
done
echo "embedded against deformed, 16 spp: $("$VTEX" compare ref_embedded_16.exr ref_deformed_16.exr)"
