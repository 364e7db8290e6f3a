#!/usr/bin/env python3
"""Helper of bench/bush_field.sh (stdlib only). Run in the work directory.

  bush_field.py plan WIDTH HEIGHT VARIANTS DENSE SWEEP BEFORE
        write ground.obj, the scenes ({far,mid,near}.toml; {far,mid,near}_dense.toml with DENSE=1;
        sweep_NN.toml and sweep.txt with SWEEP=1) and rows.txt, the renders to time, one a line:
        section|view|name|spp|command|arguments
  bush_field.py truth-key SCENE SPP MESH TRUTH_KEY
        print the cache key of a truth image (sha256 of the scene file, the spp, the source
        mesh and TRUTH_KEY) and write truth/KEY.txt saying what went into it
  bush_field.py report RUNS
        read rows.txt, truths.txt, out/*.json; write bush_field.csv and bush_field.md (table,
        goals, dense and sweep sections) and print the markdown
"""
import csv
import hashlib
import json
import math
import os
import re
import statistics
import sys

# The scene of issue 12. The three cameras lie on one line through LOOK_AT (distances 4.1, 31
# and 85 units), so the sweep can walk that line.
LOOK_AT = (0.0, 0.0, 0.5)
CAMERAS = {
    'far': (36.725582, -63.610577, 42.907051),
    'mid': (13.669476, -23.676228, 16.284151),
    'near': (1.784539, -3.090912, 2.560608),
}
VIEWS = ['far', 'mid', 'near']
GROUND = 20  # 20×20 unit quads in z = 0, centred on the origin
SWEEP_STEPS = 12
# The light; LIGHT="x, y, z" (bush_field.sh's environment) lights the field from another
# direction, to see how the texel's bias moves with the angle between the view and the light.
DEFAULT_LIGHT = (-1.0, -0.5, -1.0)


def light_direction():
    text = os.environ.get('LIGHT', '')
    if not text:
        return DEFAULT_LIGHT
    try:
        d = tuple(float(x) for x in text.split(','))
    except ValueError:
        d = ()
    if len(d) != 3 or not all(math.isfinite(x) for x in d) or not d[2] < 0:
        sys.exit('bush_field.py: LIGHT must be three numbers "x, y, z" with z < 0 (a light from above), not %r' % text)
    return d

SCENE = '''[camera]
position = [%.6f, %.6f, %.6f]
look_at  = [%g, %g, %g]
up       = [0, 0, 1]
fov_y    = 40
width    = %d
height   = %d

[[light]]
type      = "directional"
direction = [%s]
color     = [3, 3, 3]

[[texel]]
name     = "bush"
volume   = "%s.vto"
source   = "%s.glb"
material = { diffuse = [1, 1, 1], specular = [0, 0, 0], ambient = [0, 0, 0] }

[[surface]]
mesh      = "%s"
texel     = "bush"
height    = 1.0
placement = "on"
repeat    = [1, 1]
material  = { diffuse = [0.35, 0.28, 0.2], specular = [0, 0, 0], ambient = [0, 0, 0] }
'''

COLUMNS = ['section', 'view', 'distance', 'row', 'renderer', 'spp', 'args', 'runs', 'wall_seconds',
           'load_seconds', 'rmse', 'rmse_coarse', 'rmse_pixel', 'bias_r_pct', 'bias_g_pct', 'bias_b_pct',
           'mean_g', 'truth_mean_g', 'truth_spp', 'time_vs_ref16', 'time_vs_ref1']


def write_ground(n=GROUND, path='ground.obj'):
    """n×n unit quads in z = 0, centred on the origin, counter-clockwise seen from +z."""
    with open(path, 'w') as f:
        for j in range(n + 1):
            for i in range(n + 1):
                f.write('v %g %g 0\n' % (-n / 2 + i, -n / 2 + j))
        for j in range(n):
            for i in range(n):
                a = j * (n + 1) + i + 1
                f.write('f %d %d %d %d\n' % (a, a + 1, a + n + 2, a + n + 1))


def write_scene(path, position, width, height, bush='bush', mesh='ground.obj', volume=None):
    """`volume` (default: `bush`) names the .vto, `bush` the source mesh beside it."""
    with open(path, 'w') as f:
        light = ', '.join('%g' % x for x in light_direction())
        f.write(SCENE % (tuple(position) + LOOK_AT + (width, height, light, volume or bush, bush, mesh)))


def grid(n, width, height):
    """grid_N.obj, the field's ground widened to n×n quads, and grid_N.toml, seen from the far
    camera's direction at n/20 of its distance, so that the whole grid fills the image as the
    field does (bench/big_mesh.sh)."""
    mesh = 'grid_%d.obj' % n
    write_ground(n, mesh)
    s = n / GROUND
    position = tuple(c + (f - c) * s for f, c in zip(CAMERAS['far'], LOOK_AT))
    write_scene('grid_%d.toml' % n, position, width, height, mesh=mesh)


def distance(p):
    return math.dist(p, LOOK_AT)


def sweep_positions():
    """SWEEP_STEPS points on the segment near → far whose distances to LOOK_AT are spaced
    geometrically from the near camera's to the far camera's. Found by bisection on the segment
    parameter (the distance grows along it: the segment points away from LOOK_AT)."""
    near, far = CAMERAS['near'], CAMERAS['far']
    d0, d1 = distance(near), distance(far)
    out = []
    for k in range(SWEEP_STEPS):
        target = d0 * (d1 / d0) ** (k / (SWEEP_STEPS - 1))
        lo, hi = 0.0, 1.0
        for _ in range(60):
            t = 0.5 * (lo + hi)
            p = [a + t * (b - a) for a, b in zip(near, far)]
            lo, hi = (t, hi) if distance(p) < target else (lo, t)
        out.append([a + lo * (b - a) for a, b in zip(near, far)])
    return out


def parse_variants(text):
    """'name=args;name=args' → [(name, args)]; names become file names, so they are checked."""
    variants = []
    for item in filter(None, (s.strip() for s in text.split(';'))):
        name, sep, args = item.partition('=')
        name = name.strip()
        if not sep or not re.fullmatch(r'[A-Za-z0-9._+-]+', name) or name in ('texel', 'texel16', 'ref1', 'ref16'):
            sys.exit('bush_field.py: bad VARIANTS entry %r (want name=args, name of letters, digits, ._+-, '
                     'not a built-in row name)' % item)
        if '|' in args:
            sys.exit('bush_field.py: VARIANTS arguments cannot contain "|": %r' % item)
        variants.append((name, args.strip()))
    return variants


def plan(width, height, variants_text, dense, sweep, before):
    variants = parse_variants(variants_text)
    write_ground()
    rows = []
    for view in VIEWS:
        write_scene(view + '.toml', CAMERAS[view], width, height)
        rows += [('main', view, 'ref1', 1, 'reference', '--spp 1'),
                 ('main', view, 'ref16', 16, 'reference', '--spp 16'),
                 ('main', view, 'texel', 1, 'render', '')]
        # The older binary's texel (BEFORE), right after today's, from the texel that binary built
        # (bush.before.vto: an older binary may not read what today's writes).
        if before:
            write_scene(view + '.before.toml', CAMERAS[view], width, height, volume='bush.before')
            rows.append(('before', view, 'before', 1, 'render', ''))
        # The dense texel right after the sparse one: a round's two renders are seconds apart,
        # and the dense / sparse ratio is taken per round (dense_section).
        if dense:
            write_scene(view + '_dense.toml', CAMERAS[view], width, height, 'bush_dense')
            rows.append(('dense', view + '_dense', 'texel', 1, 'render', ''))
        if view == 'near':
            rows.append(('main', view, 'texel16', 16, 'render', '--spp 16'))
        for name, args in variants:
            spp = re.search(r'--spp\s+(\d+)', args)
            rows.append(('variant', view, name, int(spp.group(1)) if spp else 1, 'render', args))
    if dense:
        rows.append(('dense', 'near_dense', 'ref1', 1, 'reference', '--spp 1'))
    if sweep:
        with open('sweep.txt', 'w') as f:
            for k, p in enumerate(sweep_positions()):
                view = 'sweep_%02d' % (k + 1)
                write_scene(view + '.toml', p, width, height)
                f.write('%s %.6f\n' % (view, distance(p)))
                rows += [('sweep', view, 'ref1', 1, 'reference', '--spp 1'), ('sweep', view, 'texel', 1, 'render', '')]
    with open('rows.txt', 'w') as f:
        for r in rows:
            f.write('|'.join(str(x) for x in r) + '\n')


def sha256_file(path):
    h = hashlib.sha256()
    with open(path, 'rb') as f:
        for chunk in iter(lambda: f.read(1 << 20), b''):
            h.update(chunk)
    return h.hexdigest()


def truth_key(scene, spp, mesh, key):
    # The truth is the reference renderer's image of this scene: it changes with the scene text,
    # the sample count and the source mesh; TRUTH_KEY stands for the renderer itself, whose
    # sources are not at hand at run time (bump it when the reference renderer changes).
    with open(scene, 'rb') as f:
        text = f.read()
    parts = [hashlib.sha256(text).hexdigest(), 'spp=%d' % int(spp), 'mesh=' + sha256_file(mesh), 'key=' + key]
    digest = hashlib.sha256('\n'.join(parts).encode()).hexdigest()[:20]
    os.makedirs('truth', exist_ok=True)
    with open(os.path.join('truth', digest + '.txt'), 'w') as f:
        f.write('scene %s (sha256 %s)\nspp %d\nmesh %s (sha256 %s)\nTRUTH_KEY %s\n\n' % (
            scene, parts[0], int(spp), mesh, parts[2][5:], key))
        f.write(text.decode())
    print(digest)


# ---------------------------------------------------------------- report
def read_rows():
    rows = []
    with open('rows.txt') as f:
        for line in f:
            section, view, name, spp, command, args = line.rstrip('\n').split('|', 5)
            rows.append(dict(section=section, view=view, row=name, spp=int(spp), renderer=command, args=args))
    return rows


def read_truths():
    truths = {}
    if os.path.exists('truths.txt'):
        with open('truths.txt') as f:
            for line in f:
                view, spp, key, how = line.split()
                truths[view] = dict(spp=int(spp), key=key, how=how)
    return truths


def measure(r, runs):
    """Median wall/load seconds of the RUNS stats files; the comparison with the truth if any."""
    base = os.path.join('out', '%s.%s' % (r['view'], r['row']))
    walls, loads = [], []
    for i in range(1, runs + 1):
        with open('%s.r%d.json' % (base, i)) as f:
            s = json.load(f)
        walls.append(s['wall_seconds'])
        loads.append(s.get('load_seconds', 0.0))
    r.update(runs=runs, walls=walls, wall_seconds=statistics.median(walls), load_seconds=statistics.median(loads))
    if os.path.exists(base + '.cmp.json'):
        with open(base + '.cmp.json') as f:
            c = json.load(f)
        r.update(rmse=c['rmse'], rmse_coarse=c['rmse_coarse'], rmse_pixel=c['rmse_pixel'],
                 bias=[None if b is None else 100 * b for b in c['bias']], mean_g=c['mean_a'][1],
                 truth_mean_g=c['mean_b'][1])


def find(rows, view, name):
    return next((r for r in rows if r['view'] == view and r['row'] == name), None)


def round_ratio(r, base):
    """r's time over base's: the median of the rounds' own ratios. A round runs a view's rows
    seconds apart, and the machine's speed drifts between rounds by more than within one."""
    return statistics.median(a / b for a, b in zip(r['walls'], base['walls']))


def add_ratios(rows):
    for r in rows:
        for ref in ('ref16', 'ref1'):
            base = find(rows, r['view'], ref)
            if base is not None:
                r['time_vs_' + ref] = round_ratio(r, base)


def fmt(v, spec):
    return '' if v is None else spec % v


def write_csv(rows, distances, truths):
    with open('bush_field.csv', 'w', newline='') as f:
        w = csv.DictWriter(f, COLUMNS)
        w.writeheader()
        for r in rows:
            bias = r.get('bias') or [None] * 3
            w.writerow(dict(
                section=r['section'], view=r['view'], distance=fmt(distances.get(r['view']), '%.4f'), row=r['row'],
                renderer=r['renderer'], spp=r['spp'], args=r['args'], runs=r['runs'],
                wall_seconds='%.4f' % r['wall_seconds'], load_seconds='%.4f' % r['load_seconds'],
                rmse=fmt(r.get('rmse'), '%.6g'), rmse_coarse=fmt(r.get('rmse_coarse'), '%.6g'),
                rmse_pixel=fmt(r.get('rmse_pixel'), '%.6g'), bias_r_pct=fmt(bias[0], '%.3f'),
                bias_g_pct=fmt(bias[1], '%.3f'), bias_b_pct=fmt(bias[2], '%.3f'),
                mean_g=fmt(r.get('mean_g'), '%.6g'), truth_mean_g=fmt(r.get('truth_mean_g'), '%.6g'),
                truth_spp=truths.get(r['view'], {}).get('spp', ''),
                time_vs_ref16=fmt(r.get('time_vs_ref16'), '%.4g'), time_vs_ref1=fmt(r.get('time_vs_ref1'), '%.4g')))


def label(r):
    what = {'ref1': 'reference 1 spp', 'ref16': 'reference 16 spp', 'texel': 'texel (defaults)',
            'texel16': 'texel --spp 16', 'before': 'texel (defaults), BEFORE binary'}.get(r['row'], '%s: `%s`' % (r['row'], r['args']))
    return what


def bias_cell(r):
    if 'bias' not in r:
        return ''
    return ' / '.join('n/a' if b is None else '%+.1f' % b for b in r['bias'])


def main_table(rows, truths):
    out = ['| view | row | time s | × ref-16 | × ref-1 | RMSE | RMSE 4×4 | RMSE pixel | bias R / G / B % |',
           '| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |']
    for r in rows:
        if r['section'] not in ('main', 'before', 'variant'):
            continue
        out.append('| %s | %s | %.3f | %s | %s | %s | %s | %s | %s |' % (
            r['view'], label(r), r['wall_seconds'], fmt(r.get('time_vs_ref16'), '%.3g'),
            fmt(r.get('time_vs_ref1'), '%.3g'), fmt(r.get('rmse'), '%.4f'), fmt(r.get('rmse_coarse'), '%.4f'),
            fmt(r.get('rmse_pixel'), '%.4f'), bias_cell(r)))
    out.append('')
    out.append('Truth: ' + ', '.join('%s %d spp (%s)' % (v, truths[v]['spp'], truths[v]['how'])
                                     for v in VIEWS if v in truths) + '.')
    # The reference's jitter is a hash of (pixel, sample index): a reference row with the truth's
    # sample count draws the very same samples.
    same = [v for v in VIEWS if v in truths and truths[v]['spp'] in (1, 16)]
    if same:
        out.append('**Caution**: at %s the truth has the sample count of a reference row, which is then '
                   'the truth itself (error 0); the goals against it mean nothing.' % ', '.join(same))
    return out


def equal_error_section(rows):
    """What the texel's time is worth: the reference's time at each texel row's RMSE, on the
    reference's own trend between its 1- and 16-spp rows (time ∝ RMSE^−b, a straight line in
    log-log through the two), and the texel's time over it."""
    out = ['| view | row | RMSE | time s | reference at that RMSE s | texel / reference | b |',
           '| --- | --- | ---: | ---: | ---: | ---: | ---: |']
    for r in rows:
        if r['section'] not in ('main', 'before', 'variant') or r['row'] in ('ref1', 'ref16') or r.get('rmse') is None:
            continue
        one, sixteen = find(rows, r['view'], 'ref1'), find(rows, r['view'], 'ref16')
        if one is None or sixteen is None or not (one.get('rmse') or 0) > (sixteen.get('rmse') or 0) > 0:
            continue
        b = math.log(sixteen['wall_seconds'] / one['wall_seconds']) / math.log(one['rmse'] / sixteen['rmse'])
        reference = one['wall_seconds'] * (one['rmse'] / r['rmse']) ** b
        outside = not sixteen['rmse'] <= r['rmse'] <= one['rmse']
        out.append('| %s | %s | %.4f | %.3f | %.3f%s | %.3g | %.2f |' % (
            r['view'], label(r), r['rmse'], r['wall_seconds'], reference, ' (extrapolated)' if outside else '',
            r['wall_seconds'] / reference, b))
    return out


def check(goals, name, measured, limit, spec, limit_text):
    """Appends a table row `name | measured | ≤ limit (limit_text) | PASS/FAIL`; True on PASS."""
    ok = measured is not None and measured <= limit
    goals.append('| %s | %s | ≤ %s (%s) | %s |' % (name, fmt(measured, spec) or 'n/a', spec % limit, limit_text,
                                                  'PASS' if ok else 'FAIL'))
    return ok


def goals_section(rows):
    """The issue's goals for the default texel render, each PASS or FAIL."""
    g = ['| goal | measured | limit | result |', '| --- | ---: | --- | --- |']
    # view, row, the row its RMSE is held to and by what factor, the row its time is held to and the factor
    spec = [('far', 'texel', 'ref16', 1.0, 'ref16', 0.1), ('mid', 'texel', 'ref16', 1.0, 'ref16', 0.25),
            ('near', 'texel', 'ref1', 1.0, 'ref1', 1.5), ('near', 'texel16', 'ref16', 1.1, 'ref16', 1.5)]
    passed = 0
    for view, name, err_ref, err_factor, time_ref, time_factor in spec:
        r, e, t = find(rows, view, name), find(rows, view, err_ref), find(rows, view, time_ref)
        if r is None or e is None or t is None:
            continue
        who = '%s, %s' % (view, label(r))
        passed += check(g, who + ': RMSE', r.get('rmse'), err_factor * e['rmse'], '%.4f',
                        '%g × %s RMSE' % (err_factor, err_ref))
        passed += check(g, who + ': time / %s time' % time_ref, r['time_vs_' + time_ref], time_factor, '%.3f',
                        'median of the rounds\' ratios')
    for view in VIEWS:
        r = find(rows, view, 'texel')
        if r is None or 'bias' not in r:
            continue
        worst = None if None in r['bias'] else max(abs(b) for b in r['bias'])
        passed += check(g, '%s, texel (defaults): largest channel bias %%' % view, worst, 2.0, '%.2f', '± 2 %')
    total = len(g) - 2
    return ['%d of %d goals pass.' % (passed, total), ''] + g


def dense_section(rows):
    # The time goal, and the dense texel's own error against its own truth (a render that is
    # fast because it is wrong shows here).
    out = ['| view | sparse s | dense s | dense / sparse | goal ≤ 1.15 | dense RMSE | dense bias R / G / B % |',
           '| --- | ---: | ---: | ---: | --- | ---: | ---: |']
    for view in VIEWS:
        d, s = find(rows, view + '_dense', 'texel'), find(rows, view, 'texel')
        if d and s:
            ratio = round_ratio(d, s)
            goal = ('PASS' if ratio <= 1.15 else 'FAIL') if view != 'near' else '(none)'
            out.append('| %s | %.3f | %.3f | %.3f | %s | %s | %s |' % (
                view, s['wall_seconds'], d['wall_seconds'], ratio, goal,
                fmt(d.get('rmse'), '%.4f'), bias_cell(d) if 'bias' in d else 'n/a'))
    # Near, where the hybrid's mesh draws a dense bush, against ray tracing the dense mesh.
    d, r = find(rows, 'near_dense', 'texel'), find(rows, 'near_dense', 'ref1')
    if d and r:
        out += ['', 'Near, dense: texel %.3f s, RMSE %s; `vtex reference --spp 1` %.3f s, RMSE %s (texel / ref-1 time %.2f).' % (
            d['wall_seconds'], fmt(d.get('rmse'), '%.4f'), r['wall_seconds'], fmt(r.get('rmse'), '%.4f'),
            d['wall_seconds'] / r['wall_seconds'])]
    return out


def sweep_section(rows, distances, truths):
    out = ['| distance | truth spp | truth mean G | texel mean G | texel G bias % | texel RMSE | texel s | '
           'ref-1 mean G | ref-1 RMSE | ref-1 s | texel / ref-1 time |',
           '| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |']
    for view in sorted((v for v in distances if v.startswith('sweep_')), key=distances.get):
        t, r = find(rows, view, 'texel'), find(rows, view, 'ref1')
        if not t or not r or 'rmse' not in t:
            continue
        out.append('| %.2f | %d | %.5f | %.5f | %s | %.4f | %.3f | %.5f | %.4f | %.3f | %.3g |' % (
            distances[view], truths[view]['spp'], t['truth_mean_g'], t['mean_g'], fmt(t['bias'][1], '%+.1f'),
            t['rmse'], t['wall_seconds'], r['mean_g'], r['rmse'], r['wall_seconds'], t['time_vs_ref1']))
    return out


def report(runs):
    rows, truths = read_rows(), read_truths()
    for r in rows:
        measure(r, runs)
    add_ratios(rows)
    distances = {v: distance(p) for v, p in CAMERAS.items()}
    distances.update({v + '_dense': distance(CAMERAS[v]) for v in VIEWS})
    if os.path.exists('sweep.txt'):
        with open('sweep.txt') as f:
            distances.update({v: float(d) for v, d in (line.split() for line in f)})
    write_csv(rows, distances, truths)
    md = ['# Bush field (issue 12)', '', 'Median of %d run(s) per row, `wall_seconds` of `--stats`; times against '
          'the references (× ref-16, × ref-1, the goals, dense / sparse) are the medians of the rounds\' own ratios; '
          'errors against the truth by `vtex compare` (bias = row mean / truth mean − 1).' % runs, '']
    if light_direction() != DEFAULT_LIGHT:
        md += ['The light travels along (%s) (LIGHT), not the issue\'s (−1, −0.5, −1): the goals below are '
               'the issue\'s, for another scene.' % ', '.join('%g' % x for x in light_direction()), '']
    md += main_table(rows, truths)
    md += ['', '## At equal error', '', 'The reference\'s time at each texel row\'s RMSE, by the reference\'s trend '
           'between its 1- and 16-spp rows (time ∝ RMSE^−b); below 1 the texel is faster at equal error.', '']
    md += equal_error_section(rows)
    md += ['', '## Goals (default texel render)', ''] + goals_section(rows)
    if any(r['section'] == 'dense' for r in rows):
        md += ['', '## Dense bush (20 000 leaves, same 256³ resolution)', ''] + dense_section(rows)
    if any(r['section'] == 'sweep' for r in rows):
        md += ['', '## Distance sweep (defaults and the 1-spp reference, near → far)', '']
        md += sweep_section(rows, distances, truths)
    text = '\n'.join(md) + '\n'
    with open('bush_field.md', 'w') as f:
        f.write(text)
    print(text, end='')


if __name__ == '__main__':
    if len(sys.argv) == 8 and sys.argv[1] == 'plan':
        plan(int(sys.argv[2]), int(sys.argv[3]), sys.argv[4], sys.argv[5] == '1', sys.argv[6] == '1', sys.argv[7] == '1')
    elif len(sys.argv) == 6 and sys.argv[1] == 'truth-key':
        truth_key(*sys.argv[2:])
    elif len(sys.argv) == 3 and sys.argv[1] == 'report':
        report(int(sys.argv[2]))
    elif len(sys.argv) == 5 and sys.argv[1] == 'grid':
        grid(int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]))
    else:
        sys.exit(__doc__)
