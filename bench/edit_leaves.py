#!/usr/bin/env python3
"""Moves a cluster of the bush pattern's leaves, for bench/partial_update.sh.

usage: edit_leaves.py IN.glb OUT.glb FRACTION N
The bush (vtex pattern bush) writes one POSITION accessor of 9 vertices a leaf (centre, then 8
on the rim), in leaf order. This moves the FRACTION of the leaves whose centres lie nearest to
(0.5, 0.55, 0.9) by (0.004, -0.003, 0.002) reference units, writes OUT.glb with the same layout,
and prints the region of an N³ grid the moved leaves touch before and after, as `vtex sample
--region` takes it (x0,y0,z0,x1,y1,z1, the maximum exclusive): voxel v holds a piece of a
triangle only if v <= its upper bound and v + 1 >= its lower bound.
"""
import json
import math
import struct
import sys

AT = (0.5, 0.55, 0.9)
OFFSET = (0.004, -0.003, 0.002)
LEAF = 9


def main():
    source, target, fraction, n = sys.argv[1], sys.argv[2], float(sys.argv[3]), int(sys.argv[4])
    data = bytearray(open(source, 'rb').read())
    json_length = struct.unpack_from('<I', data, 12)[0]
    gltf = json.loads(data[20:20 + json_length])
    binary = 20 + json_length + 8  # the BIN chunk's payload
    accessor = gltf['meshes'][0]['primitives'][0]['attributes']['POSITION']
    acc = gltf['accessors'][accessor]
    view = gltf['bufferViews'][acc['bufferView']]
    assert acc['componentType'] == 5126 and acc['type'] == 'VEC3' and view.get('byteStride', 12) == 12
    start = binary + view.get('byteOffset', 0) + acc.get('byteOffset', 0)
    count = acc['count']
    positions = [list(struct.unpack_from('<3f', data, start + 12 * i)) for i in range(count)]
    leaves = count // LEAF
    order = sorted(range(leaves), key=lambda l: math.dist(positions[LEAF * l], AT))
    moved = order[:max(1, round(fraction * leaves))]
    lo, hi = [math.inf] * 3, [-math.inf] * 3
    for leaf in moved:
        for v in range(LEAF * leaf, LEAF * leaf + LEAF):
            before = positions[v]
            after = list(struct.unpack('<3f', struct.pack('<3f', *[p + o for p, o in zip(before, OFFSET)])))
            for p in (before, after):
                lo = [min(a, b * n) for a, b in zip(lo, p)]
                hi = [max(a, b * n) for a, b in zip(hi, p)]
            positions[v] = after
            struct.pack_into('<3f', data, start + 12 * v, *after)
    # glTF requires the accessor's bounds; the JSON chunk keeps its length (padded with spaces).
    acc['min'] = [min(p[a] for p in positions) for a in range(3)]
    acc['max'] = [max(p[a] for p in positions) for a in range(3)]
    text = json.dumps(gltf, separators=(',', ':')).encode()
    assert len(text) <= json_length, 'JSON chunk grew'
    data[20:20 + json_length] = text + b' ' * (json_length - len(text))
    open(target, 'wb').write(data)
    region = [max(0, min(n, math.floor(x) - 1)) for x in lo] + [max(0, min(n, math.floor(x) + 1)) for x in hi]
    print(','.join(str(c) for c in region))


if __name__ == '__main__':
    main()
