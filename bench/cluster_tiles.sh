#!/bin/bash
# Tiles on a Slurm cluster (issue 18): examples/fur-torus's texel render and its 16-spp reference,
# each in N row tiles, submitted with `vtex run --executor slurm`, the texel already cached.
# Per N: the wall time from the submission to the last job's end (polling squeue every 0.1 s),
# and the render work the stages' stats record (a tiled render's: its tiles' summed). On one node
# the difference between 1 and N tiles is overhead (scheduling, one process start, scene load and
# BVH build per tile), not speed-up. Medians over RUNS.
#   usage: bench/cluster_tiles.sh [path/to/vtex] [RUNS] [tiles...]    (needs SLURM_CONF set:
#          eval "$(bash scripts/slurm-cluster.sh start /tmp/slurm)" as root starts a one-node cluster)
set -euo pipefail
VTEX=${1:-build/apps/vtex/vtex}
RUNS=${2:-3}
shift 2 || true
TILES=${*:-1 4}
case $VTEX in /*) ;; *) VTEX=$(pwd)/$VTEX ;; esac
: "${SLURM_CONF:?set SLURM_CONF to a running cluster (scripts/slurm-cluster.sh start DIR)}"
HERE=$(cd "$(dirname "$0")/.." && pwd)
DIR=$(mktemp -d)
trap 'rm -rf "$DIR"' EXIT
cp -r "$HERE"/examples/fur-torus/. "$DIR"/
# pN.toml: the example with `tiles = N` in each [[render]] (its output is DIR/out for every N, so
# the texel is shared).
for n in $TILES; do
    python3 - "$DIR/pipeline.toml" "$DIR/p$n.toml" "$n" <<'PY'
import sys
source, target, n = sys.argv[1:]
blocks = open(source).read().split("[[")
for i, b in enumerate(blocks):
    if b.startswith("render]]"):
        lines = b.split("\n")
        lines.insert(1, "tiles = " + n)
        blocks[i] = "\n".join(lines)
open(target, "w").write("[[".join(blocks))
PY
done
wait_for() {  # the jobs of the last submission, until none is pending or running
    local ids
    ids=$(python3 -c 'import json,sys; print(",".join(j["job"] for j in json.load(open(sys.argv[1]))["jobs"]))' "$DIR/out/slurm/jobs.json")
    [[ -z $ids ]] && return 0
    while squeue -h -t PENDING,RUNNING,CONFIGURING,COMPLETING -j "$ids" -o %i 2>/dev/null | grep -q .; do sleep 0.1; done
}
# The texel, once.
first=$(echo $TILES | cut -d' ' -f1)
"$VTEX" -q run "$DIR/p$first.toml" --executor slurm
wait_for
median() { sort -n | awk '{v[NR] = $1} END {print v[int((NR + 1) / 2)]}'; }
printf '%6s %10s %12s %12s\n' tiles jobs wall_s render_work_s
for n in $TILES; do
    : >"$DIR/wall" ; : >"$DIR/work"
    for ((r = 0; r < RUNS; ++r)); do
        rm -rf "$DIR/out/tiles" "$DIR/out/renders" "$DIR/out/compares"
        start=$(date +%s.%N)
        "$VTEX" -q run "$DIR/p$n.toml" --executor slurm
        wait_for
        end=$(date +%s.%N)
        echo "$end - $start" | bc >>"$DIR/wall"
        python3 -c 'import json,sys
s = sum(json.load(open(f))["wall_seconds"] for f in sys.argv[1:])
print(s)' "$DIR"/out/renders/*.stats.json >>"$DIR/work"
        jobs=$(python3 -c 'import json,sys; print(len(json.load(open(sys.argv[1]))["jobs"]))' "$DIR/out/slurm/jobs.json")
    done
    printf '%6s %10s %12.2f %12.2f\n' "$n" "$jobs" "$(median <"$DIR/wall")" "$(median <"$DIR/work")"
done
