#!/usr/bin/env bash
# Ingest throughput (triangles/s) and peak memory (max RSS) on a generated ~2M-triangle closed
# mesh (a torus of 1000 x 1000 quads), as .glb and as .obj; median of 3 runs of `vtex ingest`.
#   bench/ingest_throughput.sh [path/to/vtex] [work-dir]
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
vtex=${1:-$root/build/apps/vtex/vtex}
work=${2:-$(mktemp -d)}
mkdir -p "$work"
n=${VTEX_BENCH_GRID:-1000}

python3 - "$work" "$n" <<'PY'
import math, struct, sys, json
work, n = sys.argv[1], int(sys.argv[2])
R, r = 1.0, 0.35
pos = []
for i in range(n):
    u = 2 * math.pi * i / n
    for j in range(n):
        v = 2 * math.pi * j / n
        pos.append(((R + r * math.cos(v)) * math.cos(u), (R + r * math.cos(v)) * math.sin(u), r * math.sin(v)))
tris = []
for i in range(n):
    for j in range(n):
        a, b = i * n + j, ((i + 1) % n) * n + j
        c, d = ((i + 1) % n) * n + (j + 1) % n, i * n + (j + 1) % n
        tris.append((a, b, c)); tris.append((a, c, d))
with open(f"{work}/torus.obj", "w") as f:
    f.write("".join(f"v {x:.7g} {y:.7g} {z:.7g}\n" for x, y, z in pos))
    f.write("".join(f"f {a+1} {b+1} {c+1}\n" for a, b, c in tris))
pbytes = b"".join(struct.pack("<3f", *p) for p in pos)
ibytes = struct.pack(f"<{3*len(tris)}I", *[k for t in tris for k in t])
lo = [min(p[k] for p in pos) for k in range(3)]; hi = [max(p[k] for p in pos) for k in range(3)]
doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
       "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
       "buffers": [{"byteLength": len(pbytes) + len(ibytes)}],
       "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(pbytes)},
                       {"buffer": 0, "byteOffset": len(pbytes), "byteLength": len(ibytes)}],
       "accessors": [{"bufferView": 0, "componentType": 5126, "count": len(pos), "type": "VEC3", "min": lo, "max": hi},
                     {"bufferView": 1, "componentType": 5125, "count": 3 * len(tris), "type": "SCALAR"}]}
js = json.dumps(doc).encode(); js += b" " * (-len(js) % 4)
binary = pbytes + ibytes
with open(f"{work}/torus.glb", "wb") as f:
    f.write(struct.pack("<4sII", b"glTF", 2, 12 + 8 + len(js) + 8 + len(binary)))
    f.write(struct.pack("<I4s", len(js), b"JSON") + js + struct.pack("<I4s", len(binary), b"BIN\0") + binary)
print(f"generated {len(tris)} triangles, {len(pos)} vertices")
PY

triangles=$((2 * n * n))
printf '%-6s %12s %10s %14s %12s\n' format triangles seconds triangles/s max_rss_MB
for format in glb obj; do
    times=() rss=()
    for run in 1 2 3; do
        /usr/bin/time -v "$vtex" -q ingest "$work/torus.$format" -o "$work/out_$format.glb" 2> "$work/time.txt"
        times+=("$(awk -F': ' '/Elapsed \(wall clock\)/ {n=split($2,p,":"); s=0; for(i=1;i<=n;i++) s=s*60+p[i]; print s}' "$work/time.txt")")
        rss+=("$(awk -F': ' '/Maximum resident set size/ {print $2}' "$work/time.txt")")
    done
    median=$(printf '%s\n' "${times[@]}" | sort -g | sed -n 2p)
    medianRss=$(printf '%s\n' "${rss[@]}" | sort -g | sed -n 2p)
    awk -v f="$format" -v t="$triangles" -v s="$median" -v m="$medianRss" \
        'BEGIN { printf "%-6s %12d %10.2f %14.0f %12.0f\n", f, t, s, t / s, m / 1024 }'
done
