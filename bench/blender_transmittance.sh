#!/usr/bin/env bash
# Does Blender render a `vtex export`ed texel with the optical depth vtex renders it with? A bush
# texel is built, exported to OpenVDB at its finest level and rendered twice from the side: by
# `vtex render` (one unit cell, shell height 1, so reference space is world space) and by Blender's
# Cycles with a Principled Volume reading the `density` grid. The transmittance (1 − alpha) of the
# two images is compared pixel by pixel (bench/blender_transmittance.py; docs/export.md has the
# figures). Not part of CI: it wants Debian's blender (`apt-get install -y blender`, ~2 min).
#   bash bench/blender_transmittance.sh build/apps/vtex/vtex DIR [RESOLUTION=64] [SIZE=128] [SAMPLES=16]
set -euo pipefail
vtex=$(realpath "$1")
dir=$2
resolution=${3:-64}
size=${4:-128}
samples=${5:-16}
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
mkdir -p "$dir"
dir=$(realpath "$dir")
command -v blender >/dev/null || { echo "blender is not installed (apt-get install -y blender)" >&2; exit 1; }

"$vtex" -q pattern bush -o "$dir/bush.glb"
"$vtex" -q sample "$dir/bush.glb" -o "$dir/bush.vtl" --resolution "$resolution"
"$vtex" -q build "$dir/bush.vtl" -o "$dir/bush.vto"
# Three exports: OpenVDB's voxel centres (the default), Blender's, and Blender's with the density
# taken along the view (+y, nearly: the camera below) instead of averaged over directions.
"$vtex" -q export "$dir/bush.vto" -o "$dir/openvdb.vdb"
"$vtex" -q export "$dir/bush.vto" -o "$dir/blender.vdb" --voxel-centres blender
"$vtex" -q export "$dir/bush.vto" -o "$dir/along.vdb" --voxel-centres blender --along 0,1,0

# The unit square at z = 0 under a shell of height 1: X(u, v, w) = (u, v, w), the texel's
# reference cube in world units, as the export places it (--scale 1, no translation). A camera
# far to the side with a narrow field keeps the rays nearly parallel and off the floor.
position="0.5,-12,0.55"
look_at="0.5,0.5,0.5"
fov=5.5
cat >"$dir/plane.obj" <<'EOF'
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
f 1 2 3 4
EOF
cat >"$dir/scene.toml" <<EOF
[camera]
position = [${position}]
look_at = [${look_at}]
up = [0, 0, 1]
fov_y = ${fov}
width = ${size}
height = ${size}

[[light]]
type = "directional"
direction = [0, 0, -1]

[[texel]]
name = "bush"
volume = "bush.vto"
tau = 1

[[surface]]
mesh = "plane.obj"
texel = "bush"
height = 1
EOF
# 16 spp: alpha is exact per sample (no noise), the strata only antialias.
"$vtex" render "$dir/scene.toml" -o "$dir/vtex.exr" --spp 16 --lod-bias -4
: >"$dir/comparison.jsonl"
for variant in openvdb blender along; do
    blender -b --factory-startup --python "$here/blender_transmittance.py" -- \
        "$dir/$variant.vdb" "$dir/vtex.exr" "$dir" "$position" "$look_at" "$fov" "$size" "$samples" 2>&1 |
        grep '^VTEX_BLENDER' | sed "s/^VTEX_BLENDER {/{\"export\": \"$variant\", /" | tee -a "$dir/comparison.jsonl"
done
