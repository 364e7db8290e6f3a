#!/bin/sh
# Issue 18, "one job must scale too": load time and peak memory of a big base mesh. An n×n grid
# of unit quads in z = 0 (n² faces, one OBJ), each carrying the bush texel, seen whole at
# WIDTH×HEIGHT from the bush field's far direction (the camera distance scaled with n, so the
# image stays alike; the grid and its scene are bush_field.py's, `grid N`). For each FACES
# count it renders RUNS times with `vtex render` and reports the median `load_seconds` and
# `wall_seconds` of stats.json, the median peak RSS (/usr/bin/time -v), and the peak RSS per
# face, which should stay flat (linear growth).
# Goal (issue 18): 10⁶ faces load and build their BVH in ≤ 1.5 s and ≤ 300 MB.
# Usage: bench/big_mesh.sh VTEX_BINARY [DIR] [RUNS] [THREADS]
#   (environment: FACES ("1000 10000 100000 1000000", rounded to squares), WIDTH, HEIGHT
#    (768×576), RESOLUTION (the texel's, 64: the texel is not what is measured), REFERENCE=1
#    also times `vtex reference` at 1 spp)
set -eu
VTEX=${1:?usage: big_mesh.sh VTEX_BINARY [DIR] [RUNS] [THREADS]}
case $VTEX in /*) ;; *) VTEX=$(pwd)/$VTEX ;; esac
BENCH=$(cd "$(dirname "$0")" && pwd)
DIR=${2:-/tmp/vtex-big-mesh}
RUNS=${3:-${RUNS:-3}}
THREADS=${4:-${THREADS:-2}}
FACES=${FACES:-"1000 10000 100000 1000000"}
WIDTH=${WIDTH:-768}
HEIGHT=${HEIGHT:-576}
RESOLUTION=${RESOLUTION:-64}
REFERENCE=${REFERENCE:-0}
mkdir -p "$DIR"
cd "$DIR"
"$VTEX" -q pattern bush -o bush.glb
"$VTEX" -q sample bush.glb -o bush.vtl --resolution "$RESOLUTION"
"$VTEX" -q build bush.vtl -o bush.vto


# one CMD N RUN: a render of grid_N, its stats in CMD_N_RUN.json, its peak RSS (kB) printed
one() {
  /usr/bin/time -v "$VTEX" -q "$1" "grid_$2.toml" -o "$1_$2.exr" --stats "$1_$2_$3.json" \
    --threads "$THREADS" 2> "time_$1_$2_$3.txt" >/dev/null
  awk -F': ' '/Maximum resident set size/ {print $2}' "time_$1_$2_$3.txt"
}
median() { sort -g | awk '{v[NR]=$1} END {print v[int((NR+1)/2)]}'; }
field() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])" "$1" "$2"; }

CMDS=render
[ "$REFERENCE" = 1 ] && CMDS="render reference"
echo "| command | faces | obj MB | load s | render s | peak MB | peak bytes/face |" > big_mesh.md
echo "|---|---|---|---|---|---|---|" >> big_mesh.md
echo "command,faces,obj_mb,load_seconds,wall_seconds,peak_mb" > big_mesh.csv
for f in $FACES; do
  n=$(python3 -c "import math; print(max(1, round(math.sqrt($f))))")
  python3 "$BENCH/bush_field.py" grid "$n" "$WIDTH" "$HEIGHT"
  for cmd in $CMDS; do
    : > rss.txt; : > load.txt; : > wall.txt
    r=1
    while [ "$r" -le "$RUNS" ]; do
      one "$cmd" "$n" "$r" >> rss.txt
      field "${cmd}_${n}_$r.json" load_seconds >> load.txt
      field "${cmd}_${n}_$r.json" wall_seconds >> wall.txt
      r=$((r + 1))
    done
    faces=$((n * n))
    mb=$(du -m "grid_$n.obj" | cut -f1)
    load=$(median < load.txt); wall=$(median < wall.txt); rss=$(median < rss.txt)
    awk -v c="$cmd" -v f="$faces" -v m="$mb" -v l="$load" -v w="$wall" -v r="$rss" 'BEGIN {
      printf "| %s | %d | %d | %.3f | %.3f | %.1f | %.0f |\n", c, f, m, l, w, r / 1024, r * 1024 / f >> "big_mesh.md"
      printf "%s,%d,%d,%.4f,%.4f,%.1f\n", c, f, m, l, w, r / 1024 >> "big_mesh.csv" }'
  done
done
echo "vtex: $VTEX, $RUNS runs, $THREADS threads, ${WIDTH}×$HEIGHT, texel at $RESOLUTION³; $(uptime)" >> big_mesh.md
cat big_mesh.md
