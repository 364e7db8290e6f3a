#!/usr/bin/env python3
"""Helper of bench/error_vs_time.sh (stdlib only).

  error_vs_time.py scenes WIDTH HEIGHT          write terrain.obj and {near,middle,far}_{neyret,sggx}.toml
  error_vs_time.py row CSV KEY=VALUE... STATS.json... COMPARE.json
                                                append one CSV row (median wall/load over the stats files)
  error_vs_time.py report CSV SVG_PREFIX MD      plot (one SVG per distance + one with all three),
                                                speed-ups at equal error, markdown tables
"""
import csv
import json
import math
import os
import statistics
import sys

DISTANCES = ['near', 'middle', 'far']
COLUMNS = ['distance', 'renderer', 'lod_bias', 'spp', 'filter', 'shading', 'runs',
           'wall_seconds', 'load_seconds', 'rmse', 'psnr', 'ssim']

# Camera per distance: look-at point, distance to it, elevation (degrees). fov 40°: a pixel spans
# 2·tan(20°)/height radians. At 160×120: near (1.2) ≈ 1.1 px per 1/128 voxel at the look-at
# point (more nearer the camera); middle (8) ≈ 20 px per texel cell; far (50) ≈ 3.3 px per cell.
CAMERAS = {
    'near': ([0.5, 0.5, 0.45], 1.2, 45.0),
    'middle': ([0.5, 0.5, 0.45], 8.0, 45.0),
    'far': ([0.5, 0.5, 0.0], 50.0, 50.0),
}
TERRAIN = 80  # 80×80 unit quads, centred on the origin, gently undulating


def scenes(width, height):
    n = TERRAIN
    with open('terrain.obj', 'w') as f:
        for j in range(n + 1):
            for i in range(n + 1):
                x, y = -n / 2 + i, -n / 2 + j
                f.write('v %g %g %g\n' % (x, y, 0.6 * math.sin(0.15 * x) * math.cos(0.13 * y)))
        for j in range(n):
            for i in range(n):
                a = j * (n + 1) + i + 1
                f.write('f %d %d %d %d\n' % (a, a + 1, a + n + 2, a + n + 1))
    az = math.radians(-110.0)
    for name, (look, dist, elev) in CAMERAS.items():
        e = math.radians(elev)
        pos = [look[0] + dist * math.cos(e) * math.cos(az),
               look[1] + dist * math.cos(e) * math.sin(az),
               look[2] + dist * math.sin(e)]
        for filt in ('neyret', 'sggx'):
            with open('%s_%s.toml' % (name, filt), 'w') as f:
                f.write('''[camera]
position = [%.6f, %.6f, %.6f]
look_at  = [%g, %g, %g]
fov_y    = 40
width    = %d
height   = %d

[[light]]
type      = "directional"
direction = [-1, 0.6, -0.8]
color     = [3, 3, 3]

[[texel]]
name     = "bush"
volume   = "bush_%s.vto"
source   = "bush.glb"
material = { diffuse = [1, 1, 1], specular = [0.05, 0.05, 0.05], shininess = 20, ambient = [0.08, 0.08, 0.08] }

[[surface]]
mesh     = "terrain.obj"
texel    = "bush"
height   = 1.0
material = { diffuse = [0.35, 0.3, 0.22], ambient = [0.03, 0.03, 0.03] }
''' % (pos[0], pos[1], pos[2], look[0], look[1], look[2], width, height, filt))


def row(csv_path, args):
    fields = dict(a.split('=', 1) for a in args if '=' in a)
    files = [a for a in args if '=' not in a]
    stats, cmp_file = files[:-1], files[-1]
    walls, loads = [], []
    for s in stats:
        with open(s) as f:
            j = json.load(f)
        walls.append(j['wall_seconds'])
        loads.append(j['load_seconds'])
    with open(cmp_file) as f:
        c = json.load(f)
    fields.update(runs=len(walls), wall_seconds='%.4f' % statistics.median(walls),
                  load_seconds='%.4f' % statistics.median(loads), rmse='%.6g' % c['rmse'],
                  psnr='inf' if c['psnr'] is None else '%.3f' % c['psnr'], ssim='%.4f' % c['ssim'])
    new = not os.path.exists(csv_path)
    with open(csv_path, 'a', newline='') as f:
        w = csv.DictWriter(f, COLUMNS)
        if new:
            w.writeheader()
        w.writerow({k: fields.get(k, '') for k in COLUMNS})


def load(csv_path):
    with open(csv_path) as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        for k in ('wall_seconds', 'load_seconds', 'rmse', 'psnr', 'ssim'):
            r[k] = float(r[k])
        r['spp'] = int(r['spp'])
    return rows


def equal_error_time(ref, e):
    """Reference wall time at RMSE e: piecewise linear in (log time, log RMSE) between the
    reference's points (sorted by spp). Outside their RMSE range the nearest segment is extended
    (returned flag 'extrapolated')."""
    pts = sorted((math.log(r['rmse']), math.log(r['wall_seconds'])) for r in ref)  # ascending error
    le = math.log(e)
    if le < pts[0][0]:
        seg, flag = (pts[0], pts[1]), 'below'   # better than the most samples: extrapolated
    elif le > pts[-1][0]:
        seg, flag = (pts[-2], pts[-1]), 'above'  # worse than 1 spp: extrapolated
    else:
        for a, b in zip(pts, pts[1:]):
            if a[0] <= le <= b[0]:
                seg, flag = (a, b), ''
                break
    (e0, t0), (e1, t1) = seg
    t = t0 if e1 == e0 else t0 + (t1 - t0) * (le - e0) / (e1 - e0)
    return math.exp(t), flag


def config(r):
    return 'bias %+d, %d spp, %s, %s' % (int(float(r['lod_bias'])), r['spp'], r['filter'], r['shading'])


# ---------------------------------------------------------------- SVG
BIAS_COLOUR = {-1: '#1f77b4', 0: '#2ca02c', 1: '#ff7f0e'}


def marker(x, y, shape, colour, filled, size=5):
    fill = colour if filled else 'white'
    st = 'fill="%s" stroke="%s" stroke-width="1.5"' % (fill, colour)
    if shape == 'circle':
        return '<circle cx="%.1f" cy="%.1f" r="%.1f" %s/>' % (x, y, size, st)
    if shape == 'square':
        return '<rect x="%.1f" y="%.1f" width="%.1f" height="%.1f" %s/>' % (x - size, y - size, 2 * size, 2 * size, st)
    if shape == 'diamond':
        s = size * 1.3
        return '<polygon points="%.1f,%.1f %.1f,%.1f %.1f,%.1f %.1f,%.1f" %s/>' % (x, y - s, x + s, y, x, y + s, x - s, y, st)
    s = size * 1.3  # triangle
    return '<polygon points="%.1f,%.1f %.1f,%.1f %.1f,%.1f" %s/>' % (x, y - s, x + s, y + s * 0.8, x - s, y + s * 0.8, st)


def shape_of(r):
    return {('fast', 'neyret'): 'circle', ('fast', 'sggx'): 'diamond',
            ('reference', 'neyret'): 'square', ('reference', 'sggx'): 'triangle'}[(r['shading'], r['filter'])]


def decades(lo, hi):
    a, b = math.floor(math.log10(lo)), math.ceil(math.log10(hi))
    return a, b


def panel(rows, dist, ox, oy, w, h):
    """One log-log panel at (ox, oy), plot area w×h. Returns SVG elements."""
    tex = [r for r in rows if r['distance'] == dist and r['renderer'] == 'texel']
    ref = sorted([r for r in rows if r['distance'] == dist and r['renderer'] == 'reference'], key=lambda r: r['spp'])
    allr = tex + ref
    tlo, thi = decades(min(r['wall_seconds'] for r in allr) / 1.2, max(r['wall_seconds'] for r in allr) * 1.2)
    elo = math.log10(min(r['rmse'] for r in allr) / 1.15)
    ehi = math.log10(max(r['rmse'] for r in allr) * 1.15)
    elo, ehi = math.floor(elo * 4) / 4, math.ceil(ehi * 4) / 4

    def X(t):
        return ox + w * (math.log10(t) - tlo) / (thi - tlo)

    def Y(e):
        return oy + h - h * (math.log10(e) - elo) / (ehi - elo)

    out = ['<rect x="%d" y="%d" width="%d" height="%d" fill="none" stroke="#333"/>' % (ox, oy, w, h)]
    for d in range(tlo, thi + 1):
        x = X(10 ** d)
        out.append('<line x1="%.1f" y1="%d" x2="%.1f" y2="%d" stroke="#ddd"/>' % (x, oy, x, oy + h))
        out.append('<text x="%.1f" y="%d" font-size="11" text-anchor="middle">%s</text>' % (x, oy + h + 14, ('%g' % 10 ** d)))
        for m in range(2, 10):
            if d + math.log10(m) < thi:
                xm = X(m * 10 ** d)
                out.append('<line x1="%.1f" y1="%d" x2="%.1f" y2="%d" stroke="#999"/>' % (xm, oy + h, xm, oy + h - 4))
    # y ticks: 1, 2, 5 × 10^k inside the range
    for k in range(math.floor(elo) - 1, math.ceil(ehi) + 1):
        for m in (1, 2, 3, 5):
            v = m * 10 ** k
            if elo <= math.log10(v) <= ehi:
                y = Y(v)
                out.append('<line x1="%d" y1="%.1f" x2="%d" y2="%.1f" stroke="#ddd"/>' % (ox, y, ox + w, y))
                out.append('<text x="%d" y="%.1f" font-size="11" text-anchor="end">%g</text>' % (ox - 4, y + 4, v))
    out.append('<text x="%.1f" y="%d" font-size="12" text-anchor="middle">wall time (s, render only, log)</text>' % (ox + w / 2, oy + h + 30))
    out.append('<text x="%d" y="%.1f" font-size="12" text-anchor="middle" transform="rotate(-90 %d %.1f)">RMSE vs reference at 1024 spp (linear RGB, log)</text>' % (ox - 42, oy + h / 2, ox - 42, oy + h / 2))
    out.append('<text x="%.1f" y="%d" font-size="14" font-weight="bold" text-anchor="middle">%s</text>' % (ox + w / 2, oy - 8, dist))
    # reference curve
    pts = ' '.join('%.1f,%.1f' % (X(r['wall_seconds']), Y(r['rmse'])) for r in ref)
    out.append('<polyline points="%s" fill="none" stroke="black" stroke-width="2"/>' % pts)
    for r in ref:
        x, y = X(r['wall_seconds']), Y(r['rmse'])
        out.append('<circle cx="%.1f" cy="%.1f" r="3.5" fill="black"/>' % (x, y))
        out.append('<text x="%.1f" y="%.1f" font-size="10">%d spp</text>' % (x + 5, y - 5, r['spp']))
    for r in tex:
        out.append(marker(X(r['wall_seconds']), Y(r['rmse']), shape_of(r), BIAS_COLOUR[int(float(r['lod_bias']))], r['spp'] > 1))
    return out


def legend(ox, oy):
    out = ['<line x1="%d" y1="%d" x2="%d" y2="%d" stroke="black" stroke-width="2"/>' % (ox, oy, ox + 22, oy),
           '<circle cx="%d" cy="%d" r="3.5" fill="black"/>' % (ox + 11, oy),
           '<text x="%d" y="%d" font-size="11">reference renderer (explicit leaves), 1/4/16/64 spp</text>' % (ox + 30, oy + 4)]
    y = oy + 18
    for b, c in BIAS_COLOUR.items():
        out.append('<rect x="%d" y="%d" width="12" height="12" fill="%s"/>' % (ox + 5, y - 6, c))
        out.append('<text x="%d" y="%d" font-size="11">texel, lod-bias %+d</text>' % (ox + 30, y + 4, b))
        y += 16
    for shape, label in (('circle', 'fast shading, neyret filter'), ('diamond', 'fast shading, sggx filter'),
                         ('square', 'reference shading, neyret filter'), ('triangle', 'reference shading, sggx filter')):
        out.append(marker(ox + 11, y, shape, '#555', False, 4.5))
        out.append('<text x="%d" y="%d" font-size="11">%s</text>' % (ox + 30, y + 4, label))
        y += 16
    out.append(marker(ox + 6, y, 'circle', '#555', False, 4.5))
    out.append(marker(ox + 18, y, 'circle', '#555', True, 4.5))
    out.append('<text x="%d" y="%d" font-size="11">hollow: 1 spp, filled: 4 spp</text>' % (ox + 30, y + 4))
    return out


def svg(elements, w, h):
    return ('<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" viewBox="0 0 %d %d" '
            'font-family="sans-serif">\n<rect width="100%%" height="100%%" fill="white"/>\n%s\n</svg>\n'
            % (w, h, w, h, '\n'.join(elements)))


def report(csv_path, svg_prefix, md_path):
    rows = load(csv_path)
    dists = [d for d in DISTANCES if any(r['distance'] == d for r in rows)]
    pw, ph = 330, 280
    # one file per distance
    for d in dists:
        els = panel(rows, d, 70, 30, pw, ph) + legend(70 + pw + 20, 50)
        with open('%s-%s.svg' % (svg_prefix, d), 'w') as f:
            f.write(svg(els, 70 + pw + 400, ph + 80))
    # all distances in one file
    els = []
    for i, d in enumerate(dists):
        els += panel(rows, d, 70 + i * (pw + 80), 30, pw, ph)
    els += legend(70, ph + 90)
    with open('%s.svg' % svg_prefix, 'w') as f:
        f.write(svg(els, 70 + len(dists) * (pw + 80), ph + 240))

    md = []
    summary = []
    for d in dists:
        ref = sorted([r for r in rows if r['distance'] == d and r['renderer'] == 'reference'], key=lambda r: r['spp'])
        tex = [r for r in rows if r['distance'] == d and r['renderer'] == 'texel']
        ref64 = max(ref, key=lambda r: r['spp'])
        md.append('\n### %s\n' % d)
        md.append('| renderer | configuration | wall s | load s | RMSE | PSNR dB | SSIM | reference s at equal RMSE | speed-up |')
        md.append('| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |')
        for r in ref:
            md.append('| reference | %d spp | %.3f | %.3f | %.4f | %.2f | %.3f | | |' % (
                r['spp'], r['wall_seconds'], r['load_seconds'], r['rmse'], r['psnr'], r['ssim']))
        best = None
        for r in sorted(tex, key=lambda r: r['rmse']):
            t, flag = equal_error_time(ref, r['rmse'])
            s = t / r['wall_seconds']
            r['speedup'], r['flag'] = s, flag
            mark = {'': '', 'above': ' (ext.↑)', 'below': ' (ext.↓)'}[flag]
            md.append('| texel | %s | %.3f | %.3f | %.4f | %.2f | %.3f | %.3f%s | %.3g× |' % (
                config(r), r['wall_seconds'], r['load_seconds'], r['rmse'], r['psnr'], r['ssim'], t, mark, s))
            if best is None or s > best['speedup']:
                best = r
        lowest = min(tex, key=lambda r: r['rmse'])
        below64 = [r for r in tex if r['rmse'] < ref64['rmse']]
        summary.append((d, best, lowest, ref, below64, tex))
    head = ['| distance | best texel configuration (speed-up) | its RMSE | its wall s | reference RMSE 1 / 64 spp | reference s 1 / 64 spp | lowest texel RMSE (config) | texel below 64-spp error? |',
            '| --- | --- | ---: | ---: | ---: | ---: | --- | --- |']
    for d, best, lowest, ref, below64, tex in summary:
        mark = {'': '', 'above': ', extrapolated beyond 1 spp', 'below': ', extrapolated beyond 64 spp'}[best['flag']]
        head.append('| %s | %s (**%.3g×**%s) | %.4f | %.3f | %.4f / %.4f | %.3f / %.3f | %.4f (%s) | %s |' % (
            d, config(best), best['speedup'], mark, best['rmse'], best['wall_seconds'], ref[0]['rmse'], ref[-1]['rmse'],
            ref[0]['wall_seconds'], ref[-1]['wall_seconds'], lowest['rmse'], config(lowest),
            ('yes: %d of %d' % (len(below64), len(tex))) if below64 else 'no'))
    with open(md_path, 'w') as f:
        f.write('\n'.join(head + md) + '\n')
    print('\n'.join(head))


if __name__ == '__main__':
    cmd = sys.argv[1]
    if cmd == 'scenes':
        scenes(int(sys.argv[2]), int(sys.argv[3]))
    elif cmd == 'row':
        row(sys.argv[2], sys.argv[3:])
    elif cmd == 'report':
        report(sys.argv[2], sys.argv[3], sys.argv[4])
    else:
        sys.exit(__doc__)
