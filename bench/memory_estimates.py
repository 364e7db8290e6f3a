#!/usr/bin/env python3
"""The memory estimates of vtex sample, build, render and reference against measured peaks.

  bench/memory_estimates.py VTEX WORKDIR

Makes its inputs in WORKDIR (the bush pattern with 2000 and 20000 leaves sampled at 256^3 and
built; a one-quad plane, a 500x500-quad OBJ grid and a 4x4 field of bush texels), then, for
each command, takes

  * the estimate: the refusal's "needs about ..." with --max-memory 1KiB (exit 3, nothing done);
  * the peak: ru_maxrss of resource.getrusage(RUSAGE_CHILDREN), the command run without a limit
    from a helper process of its own (this script, --peak), so that each peak is one command's.

Prints two markdown tables: every command's estimate and peak, and the factors the estimates
are built from (renderer.h estimateRenderMemory, octree.h estimateBuildMemory) next to what the
peaks give for them. Stdlib only; about a minute on two cores.
"""
import os
import re
import resource
import subprocess
import sys
import time

MIB = 1 << 20
UNITS = {'KiB': 1 << 10, 'MiB': 1 << 20, 'GiB': 1 << 30}

PLANE_OBJ = 'v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n'
GRID = 500  # quads a side of grid.obj (about 11 MB)
FIELD = 4   # unit cells a side of the bush field

CAMERA = '''[camera]
position = [%s]
look_at = [%s]
width = 256
height = 256
'''
DIRECTIONAL = '[[light]]\ntype = "directional"\ndirection = [-1, -0.5, -1]\n'
# No shadow lattice for a point light: the scene's files alone above the plane's render.
POINT = '[[light]]\ntype = "point"\nposition = [0, 0, 4]\ncolor = [16, 16, 16]\n'
BUSH_TEXEL = '[[texel]]\nname = "bush"\nvolume = "bush.vto"\nsource = "bush.glb"\n'


def peak_main(argv):
    """--peak CMD...: run CMD (output discarded), print its peak resident memory in bytes."""
    done = subprocess.run(argv, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                          stderr=subprocess.PIPE, text=True)
    if done.returncode != 0:
        sys.exit('%s: exit %d: %s' % (' '.join(argv), done.returncode, done.stderr.strip()))
    print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * 1024)  # Linux: KiB


def vtex(binary, *args):
    subprocess.run([binary, '-q', *args], check=True, stdin=subprocess.DEVNULL)


def estimate(binary, args):
    """The estimate in the refusal of `vtex ARGS --max-memory 1KiB`: (text, bytes)."""
    done = subprocess.run([binary, *args, '--max-memory', '1KiB'], stdin=subprocess.DEVNULL,
                          capture_output=True, text=True)
    found = re.search(r'needs about ([0-9.]+) (KiB|MiB|GiB)', done.stderr)
    if done.returncode != 3 or not found:
        sys.exit('%s: expected a refusal (exit 3), got exit %d: %s'
                 % (' '.join(args), done.returncode, done.stderr.strip()))
    return found.group(1) + ' ' + found.group(2), float(found.group(1)) * UNITS[found.group(2)]


def peak(binary, args):
    out = subprocess.run([sys.executable, os.path.abspath(__file__), '--peak', binary, *args],
                         check=True, capture_output=True, text=True).stdout
    return int(out)


def write_grid(path, n, origin):
    """n×n unit quads in z = 0, their corner at (origin, origin)."""
    with open(path, 'w') as f:
        for j in range(n + 1):
            for i in range(n + 1):
                f.write('v %d %d 0\n' % (origin + i, origin + j))
        for j in range(n):
            for i in range(n):
                a = j * (n + 1) + i + 1
                f.write('f %d %d %d %d\n' % (a, a + 1, a + n + 2, a + n + 1))


def make_inputs(binary):
    for name, leaves in (('bush', 2000), ('bush20k', 20000)):
        vtex(binary, 'pattern', 'bush', '-o', name + '.glb', '--leaves', str(leaves))
    with open('plane.obj', 'w') as f:
        f.write(PLANE_OBJ)
    write_grid('grid.obj', GRID, 0)
    write_grid('field.obj', FIELD, -(FIELD // 2))
    field = '[[surface]]\nmesh = "field.obj"\ntexel = "bush"\n'
    scenes = {
        'plane.toml': CAMERA % ('0.5, -2, 1.5', '0.5, 0.5, 0') + DIRECTIONAL + '[[surface]]\nmesh = "plane.obj"\n',
        'grid.toml': CAMERA % ('250, -300, 400', '250, 250, 0') + DIRECTIONAL + '[[surface]]\nmesh = "grid.obj"\n',
        'field_point.toml': CAMERA % ('3, -5, 3.5', '0, 0, 0.5') + POINT + BUSH_TEXEL + field,
        'field.toml': CAMERA % ('3, -5, 3.5', '0, 0, 0.5') + DIRECTIONAL + BUSH_TEXEL + field,
    }
    for name, text in scenes.items():
        with open(name, 'w') as f:
            f.write(text)


def main():
    if len(sys.argv) > 1 and sys.argv[1] == '--peak':
        return peak_main(sys.argv[2:])
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    binary, workdir = os.path.abspath(sys.argv[1]), sys.argv[2]
    os.makedirs(workdir, exist_ok=True)
    os.chdir(workdir)
    start = time.monotonic()
    make_inputs(binary)

    big = ['--width', '4096', '--height', '4096']
    # (key, the command as the table shows it, its arguments); the samples come first: the
    # builds read their volumes, the renders the bush's octree.
    rows = [
        ('sample', 'sample bush.glb -r 256', ['sample', 'bush.glb', '-o', 'bush.vtl', '-r', '256']),
        ('sample20k', 'sample bush20k.glb -r 256', ['sample', 'bush20k.glb', '-o', 'bush20k.vtl', '-r', '256']),
        ('build', 'build bush.vtl', ['build', 'bush.vtl', '-o', 'bush.vto']),
        ('build20k', 'build bush20k.vtl', ['build', 'bush20k.vtl', '-o', 'bush20k.vto']),
        ('plane', 'render plane.toml (256x256) --png',
         ['render', 'plane.toml', '-o', 'out.exr', '--png', 'out.png']),
        ('plane4k', 'render plane.toml --width 4096 --height 4096 --png',
         ['render', 'plane.toml', '-o', 'out.exr', '--png', 'out.png', *big]),
        ('plane4kaov', 'render plane.toml --width 4096 --height 4096 --png --aov',
         ['render', 'plane.toml', '-o', 'out.exr', '--png', 'out.png', '--aov', *big]),
        ('grid', 'render grid.toml (256x256) --png', ['render', 'grid.toml', '-o', 'out.exr', '--png', 'out.png']),
        ('fieldpoint', 'render field_point.toml (256x256) --png',
         ['render', 'field_point.toml', '-o', 'out.exr', '--png', 'out.png']),
        ('field', 'render field.toml (256x256) --png', ['render', 'field.toml', '-o', 'out.exr', '--png', 'out.png']),
        ('reference', 'reference field.toml (256x256) --spp 1 --png',
         ['reference', 'field.toml', '-o', 'out.exr', '--png', 'out.png', '--spp', '1']),
    ]
    measured = {}
    for key, shown, args in rows:
        text, bytes_ = estimate(binary, args)
        measured[key] = (shown, text, bytes_, peak(binary, args))

    version = subprocess.run([binary, '--version'], capture_output=True, text=True).stdout.strip()
    print('%s, %d cores; `bench/memory_estimates.py %s %s`, %.0f s\n'
          % (version, os.cpu_count(), sys.argv[1], sys.argv[2], time.monotonic() - start))
    print('| command | estimate | peak RSS | estimate / peak |')
    print('| --- | ---: | ---: | ---: |')
    for shown, text, bytes_, rss in measured.values():
        print('| `vtex %s` | %s | %.1f MiB | %.3f%s |'
              % (shown, text, rss / MIB, bytes_ / rss, '' if bytes_ >= rss else ' (peak above)'))
    print('\nEstimates as the refusal prints them (to 1 MiB, or 0.1 GiB); field.toml\'s includes the'
          ' shadow lattices\' 256 MiB cap (a directional light), field_point.toml\'s does not.')

    size = os.path.getsize
    pixels = 4096 * 4096 - 256 * 256
    plane = measured['plane'][3]
    factors = [
        ('image, bytes a pixel (4096² − 256² renders of plane.toml, EXR and PNG)', '22',
         (measured['plane4k'][3] - plane) / pixels),
        ('image with --aov, bytes a pixel (the same)', '30', (measured['plane4kaov'][3] - plane) / pixels),
        ('base mesh, × its file (grid.obj above plane.toml, %.1f MB)' % (size('grid.obj') / 1e6), '10',
         (measured['grid'][3] - plane) / size('grid.obj')),
        ('octree and source mesh, × their files (field_point.toml above plane.toml, %.1f MB)'
         % ((size('bush.vto') + size('bush.glb')) / 1e6), '3',
         (measured['fieldpoint'][3] - plane) / (size('bush.vto') + size('bush.glb'))),
        ('build, peak × the .vtl (bush.vtl, %.1f MB)' % (size('bush.vtl') / 1e6), '12 (+ 32 MiB)',
         measured['build'][3] / size('bush.vtl')),
        ('build, peak × the .vtl (bush20k.vtl, %.1f MB)' % (size('bush20k.vtl') / 1e6), '12 (+ 32 MiB)',
         measured['build20k'][3] / size('bush20k.vtl')),
    ]
    print('\n| factor | in the estimate | measured |')
    print('| --- | ---: | ---: |')
    for name, assumed, value in factors:
        print('| %s | %s | %.1f |' % (name, assumed, value))


if __name__ == '__main__':
    main()
