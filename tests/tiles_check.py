"""Checks of `roadsplat tiles` output for tests/cli_tiles_test.sh (pure
Python; PNGs through tests/png_read.py, independent of cli/png.c).

  tiles_check.py manifest OUTDIR          every listed hash = the file's, every file listed
  tiles_check.py window TILE WIN.png      TILE = WIN padded with transparent pixels
  tiles_check.py parent OUTDIR Z X Y [n]  tile = 2x2 box filter of its children on disk
                                          (n: the normal layer, the renormalised vector mean)
  tiles_check.py halo OUTDIR              every halo pixel = the neighbour tile's pixel
  tiles_check.py seam A B Z LIMIT         level-Z tiles of A that differ from B's: mean |diff| < LIMIT
  tiles_check.py normal_window TILE WIN.png  normal TILE = WIN, alpha 0 beyond it
  tiles_check.py sparse OUTDIR WEIGHT.pgm tiles finer than dense_max exist iff they hold a road
  tiles_check.py mbtiles FILE OUTDIR      the MBTiles rows (TMS) = the folder's tiles (normal_tiles: the _n ones)
  tiles_check.py same A.png B.png          the same pixels (RGBA; the main command's PNG and a tile are
                                          compressed by different libraries: docs/tiles.md)
"""
import hashlib, json, math, os, sqlite3, sys
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from png_read import read


def rgba(path):
    w, h, ch, px = read(path)
    if ch == 4:
        return w, h, bytes(px)
    out = bytearray(w * h * 4)
    for i in range(w * h):
        out[4 * i:4 * i + 3] = px[3 * i:3 * i + 3]
        out[4 * i + 3] = 255
    return w, h, bytes(out)


def manifest(d):
    m = json.load(open(os.path.join(d, 'tiles.json')))
    listed = m['tiles']
    on_disk = set()
    for root, _, files in os.walk(d):
        for f in files:
            if f.endswith('.png'):
                rel = os.path.relpath(os.path.join(root, f), d)[:-4]
                on_disk.add(rel)
    assert on_disk == set(listed), 'files %d, listed %d' % (len(on_disk), len(listed))
    for k, h in listed.items():
        assert hashlib.sha256(open(os.path.join(d, k + '.png'), 'rb').read()).hexdigest() == h, k
    assert m['tiles_written'] + m.get('normal_tiles_written', 0) == len(listed)
    return m


def window(tile, win):
    tw, th, t = rgba(tile)
    ww, wh, w = rgba(win)
    for y in range(th):
        for x in range(tw):
            a = t[4 * (y * tw + x):4 * (y * tw + x) + 4]
            b = w[4 * (y * ww + x):4 * (y * ww + x) + 4] if x < ww and y < wh else b'\0\0\0\0'
            assert a == b, 'pixel %d,%d: %r != %r' % (x, y, a, b)


def core(path, S, P):
    """The S x S pixels of a tile file (without its halo), RGBA bytes."""
    side, _, px = rgba(path)
    assert side == S + 2 * P, (path, side)
    if not P:
        return px
    return b''.join(px[4 * ((P + j) * side + P):4 * ((P + j) * side + P + S)] for j in range(S))


def normal_px(px):
    """The box filter of four RGBA normal pixels (cli/tiles.c box_rect, layer 1)."""
    A = sum(v[3] for v in px)
    if A == 0:
        return (0, 0, 0, 0)
    s = [float(sum(v[3] * (2 * v[k] - 255) for v in px)) for k in range(3)]
    f = 127.5 / math.sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2])
    out = tuple(min(255, max(0, math.floor(s[k] * f + 128.0))) for k in range(3))
    return out + ((A + 2) >> 2,)


def parent(d, z, x, y, layer=''):
    m = json.load(open(os.path.join(d, 'tiles.json')))
    S, P = m['tile_size'], m.get('halo', 0)
    tms = m['scheme'] == 'tms'
    suf = '_n' if layer == 'n' else ''
    def path(z, x, y):
        yy = (1 << z) - 1 - y if tms else y
        return os.path.join(d, str(z), str(x), '%d%s.png' % (yy, suf))
    p = core(path(z, x, y), S, P)
    h = S // 2
    for q in range(4):
        cx, cy = 2 * x + (q & 1), 2 * y + (q >> 1)
        cp = path(z + 1, cx, cy)
        c = core(cp, S, P) if os.path.exists(cp) else None
        for j in range(h):
            for i in range(h):
                o = 4 * ((((q >> 1) * h + j) * S) + (q & 1) * h + i)
                if c is None:
                    assert p[o + 3] == 0, 'missing child %s under an opaque pixel' % cp
                    continue
                px = [c[4 * ((2 * j + dy) * S + 2 * i + dx):4 * ((2 * j + dy) * S + 2 * i + dx) + 4]
                      for dy in (0, 1) for dx in (0, 1)]
                A = sum(v[3] for v in px)
                if suf:
                    want = normal_px(px)
                elif A == 0:
                    want = (0, 0, 0, 0)
                else:
                    want = tuple((sum(v[k] * v[3] for v in px) + A // 2) // A for k in range(3)) + ((A + 2) >> 2,)
                assert tuple(p[o:o + 4]) == want, 'tile %d/%d/%d pixel %d: %r != %r' % (z, x, y, o // 4, tuple(p[o:o + 4]), want)


def halo(d):
    m = json.load(open(os.path.join(d, 'tiles.json')))
    S, P, zmax = m['tile_size'], m['halo'], m['levels']['max']
    W, H = m['image']['width'], m['image']['height']
    tms = m['scheme'] == 'tms'
    assert P > 0
    cache = {}
    def tile(z, x, y, suf):
        yy = (1 << z) - 1 - y if tms else y
        k = (z, x, y, suf)
        if k not in cache:
            p = os.path.join(d, str(z), str(x), '%d%s.png' % (yy, suf))
            cache[k] = rgba(p)[2] if os.path.exists(p) else None
        return cache[k]
    side = S + 2 * P
    n_cmp = 0
    for key in m['tiles']:
        z, x, yy = key.split('/')
        suf = '_n' if yy.endswith('_n') else ''
        z, x, y = int(z), int(x), int(yy[:-2] if suf else yy)
        if tms:
            y = (1 << z) - 1 - y
        t = tile(z, x, y, suf)
        k = zmax - z
        lw, lh = -(-W // (1 << k)), -(-H // (1 << k))
        for j in range(side):
            for i in range(side):
                if P <= i < P + S and P <= j < P + S:
                    continue
                X, Y = x * S + i - P, y * S + j - P
                got = t[4 * (j * side + i):4 * (j * side + i) + 4]
                if X < 0 or Y < 0 or X >= lw or Y >= lh:
                    assert got == b'\0\0\0\0', 'tile %s halo pixel %d,%d beyond the image: %r' % (key, i, j, got)
                    continue
                nb = tile(z, X // S, Y // S, suf)
                if nb is None:
                    continue  # a road-free neighbour that is not written
                ii, jj = X % S + P, Y % S + P
                want = nb[4 * (jj * side + ii):4 * (jj * side + ii) + 4]
                assert got == want, 'tile %s halo pixel %d,%d: %r != neighbour %r' % (key, i, j, got, want)
                n_cmp += 1
    assert n_cmp > 0
    print('halo: %d pixels equal their neighbour tile\'s' % n_cmp)


def normal_window(tile, win):
    tw, th, t = rgba(tile)
    ww, wh, ch, w = read(win)
    assert ch == 3
    for y in range(th):
        for x in range(tw):
            a = t[4 * (y * tw + x):4 * (y * tw + x) + 4]
            b = bytes(w[3 * (y * ww + x):3 * (y * ww + x) + 3]) + b'\xff' if x < ww and y < wh else b'\0\0\0\0'
            assert a == b, 'pixel %d,%d: %r != %r' % (x, y, a, b)


def seam(a, b, z, limit):
    """Tiles of level z in a and b that differ (a's terrain-only tiles rendered directly, b's box-filtered):
    the mean and max per-channel difference over their opaque pixels; the mean must stay below limit."""
    m = json.load(open(os.path.join(a, 'tiles.json')))
    tot = n = mx = nd = 0
    for key in m['tiles']:
        if not key.startswith('%d/' % z) or key.endswith('_n'):
            continue
        pa, pb = os.path.join(a, key + '.png'), os.path.join(b, key + '.png')
        if open(pa, 'rb').read() == open(pb, 'rb').read():
            continue
        p, q = rgba(pa)[2], rgba(pb)[2]
        d = [abs(p[i] - q[i]) for i in range(len(p)) if i % 4 != 3 and p[i | 3] and q[i | 3]]
        tot, n, mx, nd = tot + sum(d), n + len(d), max([mx] + d), nd + 1
    assert nd > 0, 'no tile of level %d differs' % z
    print('seam: %d tiles of level %d rendered directly: mean |difference| %.3f, max %d (of 255)' % (nd, z, tot / n, mx))
    assert tot / n < limit, tot / n


def sparse(d, pgm):
    m = json.load(open(os.path.join(d, 'tiles.json')))
    S, zmax, zd = m['tile_size'], m['levels']['max'], m['levels']['dense_max']
    data = open(pgm, 'rb').read()
    parts = data.split(b'\n', 3)
    W, H = map(int, parts[1].split())
    px = parts[3]
    nx, ny = (W + S - 1) // S, (H + S - 1) // S
    road = {}
    for ty in range(ny):
        for tx in range(nx):
            r = False
            for y in range(ty * S, min(H, ty * S + S)):
                row = px[2 * (y * W + tx * S):2 * (y * W + min(W, tx * S + S))]
                if row.strip(b'\0'):
                    r = True
                    break
            road[(zmax, tx, ty)] = r
    for z in range(zmax - 1, -1, -1):
        k = 1 << (zmax - z)
        for ty in range((ny + k - 1) // k):
            for tx in range((nx + k - 1) // k):
                road[(z, tx, ty)] = any(road.get((z + 1, 2 * tx + (q & 1), 2 * ty + (q >> 1)), False) for q in range(4))
    n_road = 0
    for (z, x, y), r in road.items():
        yy = (1 << z) - 1 - y if m['scheme'] == 'tms' else y
        has = ('%d/%d/%d' % (z, x, yy)) in m['tiles']
        want = z <= zd or r
        assert has == want, 'tile %d/%d/%d: written %s, should be %s (road %s)' % (z, x, y, has, want, r)
        n_road += r
    print('sparse: %d tiles, %d with a road, %d written' % (len(road), n_road, len(m['tiles'])))


def mbtiles(f, d):
    m = json.load(open(os.path.join(d, 'tiles.json')))
    db = sqlite3.connect(f)
    meta = dict(db.execute('SELECT name, value FROM metadata'))
    assert meta['format'] == 'png' and int(meta['maxzoom']) == m['levels']['max'], meta
    n = 0
    for table, suf in (('tiles', ''), ('normal_tiles', '_n')):
        if suf and not m.get('normal_tiles_written'):
            break
        rows = list(db.execute('SELECT zoom_level, tile_column, tile_row, tile_data FROM ' + table))
        for z, x, row, blob in rows:
            y = (1 << z) - 1 - row
            assert hashlib.sha256(blob).hexdigest() == m['tiles']['%d/%d/%d%s' % (z, x, y, suf)], (table, z, x, y)
        n += len(rows)
    assert n == len(m['tiles']), (n, len(m['tiles']))


def same(a, b):
    wa, ha, pa = rgba(a)
    wb, hb, pb = rgba(b)
    assert (wa, ha) == (wb, hb), (a, wa, ha, b, wb, hb)
    assert pa == pb, '%s and %s: %d bytes differ' % (a, b, sum(x != y for x, y in zip(pa, pb)))


if __name__ == '__main__':
    c, a = sys.argv[1], sys.argv[2:]
    if c == 'manifest': manifest(a[0])
    elif c == 'window': window(a[0], a[1])
    elif c == 'parent': parent(a[0], int(a[1]), int(a[2]), int(a[3]), *a[4:])
    elif c == 'halo': halo(a[0])
    elif c == 'seam': seam(a[0], a[1], int(a[2]), float(a[3]))
    elif c == 'normal_window': normal_window(a[0], a[1])
    elif c == 'sparse': sparse(a[0], a[1])
    elif c == 'mbtiles': mbtiles(a[0], a[1])
    elif c == 'same': same(a[0], a[1])
    else: sys.exit('unknown check ' + c)
