#!/usr/bin/env python3
"""What storing a texel's source measures at build saves (docs/render.md, "Measured once, at build").

In a folder `bench/bush_field.sh` left (DENSE=1 for the 20 000-leaf rows), builds each texel again
with `vtex build --source` (bush.stored.vto, bush_dense.stored.vto), writes each view's scene with
that volume (VIEW.stored.toml), then per round renders every view with the plain texel and the
stored one, alternated, and `vtex reference VIEW.toml --spp 1`. Prints, per view, the medians of
`load_seconds`, `wall_seconds` and the end-to-end time (the process, timed here), the `.vto` bytes
read and whether the source mesh was read; every round checks that the two images are the same
bytes.

Usage: bench/stored_measures.py VTEX DIR [ROUNDS] [THREADS]   (5 rounds, 2 threads)
"""
import filecmp
import json
import os
import statistics
import subprocess
import sys
import time


def run(args):
    start = time.monotonic()
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL)
    return time.monotonic() - start


def main():
    vtex = os.path.abspath(sys.argv[1])
    folder = sys.argv[2]
    rounds = int(sys.argv[3]) if len(sys.argv) > 3 else 5
    threads = sys.argv[4] if len(sys.argv) > 4 else '2'
    os.chdir(folder)
    texels = [t for t in ('bush', 'bush_dense') if os.path.exists(t + '.vtl')]
    for t in texels:
        subprocess.run([vtex, '-q', 'build', t + '.vtl', '-o', t + '.stored.vto', '--source', t + '.glb'], check=True)
    views = []
    for t in texels:
        for view in ('far', 'mid', 'near'):
            name = view if t == 'bush' else view + '_dense'
            scene = open(name + '.toml').read()
            plain = '"%s.vto"' % t
            assert plain in scene, name
            open(name + '.stored.toml', 'w').write(scene.replace(plain, '"%s.stored.vto"' % t))
            views.append((t, name))
    rows = {}
    for _ in range(rounds):
        for t, name in views:
            for kind, scene in (('plain', name + '.toml'), ('stored', name + '.stored.toml')):
                seconds = run([vtex, 'render', scene, '-o', 'stored_%s.exr' % kind, '--threads', threads,
                               '--stats', 'stored_%s.json' % kind, '-q'])
                stats = json.load(open('stored_%s.json' % kind))
                rows.setdefault((name, kind), []).append(
                    (stats['load_seconds'], stats['wall_seconds'], seconds, stats['vto_bytes_read'],
                     stats['source_measures'][0], stats['source_loaded'][0]))
            if not filecmp.cmp('stored_plain.exr', 'stored_stored.exr', shallow=False):
                sys.exit('%s: the stored measures changed the image' % name)
            seconds = run([vtex, 'reference', name + '.toml', '--spp', '1', '-o', 'stored_ref.exr', '--threads',
                           threads, '-q'])
            rows.setdefault((name, 'ref1'), []).append((0, 0, seconds, 0, '', False))
    print('| view | load s plain → stored | render s | end to end s | 1-spp reference end to end s '
          '| .vto bytes read | mesh read |')
    print('| --- | --- | --- | --- | --- | --- | --- |')
    for _, name in views:
        plain, stored, ref = rows[(name, 'plain')], rows[(name, 'stored')], rows[(name, 'ref1')]
        assert plain[0][4] == 'measured' and stored[0][4] == 'stored', name
        med = lambda r, i: statistics.median(x[i] for x in r)
        print('| %s | %.3f → %.3f | %.3f → %.3f | %.2f → %.2f | %.2f | %.2f M → %.2f M | %s → %s |' % (
            name, med(plain, 0), med(stored, 0), med(plain, 1), med(stored, 1), med(plain, 2), med(stored, 2),
            med(ref, 2), plain[0][3] / 1e6, stored[0][3] / 1e6, 'yes' if plain[0][5] else 'no',
            'yes' if stored[0][5] else 'no'))


if __name__ == '__main__':
    main()
