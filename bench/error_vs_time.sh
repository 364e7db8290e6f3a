#!/bin/sh
# Error against run time (issue 6; DESIGN.md "Reporting error against run time").
# One scene (an 80×80-quad terrain under a 1-unit shell of the 128³ `bush` texel, one directional
# light with shadows) seen from three distances: near (a 1/128 voxel covers about a pixel), middle
# (a texel cell ≈ 20 px), far (a cell ≈ 3 px). Each is rendered
#   * by the texel renderer: lod-bias −1/0/+1 × spp 1/4 × filter neyret/sggx with --shading fast,
#     and with --shading reference (≈ 10× slower here) at spp 1 for every bias and filter, and at
#     spp 4 for lod-bias 0 only;
#   * by the reference renderer (`vtex reference`, embedded mode) at 1, 4, 16, 64 spp;
# all compared (`vtex compare`) to the reference renderer at 1024 spp. Time = `wall_seconds` of
# stats.json (render only; `load_seconds` is recorded beside it); the median of RUNS runs.
# Writes WORKDIR/error_vs_time.csv, WORKDIR/error-vs-time{,-near,-middle,-far}.svg and
# WORKDIR/error-vs-time-table.md (speed-up at equal error per texel render).
# Usage: bench/error_vs_time.sh VTEX_BINARY [WORKDIR] [THREADS] [RUNS]
#   (environment: WIDTH, HEIGHT (160×120), TRUTH_SPP (1024))
set -eu
VTEX=${1:?usage: error_vs_time.sh VTEX_BINARY [WORKDIR] [THREADS] [RUNS]}
case $VTEX in /*) ;; *) VTEX=$(pwd)/$VTEX ;; esac
DIR=${2:-/tmp/vtex-error-vs-time}
THREADS=${3:-2}
RUNS=${4:-1}
WIDTH=${WIDTH:-160}
HEIGHT=${HEIGHT:-120}
TRUTH_SPP=${TRUTH_SPP:-1024}
HELPER=$(cd "$(dirname "$0")" && pwd)/error_vs_time.py
START=$(date +%s)
echo "start: $(uptime)"
mkdir -p "$DIR"
cd "$DIR"
rm -f error_vs_time.csv

"$VTEX" -q pattern bush -o bush.glb
"$VTEX" -q sample bush.glb -o bush.vtl --resolution 128
for f in neyret sggx; do "$VTEX" -q build bush.vtl -o bush_$f.vto --filter $f; done
python3 "$HELPER" scenes "$WIDTH" "$HEIGHT"

# render RENDERER NAME SCENE ARGS...: RUNS runs → NAME.exr, NAME.r<i>.json
render() {
  r=$1 name=$2 scene=$3
  shift 3
  i=1
  while [ $i -le "$RUNS" ]; do
    "$VTEX" -q "$r" "$scene" -o "$name.exr" --stats "$name.r$i.json" --threads "$THREADS" "$@"
    i=$((i + 1))
  done
}
# record NAME KEY=VALUE...: compare NAME.exr with the truth of its distance, append a CSV row
record() {
  name=$1
  shift
  "$VTEX" compare "$name.exr" "truth_$d.exr" --json > "$name.cmp.json"
  python3 "$HELPER" row error_vs_time.csv "$@" "$name".r*.json "$name.cmp.json"
  tail -n 1 error_vs_time.csv
}

for d in near middle far; do
  echo "== $d: truth ($TRUTH_SPP spp)"
  "$VTEX" -q reference ${d}_sggx.toml -o truth_$d.exr --png truth_$d.png --spp "$TRUTH_SPP" \
    --stats truth_$d.json --threads "$THREADS"
  python3 -c "import json; s = json.load(open('truth_$d.json')); print('truth wall %.1f s' % s['wall_seconds'])"
  for spp in 1 4 16 64; do
    n=ref_${d}_$spp
    rm -f $n.r*.json
    render reference $n ${d}_sggx.toml --spp $spp
    record $n distance=$d renderer=reference spp=$spp
  done
  for f in neyret sggx; do
    for b in -1 0 1; do
      for spp in 1 4; do
        for sh in fast reference; do
          if [ $sh = reference ] && [ $spp != 1 ] && [ $b != 0 ]; then continue; fi
          n=tex_${d}_${f}_b${b}_s${spp}_$sh
          rm -f $n.r*.json
          render render $n ${d}_$f.toml --spp $spp --lod-bias $b --shading $sh
          record $n distance=$d renderer=texel lod_bias=$b spp=$spp filter=$f shading=$sh
        done
      done
    done
  done
done

python3 "$HELPER" report error_vs_time.csv error-vs-time error-vs-time-table.md
echo "end: $(uptime)"
echo "total $(( $(date +%s) - START )) s; results in $DIR"
