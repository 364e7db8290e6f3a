#!/bin/sh
# What a render reads of a .vto (issue 13, "Leave out what a scene does not need"): the bush
# (2000 leaves) sampled at N³ (default 1024) on the bush field's ground (bench/bush_field.py: 20×20
# quads, one directional light), rendered from its far, mid and near cameras, with and without
# `source =` (with a source the renderer measures every level's chord transmittance against the
# mesh, which reads every level). Per row the medians over RUNS of `load_seconds` and
# `wall_seconds` and the `vto_bytes_read` of stats.json against the file's size; `vtex reference`
# at 1 spp the same. BEFORE=path/to/older/vtex adds its rows (it read the whole file).
#   usage: bench/lazy_levels.sh [path/to/vtex] [N] [RUNS]   (environment: WIDTH, HEIGHT, BEFORE)
set -eu
VTEX=${1:-build/apps/vtex/vtex}
N=${2:-1024}
RUNS=${3:-3}
WIDTH=${WIDTH:-384}
HEIGHT=${HEIGHT:-288}
BEFORE=${BEFORE:-}
case $VTEX in /*) ;; *) VTEX=$(pwd)/$VTEX ;; esac
case $BEFORE in /*|'') ;; *) BEFORE=$(pwd)/$BEFORE ;; esac
HERE=$(cd "$(dirname "$0")" && pwd)
DIR=$(mktemp -d)
trap 'rm -rf "$DIR"' EXIT
cd "$DIR"
"$VTEX" -q pattern bush -o bush.glb
"$VTEX" -q sample bush.glb -o bush.vtl -r "$N"
"$VTEX" -q build bush.vtl -o bush.vto
python3 - "$HERE" "$WIDTH" "$HEIGHT" <<'EOF'
import sys
sys.path.insert(0, sys.argv[1])
import bush_field as b
b.write_ground()
for view in b.VIEWS:
    b.write_scene(view + '-source.toml', b.CAMERAS[view], int(sys.argv[2]), int(sys.argv[3]))
    scene = open(view + '-source.toml').read()
    open(view + '.toml', 'w').write(scene.replace('source   = "bush.glb"\n', ''))
EOF
printf '%-8s %-9s %-6s %-10s %8s %8s %12s %12s\n' binary renderer view source load_s wall_s bytes_read file_bytes
# row BINARY NAME COMMAND VIEW SOURCE: RUNS renders, the medians of their stats.json
row() {
    bin=$1 name=$2 command=$3 view=$4 source=$5
    scene=$view.toml
    [ "$source" = yes ] && scene=$view-source.toml
    extra=""
    [ "$command" = reference ] && extra="--spp 1"
    for r in $(seq "$RUNS"); do
        # shellcheck disable=SC2086
        "$bin" -q "$command" "$scene" -o out.exr --stats "s$r.json" --threads 2 $extra
    done
    python3 - "$name" "$command" "$view" "$source" "$RUNS" "$(stat -c %s bush.vto)" <<'EOF'
import json, statistics, sys
name, command, view, source, runs, size = sys.argv[1:]
stats = [json.load(open('s%d.json' % r)) for r in range(1, int(runs) + 1)]
load = statistics.median(s['load_seconds'] for s in stats)
wall = statistics.median(s['wall_seconds'] for s in stats)
read = stats[0].get('vto_bytes_read', int(size))  # older builds read the whole file
print('%-8s %-9s %-6s %-10s %8.3f %8.3f %12d %12s' % (name, command, view, source, load, wall, read, size))
EOF
}
for view in far mid near; do
    for source in no yes; do
        row "$VTEX" this render "$view" "$source"
        [ -n "$BEFORE" ] && row "$BEFORE" before render "$view" "$source"
    done
done
row "$VTEX" this reference far yes
[ -n "$BEFORE" ] && row "$BEFORE" before reference far yes
exit 0
