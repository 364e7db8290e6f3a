#!/bin/sh
# The bush-field benchmark of issue 12: does the texel render beat the explicit-geometry
# reference at equal error? 20×20 unit quads in z = 0, each carrying one 256³ `bush` texel (2000
# leaves, shell height 1), one directional light along (−1, −0.5, −1), irradiance 3, Lambert
# only, seen from three cameras on one line through (0, 0, 0.5): far (85 units), mid (31), near
# (4.1). For each view it times, side by side (the rows interleaved within each of RUNS rounds,
# so load drift hits them alike), and reports the median `wall_seconds` of:
#   * `vtex reference` at 1 and 16 spp;
#   * `vtex render` with defaults, and at near also with --spp 16;
#   * with BEFORE=VTEX_BINARY, `vtex render` with defaults by that (older) binary too, beside the
#     texel row of every view, on the texel that binary builds (bush.before.vto): a change's
#     before/after table from one run;
#   * every texel variant of VARIANTS ("name=args;name=args", e.g.
#     VARIANTS="refresh1=--shadow-refresh 1;bias-0.5=--lod-bias -0.5"), at every view;
# each row's RMSE, its 4×4-block and pixel-scale parts and its R, G, B bias against the truth
# (`vtex reference` at TRUTH_SPP, near TRUTH_SPP_NEAR), its time against the two references' (the
# median of the rounds' own ratios) and
# against the reference's at equal error (on the reference's trend between its two rows, time ∝
# RMSE^−b), and the issue's goals for the defaults as PASS/FAIL.
# Optional: DENSE=1 also times far and mid with a 20 000-leaf bush sampled at 256³ (goal:
# dense / sparse ≤ 1.15), and near (no goal; beside the dense mesh's 1-spp reference), with their
# RMSE and bias against their own truths (TRUTH_SPP, near TRUTH_SPP_NEAR); SWEEP=1 renders defaults and the 1-spp reference at 12 distances,
# geometric from near to far, against truths at SWEEP_TRUTH_SPP (64): mean green and RMSE.
# PATTERN=NAME puts another `vtex pattern` texel (grass, fur, brushed, blocks, topiary) in the
# bush's place, sampled and built as the bush is (its files keep the bush's names; the truths'
# keys hash the mesh, so each pattern has its own), to see how the renderer does beyond the bush.
# Truths are cached in DIR/truth/, keyed by scene file, spp, source mesh and TRUTH_KEY ("v1";
# change it when the reference renderer changes); a reused truth is announced.
# Writes DIR/bush_field.md and DIR/bush_field.csv, and prints the markdown.
# Usage: bench/bush_field.sh VTEX_BINARY [DIR] [RUNS] [THREADS]
#   (environment: WIDTH, HEIGHT (768×576), TRUTH_SPP (1024), TRUTH_SPP_NEAR (256), RUNS,
#    THREADS, BEFORE, VARIANTS, DENSE, SWEEP, SWEEP_TRUTH_SPP, TRUTH_KEY, COMPARE_VTEX, PATTERN (bush),
#    LIGHT ("x, y, z", the light's direction of travel; the issue's -1, -0.5, -1);
#    arguments win)
set -eu
VTEX=${1:?usage: bush_field.sh VTEX_BINARY [DIR] [RUNS] [THREADS]}
case $VTEX in /*) ;; *) VTEX=$(pwd)/$VTEX ;; esac
DIR=${2:-/tmp/vtex-bush-field}
RUNS=${3:-${RUNS:-3}}
THREADS=${4:-${THREADS:-2}}
WIDTH=${WIDTH:-768}
HEIGHT=${HEIGHT:-576}
TRUTH_SPP=${TRUTH_SPP:-1024}
TRUTH_SPP_NEAR=${TRUTH_SPP_NEAR:-256}
SWEEP_TRUTH_SPP=${SWEEP_TRUTH_SPP:-64}
TRUTH_KEY=${TRUTH_KEY:-v1}
VARIANTS=${VARIANTS:-}
DENSE=${DENSE:-0}
PATTERN=${PATTERN:-bush}
# The dense rows are a 20 000-leaf bush against the sparse one: beside another pattern their
# ratio would compare two texels.
if [ "$DENSE" = 1 ] && [ "$PATTERN" != bush ]; then
  echo "bush_field.sh: DENSE=1 compares with the bush; it cannot go with PATTERN=$PATTERN" >&2
  exit 2
fi
SWEEP=${SWEEP:-0}
# The binary that measures (`vtex compare` with its bias and split fields): by default the one
# measured; set it to a current build to measure an older one (a before/after table).
COMPARE_VTEX=${COMPARE_VTEX:-$VTEX}
case $COMPARE_VTEX in /*) ;; *) COMPARE_VTEX=$(pwd)/$COMPARE_VTEX ;; esac
BEFORE=${BEFORE:-}
case $BEFORE in /*|'') ;; *) BEFORE=$(pwd)/$BEFORE ;; esac
HELPER=$(cd "$(dirname "$0")" && pwd)/bush_field.py
START=$(date +%s)
echo "start: $(uptime)"
mkdir -p "$DIR/truth" "$DIR/out"
cd "$DIR"

# The texels: rebuilt every run, since what is measured is today's sampler and builder.
"$VTEX" -q pattern "$PATTERN" -o bush.glb
"$VTEX" -q sample bush.glb -o bush.vtl --resolution 256
"$VTEX" -q build bush.vtl -o bush.vto
if [ -n "$BEFORE" ]; then "$BEFORE" -q build bush.vtl -o bush.before.vto; fi
if [ "$DENSE" = 1 ]; then
  "$VTEX" -q pattern bush --leaves 20000 -o bush_dense.glb
  "$VTEX" -q sample bush_dense.glb -o bush_dense.vtl --resolution 256
  "$VTEX" -q build bush_dense.vtl -o bush_dense.vto
fi
python3 "$HELPER" plan "$WIDTH" "$HEIGHT" "$VARIANTS" "$DENSE" "$SWEEP" "$([ -n "$BEFORE" ] && echo 1 || echo 0)"

# truth VIEW SPP [MESH]: truth_VIEW.exr → the cached truth/KEY.exr, rendered when missing
truth() {
  view=$1 spp=$2 mesh=${3:-bush.glb}
  key=$(python3 "$HELPER" truth-key "$view.toml" "$spp" "$mesh" "$TRUTH_KEY")
  if [ -f "truth/$key.exr" ]; then
    echo "truth $view: reusing truth/$key.exr ($spp spp)"
    how=cached
  else
    echo "truth $view: rendering $spp spp → truth/$key.exr"
    "$VTEX" -q reference "$view.toml" -o "truth/$key.exr" --png "truth/$key.png" --spp "$spp" \
      --stats "truth/$key.json" --threads "$THREADS"
    python3 -c "import json; print('  %.1f s' % json.load(open('truth/$key.json'))['wall_seconds'])"
    how=rendered
  fi
  ln -sf "truth/$key.exr" "truth_$view.exr"
  echo "$view $spp $key $how" >> truths.txt
}
rm -f truths.txt
truth far "$TRUTH_SPP"
truth mid "$TRUTH_SPP"
truth near "$TRUTH_SPP_NEAR"
if [ "$DENSE" = 1 ]; then
  truth far_dense "$TRUTH_SPP" bush_dense.glb
  truth mid_dense "$TRUTH_SPP" bush_dense.glb
  truth near_dense "$TRUTH_SPP_NEAR" bush_dense.glb
fi
if [ "$SWEEP" = 1 ]; then
  while read -r view _; do truth "$view" "$SWEEP_TRUTH_SPP"; done < sweep.txt
fi

# RUNS rounds over every row of rows.txt (section|view|name|spp|command|arguments); images are
# deterministic, so the last round's image is the one compared.
rm -f out/*.json
round=1
while [ $round -le "$RUNS" ]; do
  echo "round $round of $RUNS: $(uptime)"
  while IFS='|' read -r section view name _ command args; do
    bin=$VTEX scene=$view.toml
    if [ "$section" = before ]; then bin=$BEFORE scene=$view.before.toml; fi
    # $args unquoted on purpose: it is a list of flags.
    # shellcheck disable=SC2086
    "$bin" -q "$command" "$scene" -o "out/$view.$name.exr" --stats "out/$view.$name.r$round.json" \
      --threads "$THREADS" $args < /dev/null
  done < rows.txt
  round=$((round + 1))
done
while IFS='|' read -r _ view name _; do
  if [ -e "truth_$view.exr" ]; then
    "$COMPARE_VTEX" compare "out/$view.$name.exr" "truth_$view.exr" --json > "out/$view.$name.cmp.json"
  fi
done < rows.txt

python3 "$HELPER" report "$RUNS"
echo "end: $(uptime)"
echo "total $(( $(date +%s) - START )) s; results in $DIR/bush_field.md, $DIR/bush_field.csv"
