#!/usr/bin/env python3
"""Where the bush field's bias is: each view's image split into what the ground and the leaves
contribute (docs/error-vs-time.md, "Levels fitted to the source").

For each of far.toml and mid.toml in DIR (written by bench/bush_field.sh, with its bush.vto and
bush.glb) three variants are made beside it:
  *_gcov  ground seen: no light, leaves black, the ground's ambient 1 (the fraction of ground the
          bushes let through);
  *_bl    lit ground: the leaves' diffuse 0 (black leaves);
  *_lcov  leaves seen: no light, the ground black, the leaves' ambient 1 (their coverage, with
          their albedo: what the lit leaves' bias is, less their lighting);
  *_bg    lit leaves: the ground's diffuse 0.
Each variant's truth is `vtex reference --spp SPP` (cached as DIR/truth_VARIANT.exr, reused when
present), the image and each variant are rendered with `vtex render ARGS...`, and one markdown row
per view gives the bias (row mean / truth mean − 1) of R/G/B for the image, and of G for the four
variants, and the image's RMSE against DIR/truth_VIEW.exr (bush_field.sh's truth).

With BORDER=K in the environment, the ground seen and the lit ground are also split between the
field's interior and its K outer rows of cells (the ground written as inner.obj and ring.obj, the
other part black; truths cached as DIR/truth_VIEW_{gcov,bl}{in,ring}.exr): one more row per view.
With BANDS=N, a second table gives each variant's green bias per band of N bands of the image's
rows, top (far from the camera) to bottom (`vtex compare --bands`); "–" where the truth is black.

Usage: bench/bush_field_decompose.py VTEX DIR [SPP] [-- RENDER ARGS...]
  e.g. bench/bush_field_decompose.py build/apps/vtex/vtex /tmp/bfbench 256 -- --level-fit off
       BORDER=3 bench/bush_field_decompose.py build/apps/vtex/vtex /tmp/bfbench 256
"""
import json
import os
import re
import subprocess
import sys

LEAVES = 'material = { diffuse = [1, 1, 1], specular = [0, 0, 0], ambient = [0, 0, 0] }'
GROUND = 'material  = { diffuse = [0.35, 0.28, 0.2], specular = [0, 0, 0], ambient = [0, 0, 0] }'


def variant(text, name):
    if name == 'gcov':
        text = re.sub(r'\[\[light\]\]\n(.*\n){3}', '', text)
        text = text.replace(LEAVES, LEAVES.replace('diffuse = [1, 1, 1]', 'diffuse = [0, 0, 0]'))
        return text.replace(GROUND, 'material  = { diffuse = [0, 0, 0], specular = [0, 0, 0], ambient = [1, 1, 1] }')
    if name == 'lcov':
        text = re.sub(r'\[\[light\]\]\n(.*\n){3}', '', text)
        text = text.replace(GROUND, GROUND.replace('diffuse = [0.35, 0.28, 0.2]', 'diffuse = [0, 0, 0]'))
        return text.replace(LEAVES, 'material = { diffuse = [0, 0, 0], specular = [0, 0, 0], ambient = [1, 1, 1] }')
    if name == 'bl':
        return text.replace(LEAVES, LEAVES.replace('diffuse = [1, 1, 1]', 'diffuse = [0, 0, 0]'))
    return text.replace(GROUND, GROUND.replace('diffuse = [0.35, 0.28, 0.2]', 'diffuse = [0, 0, 0]'))


NAMES = {'gcov': 'ground seen', 'bl': 'lit ground', 'lcov': 'leaves seen', 'bg': 'lit leaves'}


def compare(vtex, a, b, bands=0):
    args = [vtex, 'compare', a, b, '--json'] + (['--bands', str(bands)] if bands else [])
    return json.loads(subprocess.run(args, check=True, capture_output=True, text=True).stdout)


def band_biases(comparison):
    """The green bias per band, in %, or None where the truth's band is black."""
    return [None if band['bias'][1] is None else 100 * band['bias'][1] for band in comparison.get('bands', [])]


def split_ground(border):
    """ground.obj's faces into inner.obj (at least `border` units inside the field's edge) and
    ring.obj (the rest)."""
    vertices, faces = [], []
    with open('ground.obj') as f:
        for line in f:
            if line.startswith('v '):
                vertices.append(tuple(float(x) for x in line.split()[1:3]))
            elif line.startswith('f '):
                faces.append([int(x.split('/')[0]) for x in line.split()[1:]])
    lo = [min(v[k] for v in vertices) for k in (0, 1)]
    hi = [max(v[k] for v in vertices) for k in (0, 1)]
    parts = {'inner.obj': [], 'ring.obj': []}
    for face in faces:
        c = [sum(vertices[i - 1][k] for i in face) / len(face) for k in (0, 1)]
        inner = all(c[k] - lo[k] > border and hi[k] - c[k] > border for k in (0, 1))
        parts['inner.obj' if inner else 'ring.obj'].append(face)
    for name, part in parts.items():
        with open(name, 'w') as f:
            f.writelines('v %r %r 0\n' % v for v in vertices)
            f.writelines('f ' + ' '.join(map(str, face)) + '\n' for face in part)


def part_variant(text, name, lit):
    """Variant `name` ('gcov' or 'bl') with only the ground part `lit` ('in' or 'ring') showing."""
    text = variant(text, name)
    head, surface = text[:text.index('[[surface]]')], text[text.index('[[surface]]'):]
    material = re.search(r'material\s*=\s*\{[^}]*\}', surface).group(0)
    black = 'material = { diffuse = [0, 0, 0], specular = [0, 0, 0], ambient = [0, 0, 0] }'
    inner = surface.replace('ground.obj', 'inner.obj')
    ring = surface.replace('ground.obj', 'ring.obj')
    inner, ring = (inner, ring.replace(material, black)) if lit == 'in' else (inner.replace(material, black), ring)
    return head + inner + '\n' + ring


def main():
    args = sys.argv[1:]
    extra = []
    if '--' in args:
        extra = args[args.index('--') + 1:]
        args = args[:args.index('--')]
    if len(args) < 2:
        sys.exit(__doc__)
    vtex, folder = os.path.abspath(args[0]), args[1]
    spp = args[2] if len(args) > 2 else '256'
    border = int(os.environ['BORDER']) if os.environ.get('BORDER') else None
    bands = int(os.environ['BANDS']) if os.environ.get('BANDS') else 0
    by_band = []  # (row label, green bias per band)
    os.chdir(folder)
    if border is not None:
        split_ground(border)
    print('| view | image R / G / B % | ground seen / lit ground / leaves seen / lit leaves (G) % | image RMSE |')
    print('| --- | --- | --- | ---: |')
    for view in ('far', 'mid'):
        with open(view + '.toml') as f:
            text = f.read()
        biases = []
        for name in ('gcov', 'bl', 'lcov', 'bg'):
            scene = '%s_%s.toml' % (view, name)
            with open(scene, 'w') as f:
                f.write(variant(text, name))
            truth = 'truth_%s_%s.exr' % (view, name)
            if not os.path.exists(truth):
                subprocess.run([vtex, 'reference', scene, '-o', truth, '--spp', spp, '-q'], check=True)
            subprocess.run([vtex, 'render', scene, '-o', 'decompose.exr', '-q'] + extra, check=True)
            c = compare(vtex, 'decompose.exr', truth, bands)
            biases.append(100 * c['bias'][1])
            by_band.append(('%s %s' % (view, NAMES[name]), band_biases(c)))
        subprocess.run([vtex, 'render', view + '.toml', '-o', 'decompose.exr', '-q'] + extra, check=True)
        image = compare(vtex, 'decompose.exr', 'truth_%s.exr' % view, bands)
        by_band.append(('%s image' % view, band_biases(image)))
        print('| %s | %s | %s | %.5f |' % (view, ' / '.join('%+.1f' % (100 * b) for b in image['bias']),
                                           ' / '.join('%+.1f' % b for b in biases), image['rmse']))
        if border is not None:
            parts = []
            for lit in ('in', 'ring'):
                for name in ('gcov', 'bl'):
                    scene = '%s_%s%s.toml' % (view, name, lit)
                    with open(scene, 'w') as f:
                        f.write(part_variant(text, name, lit))
                    truth = 'truth_%s_%s%s.exr' % (view, name, lit)
                    if not os.path.exists(truth):
                        subprocess.run([vtex, 'reference', scene, '-o', truth, '--spp', spp, '-q'], check=True)
                    subprocess.run([vtex, 'render', scene, '-o', 'decompose.exr', '-q'] + extra, check=True)
                    c = compare(vtex, 'decompose.exr', truth, bands)
                    parts.append(100 * c['bias'][1])
                    by_band.append(('%s %s, %s' % (view, NAMES[name], 'interior' if lit == 'in' else 'outer rows'),
                                    band_biases(c)))
            print('| %s, interior / %d outer rows | ground seen / lit ground: %+.1f / %+.1f %% | %+.1f / %+.1f %% | |'
                  % (view, border, parts[0], parts[1], parts[2], parts[3]))
    if bands:
        print('\n| green bias %% by band of rows, top to bottom | %s |' % ' | '.join(str(k + 1) for k in range(bands)))
        print('| --- |%s' % (' ---: |' * bands))
        for label, values in by_band:
            print('| %s | %s |' % (label, ' | '.join('–' if v is None else '%+.1f' % v for v in values)))


if __name__ == '__main__':
    main()
