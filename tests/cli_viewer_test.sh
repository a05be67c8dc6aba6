#!/bin/sh
# `roadsplat tiles --viewer` (issue 28, docs/tiles.md "Viewer"): index.html
# and Leaflet beside the tiles, no network, and - when Debian's chromium is
# installed (make deps-viewer) - a headless screenshot that shows the tiles:
# the whole image at its fitted zoom, and at the finest level the very
# pixels of the splat. Usage: sh tests/cli_viewer_test.sh PATH/TO/roadsplat
BIN=${1:?usage: cli_viewer_test.sh ROADSPLAT}
. "$(dirname "$0")/cli_lib.sh"
E=docs/examples
PYDIR=$(cd "$(dirname "$0")" && pwd)
O="--quiet --cell-size 5 --z-scale 0.01 --texels 8"
if [ ! -f /usr/share/javascript/leaflet/leaflet.js ]; then
    echo "SKIP cli_viewer: libjs-leaflet is not installed (make deps installs it)"
    echo "cli_viewer: 0 passed, 0 failed"
    exit 0
fi
"$BIN" tiles $O --viewer --attribution "roads <b>'x'</b> & co" "$E/dem.pgm" "$E/roads.txt" "$T/t" && ok || bad "tiles --viewer"
for f in index.html leaflet/leaflet.js leaflet/leaflet.css leaflet/images/layers.png tiles.json 0/0/0.png; do
    [ -s "$T/t/$f" ] && ok || bad "--viewer wrote no $f"
done
cmp -s "$T/t/leaflet/leaflet.js" /usr/share/javascript/leaflet/leaflet.js && ok || bad "leaflet.js is not Debian's"
grep -q 'http' "$T/t/index.html" && bad "index.html loads something from the network" || ok
grep -q "roads &lt;b&gt;\\\\'x\\\\'&lt;/b&gt; &amp; co" "$T/t/index.html" && ! grep -q '<b>' "$T/t/index.html" && ok ||
    bad "attribution not escaped: $(grep -n attribution "$T/t/index.html")"
# the same tiles with and without --viewer
"$BIN" tiles $O "$E/dem.pgm" "$E/roads.txt" "$T/plain" &&
    diff -r -x index.html -x leaflet -x .tiles-log "$T/t" "$T/plain" >/dev/null && ok || bad "--viewer changed the tiles"

# bad usage: one line, exit 1, nothing written
"$BIN" tiles $O --viewer --format mbtiles "$E/dem.pgm" "$E/roads.txt" "$T/v.mbtiles" 2>"$T/e" && bad "--viewer with mbtiles" ||
    { grep -q -- '--viewer shows a folder of plain tiles' "$T/e" && [ ! -e "$T/v.mbtiles" ] && ok || bad "mbtiles: $(cat "$T/e")"; }
"$BIN" tiles $O --viewer --halo 2 "$E/dem.pgm" "$E/roads.txt" "$T/h" 2>"$T/e" && bad "--viewer with --halo" ||
    { grep -q -- '--halo' "$T/e" && [ ! -e "$T/h" ] && ok || bad "halo: $(cat "$T/e")"; }
"$BIN" tiles $O --attribution x "$E/dem.pgm" "$E/roads.txt" "$T/a" 2>"$T/e" && bad "--attribution without --viewer" ||
    { grep -q 'needs --viewer' "$T/e" && ok || bad "attribution: $(cat "$T/e")"; }

CH=$(command -v chromium || command -v chromium-browser || true)
if [ -z "$CH" ]; then
    echo "SKIP cli_viewer: no chromium for the screenshot checks (make deps-viewer installs Debian's chromium)"
else
    shot() { # URL-fragment OUT.png W H
        timeout 120 "$CH" --headless --no-sandbox --disable-gpu --hide-scrollbars --force-color-profile=srgb \
            --user-data-dir="$T/chrome" --window-size="$3,$4" --virtual-time-budget=8000 --screenshot="$2" \
            "file://$(cd "$T/t" && pwd)/index.html$1" >/dev/null 2>&1
    }
    "$BIN" $O --cell-size 5 "$E/dem.pgm" "$E/roads.txt" "$T/whole.png"
    # the fitted view: the image fills much of the window
    shot "" "$T/fit.png" 800 600 && python3 - "$T/fit.png" <<PY && ok || bad "fitted view shows no tiles"
import sys
sys.path.insert(0, '$PYDIR')
from png_read import read
w, h, c, d = read(sys.argv[1])
# terrain green (the tiles), against none at all without them
green = sum(1 for i in range(0, w * h * c, c) if d[i + 1] > d[i] + 10 and d[i + 1] > d[i + 2] + 10)
assert green > 0.2 * w * h, 'green %d of %d' % (green, w * h)
PY
    # the finest level centred on a road pixel: the screenshot's centre is the splat's pixel
    shot "#3/700/520" "$T/z3.png" 400 300 && python3 - "$T/z3.png" "$T/whole.png" <<PY && ok || bad "zoom 3 is not the splat"
import sys
sys.path.insert(0, '$PYDIR')
from png_read import read
w, h, c, s = read(sys.argv[1])
W, H, C, d = read(sys.argv[2])
worst = 0
for dy in range(-20, 21, 5):
    for dx in range(-20, 21, 5):
        a = ((h // 2 + dy) * w + w // 2 + dx) * c
        b = ((520 + dy) * W + 700 + dx) * C
        worst = max(worst, max(abs(s[a + k] - d[b + k]) for k in range(3)))
assert worst <= 3, 'max difference %d' % worst
PY
fi

# ---- --tiling mercator: Leaflet's default CRS, the tiles at their place ----------
"$BIN" convert "$T/none.geojson" "$T/none.txt" 2>"$T/e"
if grep -q "no GDAL support" "$T/e" || ! command -v gdal_translate >/dev/null 2>&1 || ! command -v gdaltransform >/dev/null 2>&1; then
    echo "SKIP cli_viewer mercator: no GDAL (make deps installs libgdal-dev and gdal-bin)"
else
    python3 - "$T/dem.asc" <<'PY'
import math, sys
with open(sys.argv[1], 'w') as f:
    f.write("ncols 81\nnrows 61\nxllcorner 300000\nyllcorner 5000000\ncellsize 10\n")
    for j in range(61):
        f.write(' '.join('%.2f' % (100 + 20 * math.sin(i * 0.1) + 15 * math.cos(j * 0.13)) for i in range(81)) + '\n')
PY
    gdal_translate -q -a_srs EPSG:32632 -ot Float32 "$T/dem.asc" "$T/dem.tif"
    printf 'frame world EPSG:32632\nroad ns width 6\n300400 5000020\n300400 5000590\nend\n' >"$T/utm.txt"
    "$BIN" tiles --quiet --tiling mercator --no-markings --viewer "$T/dem.tif" "$T/utm.txt" "$T/m" && ok || bad "mercator --viewer"
    grep -q 'CRS.Simple' "$T/m/index.html" && bad "mercator viewer uses CRS.Simple" || ok
    grep -q 'http' "$T/m/index.html" && bad "mercator index.html loads something from the network" || ok
    if [ -n "$CH" ]; then
        rm -rf "$T/t" && cp -r "$T/m" "$T/t" # shot() opens $T/t
        shot "" "$T/mfit.png" 800 600 && python3 - "$T/mfit.png" <<PY && ok || bad "mercator fitted view shows no tiles"
import sys
sys.path.insert(0, '$PYDIR')
from png_read import read
w, h, c, d = read(sys.argv[1])
green = sum(1 for i in range(0, w * h * c, c) if d[i + 1] > d[i] + 10 and d[i + 1] > d[i + 2] + 10)
assert green > 0.2 * w * h, 'green %d of %d' % (green, w * h)
PY
        # centred on the road's longitude and latitude (gdaltransform) at the finest zoom: the centre is road
        ll=$(echo "300400 5000300" | gdaltransform -s_srs EPSG:32632 -t_srs EPSG:4326)
        set -- $ll
        zmax=$(python3 -c "import json; print(json.load(open('$T/m/tiles.json'))['levels']['max'])")
        shot "#$zmax/$2/$1" "$T/mroad.png" 400 300 && python3 - "$T/mroad.png" <<PY && ok || bad "mercator: the road is not at its place"
import sys
sys.path.insert(0, '$PYDIR')
from png_read import read
w, h, c, d = read(sys.argv[1])
def grey(x, y):
    i = (y * w + x) * c
    return abs(d[i + 1] - d[i]) < 8
assert grey(w // 2, h // 2) and grey(w // 2, h // 2 - 40), 'centre not road'
assert not grey(w // 2 + 30, h // 2) and not grey(w // 2 - 30, h // 2), 'terrain beside it is grey too'
PY
    fi
fi
echo "cli_viewer: $pass passed, $fail failed"
[ "$fail" = 0 ]
