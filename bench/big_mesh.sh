#!/bin/sh
# Issue 18, "one job must scale too": load time and peak memory of a big base mesh. An n×n grid
# of unit quads in z = 0 (n² faces, one OBJ), each carrying the bush texel, seen whole at
# WIDTH×HEIGHT from the bush field's far direction (the camera distance scaled with n, so the
# image stays alike). For each FACES count it renders RUNS times with `vtex render` and reports
# the median `load_seconds` and `wall_seconds` of stats.json and the median peak RSS
# (/usr/bin/time -v), and the peak RSS per face, which should stay flat (linear growth).
# Goal (issue 18): 10⁶ faces load and build their BVH in ≤ 1.5 s and ≤ 300 MB.
# Usage: bench/big_mesh.sh VTEX_BINARY [DIR] [RUNS] [THREADS]
#   (environment: FACES ("1000 10000 100000 1000000", rounded to squares), WIDTH, HEIGHT
#    (768×576), RESOLUTION (the texel's, 64: the texel is not what is measured), REFERENCE=1
#    also times `vtex reference` at 1 spp)
set -eu
VTEX=${1:?usage: big_mesh.sh VTEX_BINARY [DIR] [RUNS] [THREADS]}
case $VTEX in /*) ;; *) VTEX=$(pwd)/$VTEX ;; esac
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

# grid N: grid_N.obj (N×N unit quads centred on the origin) and grid_N.toml
grid() {
  python3 - "$1" "$WIDTH" "$HEIGHT" <<'PY'
import sys
n, width, height = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
with open('grid_%d.obj' % n, 'w') as f:
    f.write(''.join('v %g %g 0\n' % (-n / 2 + i, -n / 2 + j) for j in range(n + 1) for i in range(n + 1)))
    rows = []
    for j in range(n):
        a0 = j * (n + 1) + 1
        rows.append(''.join('f %d %d %d %d\n' % (a, a + 1, a + n + 2, a + n + 1) for a in range(a0, a0 + n)))
    f.write(''.join(rows))
# The bush field's far camera (85 units from a 20-unit field), scaled with the grid.
s = n / 20.0
p = (36.725582 * s, -63.610577 * s, 42.907051 * s + 0.5)
with open('grid_%d.toml' % n, 'w') as f:
    f.write('''[camera]
position = [%.6f, %.6f, %.6f]
look_at  = [0, 0, 0.5]
up       = [0, 0, 1]
fov_y    = 40
width    = %d
height   = %d

[[light]]
type      = "directional"
direction = [-1, -0.5, -1]
color     = [3, 3, 3]

[[texel]]
name     = "bush"
volume   = "bush.vto"
source   = "bush.glb"
material = { diffuse = [1, 1, 1], specular = [0, 0, 0], ambient = [0, 0, 0] }

[[surface]]
mesh      = "grid_%d.obj"
texel     = "bush"
height    = 1.0
placement = "on"
repeat    = [1, 1]
material  = { diffuse = [0.35, 0.28, 0.2], specular = [0, 0, 0], ambient = [0, 0, 0] }
''' % (p + (width, height, n)))
PY
}

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
  grid "$n"
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
      printf "| %s | %d | %d | %.3f | %.3f | %.1f | %.0f |\n", c, f, m, l, w, r / 1024, r * 1024 / f }' >> big_mesh.md
    awk -v c="$cmd" -v f="$faces" -v m="$mb" -v l="$load" -v w="$wall" -v r="$rss" 'BEGIN {
      printf "%s,%d,%d,%.4f,%.4f,%.1f\n", c, f, m, l, w, r / 1024 }' >> big_mesh.csv
  done
done
echo "vtex: $VTEX, $RUNS runs, $THREADS threads, ${WIDTH}×$HEIGHT, texel at $RESOLUTION³; $(uptime)" >> big_mesh.md
cat big_mesh.md
