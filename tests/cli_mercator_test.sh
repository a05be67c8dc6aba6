#!/bin/sh
# `roadsplat tiles --tiling mercator` (issue 28 target 4, docs/tiles.md
# "Tiling"): EPSG:3857 XYZ tiles from a UTM GeoTIFF DEM made here. Checks
# that known roads land on their pixels (projected independently with
# gdaltransform), the MBTiles metadata and that GDAL opens the MBTiles and
# the folder's tiles.xml at the right place, the TMS rows, determinism over
# threads, shards + merge and --resume, the raster tiling's tiles.xml, and
# the refusals. Usage: sh tests/cli_mercator_test.sh PATH/TO/roadsplat
BIN=${1:?usage: cli_mercator_test.sh ROADSPLAT}
. "$(dirname "$0")/cli_lib.sh"

need_gdal cli_mercator "$BIN" gdal_translate gdaltransform gdalinfo python3
BIN=$(cd "$(dirname "$BIN")" && pwd)/$(basename "$BIN")
PYDIR=$(cd "$(dirname "$0")" && pwd)
cd "$T" || exit 1
json() { python3 -c "import json, sys; j = json.load(open(sys.argv[1])); sys.exit(0 if ($2) else 1)" "$1"; }

# ---- data -------------------------------------------------------------------
# 81 x 61 samples of 10 m in UTM 32N, 2.6 degrees west of the zone's central
# meridian (grid convergence about 1.8 degrees: north in UTM is not up in
# Web Mercator); sample (0,0) at (300005, 5000605).
python3 - <<'PY'
import math
W, H, cs = 81, 61, 10
with open('dem.asc', 'w') as f:
    f.write("ncols %d\nnrows %d\nxllcorner 300000\nyllcorner 5000000\ncellsize %d\n" % (W, H, cs))
    for j in range(H):
        f.write(' '.join('%.2f' % (100 + 20 * math.sin(i * 0.1) + 15 * math.cos(j * 0.13)) for i in range(W)) + '\n')
PY
gdal_translate -q -a_srs EPSG:32632 -ot Float32 dem.asc dem.tif
# a road along a UTM grid line each way (width 4 m), no markings
cat >roads.txt <<'R'
frame world EPSG:32632
road ns width 4
300400 5000020
300400 5000590
end
road ew width 4
300020 5000300
300790 5000300
end
R
O="--quiet --tiling mercator --no-markings"
# --dense: the accuracy check reads road-free neighbours too
O="$O --dense"
"$BIN" tiles $O --texels 16 dem.tif roads.txt m 2>e && ok || bad "tiles --tiling mercator: $(cat e)"
json m/tiles.json "j['tiling'] == 'mercator' and j['frame']['crs'] == 'EPSG:3857' and j['levels']['max'] == 18" && ok ||
    bad "manifest: $(grep -E 'tiling|levels' m/tiles.json)"

# ---- accuracy: a road's projected position against its pixels ----------------
# points on the centrelines, to EPSG:3857 by gdaltransform (PROJ), not by roadsplat
printf '300400 5000150\n300400 5000460\n300150 5000300\n300650 5000300\n' >pts.txt
gdaltransform -s_srs EPSG:32632 -t_srs EPSG:3857 <pts.txt >pts3857.txt
python3 - m pts3857.txt "$PYDIR" >acc.txt <<'PY' && ok || bad "road pixels off: $(cat acc.txt)"
import json, math, os, sys
sys.path.insert(0, sys.argv[3])
from png_read import read
d = sys.argv[1]
j = json.load(open(d + '/tiles.json'))
z, S = j['levels']['max'], j['tile_size']
half = math.pi * 6378137
res = 2 * half / (S * 2 ** z)
pts = [tuple(map(float, l.split()[:2])) for l in open(sys.argv[2])]
worst, tiles = 0, {}
for k, (mx, my) in enumerate(pts):
    gx, gy = (mx + half) / res - 0.5, (half - my) / res - 0.5  # global pixel, centres at whole numbers
    across_x = k < 2  # the north-south road: look across it along a row
    def at(i, jj):  # green minus red of global pixel (i, jj): about 30 on the terrain, 0 on the road
        tx, ty = i // S, jj // S
        if (tx, ty) not in tiles:
            tiles[tx, ty] = read('%s/%d/%d/%d.png' % (d, z, tx, ty))
        w, h, c, px = tiles[tx, ty]
        p = ((jj - ty * S) * w + i - tx * S) * c
        return px[p + 1] - px[p]
    row = []
    for o in range(-30, 31):
        i, jj = (int(round(gx)) + o, int(round(gy))) if across_x else (int(round(gx)), int(round(gy)) + o)
        row.append((o, at(i, jj)))
    far = sorted(v for o, v in row if abs(o) > 20)
    g_terrain = far[len(far) // 2]
    # a pixel's road share from its colour; the terrain's own shading (a few levels) is not road
    wts = [(o, wt if wt > 0.2 else 0.0) for o, wt in ((o, min(1.0, max(0.0, (g_terrain - v) / g_terrain))) for o, v in row)]
    s = sum(wt for o, wt in wts)
    centre = sum(o * wt for o, wt in wts) / s + (int(round(gx)) if across_x else int(round(gy)))
    want = gx if across_x else gy
    err = centre - want
    worst = max(worst, abs(err))
    print('point %d: road centre at %.3f, projected %.3f (%.3f px; %.1f road pixels across)' % (k, centre, want, err, s))
assert worst <= 1.0, worst
print('worst %.3f px' % worst)
PY
cat acc.txt

# ---- MBTiles: metadata, TMS rows, GDAL's view --------------------------------
if "$BIN" tiles --format mbtiles --help >/dev/null 2>&1 && command -v sqlite3 >/dev/null 2>&1 &&
    "$BIN" tiles $O --texels 16 --format mbtiles dem.tif roads.txt m.mbtiles 2>e; then
    sqlite3 m.mbtiles "select name || '=' || value from metadata where name != 'roadsplat_manifest'" >meta.txt
    zmin=$(python3 -c "import json; print(json.load(open('m/tiles.json'))['levels']['min'])")
    for k in name=m.mbtiles format=png type=baselayer minzoom=$zmin maxzoom=18; do
        grep -qx "$k" meta.txt && ok || bad "MBTiles metadata $k: $(cat meta.txt)"
    done
    # bounds: the DEM's corners in WGS84 (gdaltransform), within 1e-5 degrees (about 1 m)
    printf '300005 5000005\n300805 5000605\n' | gdaltransform -s_srs EPSG:32632 -t_srs EPSG:4326 >ll.txt
    python3 - meta.txt ll.txt <<'PY' && ok || bad "MBTiles bounds/center: $(cat meta.txt)"
import sys
m = dict(l.strip().split('=', 1) for l in open(sys.argv[1]))
b = [float(v) for v in m['bounds'].split(',')]
c = [float(v) for v in m['center'].split(',')]
(x0, y0), (x1, y1) = [tuple(map(float, l.split()[:2])) for l in open(sys.argv[2])]
# the corners are inside the bounds, which the curved border widens by little
assert b[0] <= x0 + 1e-9 and b[1] <= y0 + 1e-9 and b[2] >= x1 - 1e-9 and b[3] >= y1 - 1e-9, (b, x0, y0, x1, y1)
assert b[2] - b[0] < (x1 - x0) * 1.05 and b[3] - b[1] < (y1 - y0) * 1.05, b
assert b[0] < c[0] < b[2] and b[1] < c[1] < b[3] and 16 <= c[2] <= 18, c
PY
    # every row is the folder's tile at y = 2^z - 1 - row
    sqlite3 m.mbtiles "select zoom_level, tile_column, tile_row, hex(tile_data) from tiles" >rows.txt
    python3 - rows.txt m <<'PY' && ok || bad "MBTiles rows are not the folder's tiles (TMS)"
import binascii, os, sys
n = 0
for l in open(sys.argv[1]):
    z, x, r, h = l.strip().split('|')
    y = 2 ** int(z) - 1 - int(r)
    assert open('%s/%s/%s/%d.png' % (sys.argv[2], z, x, y), 'rb').read() == binascii.unhexlify(h), (z, x, y)
    n += 1
import json
assert n == json.load(open(sys.argv[2] + '/tiles.json'))['tiles_written'], n
PY
    # GDAL opens it in EPSG:3857 over the DEM's extent, within a pixel of the finest level
    printf '300005 5000005\n300805 5000605\n300005 5000605\n300805 5000005\n' |
        gdaltransform -s_srs EPSG:32632 -t_srs EPSG:3857 >corners.txt
    gdalinfo -json m.mbtiles >gi.json 2>&1
    python3 - gi.json corners.txt <<'PY' && ok || bad "GDAL's MBTiles extent: $(head -c 600 gi.json)"
import json, math, sys
g = json.load(open(sys.argv[1]))
assert 'Pseudo-Mercator' in g['coordinateSystem']['wkt'], 'not EPSG:3857'
gt, (w, h) = g['geoTransform'], g['size']
xs, ys = [], []
for l in open(sys.argv[2]):
    x, y = map(float, l.split()[:2]); xs.append(x); ys.append(y)
res = 2 * math.pi * 6378137 / (256 * 2 ** 18)
got = [gt[0], gt[3] + h * gt[5], gt[0] + w * gt[1], gt[3]]
want = [min(xs), min(ys), max(xs), max(ys)]
err = max(abs(a - b) for a, b in zip(got, want)) / res
print('GDAL MBTiles extent within %.3f finest pixels' % err)
assert err <= 1.0, (got, want)
PY
else
    echo "SKIP cli_mercator MBTiles: no SQLite module or sqlite3 ($(cat e 2>/dev/null))"
fi

# ---- the folder's tiles.xml: GDAL's WMS/TMS description -----------------------
gdalinfo m/tiles.xml >gx.txt 2>&1 && grep -q 'Pseudo-Mercator' gx.txt && ok || bad "tiles.xml: $(head -3 gx.txt)"
# a crop of the description around the north-south road is that road's picture
gdal_translate -q -projwin $(sed -n 1p pts3857.txt | awk '{print $1-60, $2+60, $1+60, $2-60}') m/tiles.xml crop.tif 2>e &&
    gdalinfo -stats crop.tif >cs.txt 2>&1 && grep -q 'Band 4' cs.txt && ok || bad "tiles.xml crop: $(cat e)"

# --scheme tms: the same pictures under TMS names, and tiles.xml says so (GDAL reads the same crop)
"$BIN" tiles $O --texels 16 --scheme tms dem.tif roads.txt tms 2>e &&
    gdal_translate -q -projwin $(sed -n 1p pts3857.txt | awk '{print $1-60, $2+60, $1+60, $2-60}') tms/tiles.xml crop_tms.tif &&
    gdal_translate -q -projwin $(sed -n 1p pts3857.txt | awk '{print $1-60, $2+60, $1+60, $2-60}') m/tiles.xml crop_xyz.tif &&
    cmp -s crop_tms.tif crop_xyz.tif && ok || bad "--scheme tms: $(cat e)"

# ---- determinism: threads, shards + merge, resume -----------------------------
"$BIN" tiles $O --texels 16 --threads 1 dem.tif roads.txt t1 && cmp -s t1/tiles.json m/tiles.json && ok ||
    bad "--threads 1 differs"
for i in 0 1 2; do "$BIN" tiles $O --texels 16 --shard $i/3 dem.tif roads.txt sh || bad "shard $i"; done
"$BIN" tiles $O --texels 16 --from-children dem.tif roads.txt sh && cmp -s sh/tiles.json m/tiles.json &&
    diff -r -x .tiles-log -x tiles.xml sh m >/dev/null && ok || bad "3 shards + merge differ from one run"
victim=$(find t1/18 -name '*.png' | sort | head -1)
rm "$victim"
"$BIN" tiles $O --texels 16 --threads 1 --resume dem.tif roads.txt t1 && cmp -s "$victim" "m/${victim#t1/}" &&
    cmp -s t1/tiles.json m/tiles.json && ok || bad "--resume did not make $victim again"

# ---- DEM tiles of one map (issue 28 target 3): the mosaic, not each tile alone ----
# two DEM files sharing the sample column 40, mosaicked by GDAL's own gdalbuildvrt
# (the VRT passes the allow-list: its sources sit beside it): the same tiles as
# the whole DEM, byte for byte
if command -v gdalbuildvrt >/dev/null 2>&1; then
    gdal_translate -q -srcwin 0 0 41 61 dem.tif west.tif && gdal_translate -q -srcwin 40 0 41 61 dem.tif east.tif &&
        gdalbuildvrt -q mosaic.vrt west.tif east.tif &&
        "$BIN" tiles $O --texels 16 mosaic.vrt roads.txt mv 2>e &&
        diff -r -x .tiles-log -x tiles.json -x tiles.xml mv m >/dev/null && ok || bad "tiles of the mosaic VRT differ: $(cat e)"
else
    echo "SKIP cli_mercator mosaic: no gdalbuildvrt"
fi

# ---- sparse levels, --zoom, the raster tiling's description, refusals ------------
# without --dense: the road-free tiles of the finer levels are left out, the rest the same bytes
S="--quiet --tiling mercator --no-markings"
"$BIN" tiles $S --texels 16 dem.tif roads.txt sp && (cd sp && find . -name '*.png' | sort) >sp.txt &&
    [ "$(wc -l <sp.txt)" -lt "$(find m -name '*.png' | wc -l)" ] &&
    (cd sp && xargs -I{} cmp -s {} ../m/{} <../sp.txt) && ok || bad "sparse run: not a subset of the dense one"
"$BIN" tiles $S --zoom 14-17 dem.tif roads.txt z 2>e && json z/tiles.json "j['levels']['min'] == 14 and j['levels']['max'] == 17" &&
    [ -d z/14 ] && [ ! -d z/13 ] && [ ! -d z/18 ] && ok || bad "--zoom 14-17: $(cat e) $(grep levels z/tiles.json)"
"$BIN" tiles --texels 4 dem.tif roads.txt r 2>e && grep -q 'not Web Mercator' e && ok || bad "raster tiling note: $(cat e)"
json r/tiles.json "j['tiling'] == 'raster' and j['frame']['crs'] == 'EPSG:32632'" && ok || bad "raster manifest"
gdalinfo -json r/tiles.xml >rx.json 2>&1 && python3 - rx.json r/tiles.json <<'PY' && ok || bad "raster tiles.xml: $(head -c 400 rx.json)"
import json, sys
g, j = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
gt, fgt = g['geoTransform'], j['frame']['geotransform']
k = 2 ** (j['levels']['max'] - j['levels']['dense_max'])
assert abs(gt[0] - fgt[0]) < 1e-6 and abs(gt[3] - fgt[3]) < 1e-6 and abs(gt[1] - fgt[1] * k) < 1e-9, (gt, fgt)
assert g['size'][0] == j['tile_size'] * 2 ** j['levels']['dense_max'], g['size']
assert 'UTM zone 32N' in g['coordinateSystem']['wkt']
PY
# the raster tiling's default 8 texels on a georeferenced DEM: a finest tile is the main
# command's --texels 8 window, asphalt grain included (the surface's world grid once
# came from a texel count of 0: a division by zero)
"$BIN" tiles --quiet --no-markings dem.tif roads.txt r8 && "$BIN" --quiet --no-markings --texels 8 --window 256,0,256,256 \
    dem.tif roads.txt w8.png && python3 "$PYDIR/tiles_check.py" same r8/2/1/0.png w8.png && ok || bad "raster tile 2/1/0 is not the --texels 8 window"
printf 'P2\n3 3\n255\n1 2 3\n4 5 6\n7 8 9\n' >p.pgm
printf 'road a width 1\n0 0\n2 2\nend\n' >p.txt
"$BIN" tiles --tiling mercator p.pgm p.txt pg 2>e && bad "mercator on a PGM" ||
    { [ "$(wc -l <e)" = 1 ] && grep -q 'needs a DEM with a CRS' e && [ ! -e pg/tiles.json ] && ok || bad "PGM: $(cat e)"; }
for args in "--tiling mercator --halo 2" "--tiling mercator --normals" "--zoom 12" "--tiling mercator --zoom 9-8" \
    "--tiling web"; do
    "$BIN" tiles $args dem.tif roads.txt bad 2>e && bad "tiles $args accepted" ||
        { [ "$(wc -l <e)" = 1 ] && ok || bad "tiles $args: $(cat e)"; }
done
echo "cli_mercator: $pass passed, $fail failed"
[ "$fail" = 0 ]
