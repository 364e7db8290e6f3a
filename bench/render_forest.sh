#!/bin/sh
# The forest benchmark of issue 5: ~600 bilinear faces on a hill covered with a 128³ `bush`
# texel, 768×576, 1 ray per pixel, one directional light with shadows. Prints the median wall
# time (of RUNS renders) of: the texel render, an Embree primary-ray render of the bare base
# mesh (no texel, no light), and the texel render of a 10× denser bush sampled at the same
# resolution. Usage: bench/render_forest.sh VTEX_BINARY [WORKDIR] [RUNS] [THREADS]
set -eu
VTEX=${1:?usage: render_forest.sh VTEX_BINARY [WORKDIR] [RUNS] [THREADS]}
DIR=${2:-/tmp/vtex-forest}
RUNS=${3:-3}
THREADS=${4:-2}
mkdir -p "$DIR"
cd "$DIR"
"$VTEX" -q pattern bush -o bush.glb
"$VTEX" -q pattern bush --leaves 20000 -o bush_dense.glb
for b in bush bush_dense; do
  "$VTEX" -q sample $b.glb -o $b.vtl --resolution 128
  "$VTEX" -q build $b.vtl -o $b.vto
done
python3 - <<'PY'
import math
nx, ny = 25, 24
with open('hill.obj', 'w') as f:
    for j in range(ny + 1):
        for i in range(nx + 1):
            x = -12.5 + 25 * i / nx; y = -12 + 24 * j / ny
            f.write('v %g %g %g\n' % (x, y, 3 * math.exp(-(x * x + y * y) / 60) + 0.4 * math.sin(0.5 * x) * math.cos(0.4 * y)))
    for j in range(ny):
        for i in range(nx):
            a = j * (nx + 1) + i + 1
            f.write('f %d %d %d %d\n' % (a, a + 1, a + nx + 2, a + nx + 1))
PY
camera='[camera]
position = [0, -22, 9]
look_at  = [0, 0, 1.5]
fov_y    = 40
width    = 768
height   = 576
'
light='[[light]]
type      = "directional"
direction = [-1, 0.6, -0.8]
color     = [3, 3, 3]
'
for b in bush bush_dense; do
  cat > forest_$b.toml <<EOT
$camera
$light
[[texel]]
name = "bush"
volume = "$b.vto"
material = { diffuse = [1, 1, 1], specular = [0.05, 0.05, 0.05], shininess = 20, ambient = [0.08, 0.08, 0.08] }

[[surface]]
mesh      = "hill.obj"
texel     = "bush"
height    = 1.0
material  = { diffuse = [0.35, 0.3, 0.22], ambient = [0.03, 0.03, 0.03] }
EOT
done
cat > bare.toml <<EOT
$camera
[[surface]]
mesh = "hill.obj"
material = { diffuse = [0.35, 0.3, 0.22], ambient = [0.03, 0.03, 0.03] }
EOT
median() { sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
run() {  # scene name
  for i in $(seq "$RUNS"); do
    "$VTEX" -q render "$1.toml" -o "$1.exr" --png "$1.png" --stats "$1.json" --threads "$THREADS"
    python3 -c "import json;print(json.load(open('$1.json'))['wall_seconds'])"
  done | median
}
texel=$(run forest_bush)
bare=$(run bare)
dense=$(run forest_bush_dense)
echo "texel render (2000 leaves): $texel s"
echo "bare base mesh (primary rays only): $bare s"
echo "texel render (20000 leaves): $dense s"
python3 -c "print('ratio texel/bare: %.1f, dense/sparse: %.3f' % ($texel / $bare, $dense / $texel))"
python3 -c "import json;s=json.load(open('forest_bush.json'));print('rays', s['rays'], 'voxels', s['voxels_visited'], 'mean level %.2f' % s['mean_level'])"
