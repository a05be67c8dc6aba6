#!/bin/sh
# CLI tests for --normal-out (issue 16, docs/normals.md): an RGB8 PNG of the
# colour output's size; a plane rising to the north decodes to the analytic
# normal, green flipped by --normal-convention dx; --window cuts the same
# pixels; threads change nothing; bad values refused with no output left.
# Usage: sh tests/cli_normals_test.sh PATH/TO/roadsplat
BIN=${1:?usage: cli_normals_test.sh ROADSPLAT}
. "$(dirname "$0")/cli_lib.sh"
PY=$(dirname "$0")/png_read.py
ref_scene "$T"
# a plane rising 0.5 m per metre to the north (sample rows go south)
printf 'P2\n9 7\n255\n' >"$T/north.pgm"
awk 'BEGIN { for (i = 0; i < 7; i++) for (j = 0; j < 9; j++) printf "%d%s", 200 - 5 * i, (j == 8) ? "\n" : " " }' >>"$T/north.pgm"
printf 'road far width 1\n100 100\n101 100\nend\n' >"$T/none.txt"
run() { "$BIN" --quiet "$@"; }
# pixel (x, y) of a PNG as "R G B"
px() { python3 -c "import sys; sys.path.insert(0, '$(dirname "$PY")'); import png_read as p
w, h, c, d = p.read('$1'); i = ($3 * w + $2) * c; print(w, h, c, d[i], d[i + 1], d[i + 2])"; }
check "plane, gl" run --cell-size 2 --z-scale 0.2 --texels 4 --normal-out "$T/n_gl.png" "$T/north.pgm" "$T/none.txt" "$T/c.png" 2>/dev/null
check "plane, dx" run --cell-size 2 --z-scale 0.2 --texels 4 --normal-out "$T/n_dx.png" --normal-convention dx \
    "$T/north.pgm" "$T/none.txt" "$T/c2.png" 2>/dev/null
# dz/dy = -5 * 0.2 / 2 = -0.5: n = (0, -0.5, 1) / sqrt(1.25), so
# (128, round((-0.4472 / 2 + 0.5) * 255) = 70, 242); dx: green 185
gl=$(px "$T/n_gl.png" 5 5); dx=$(px "$T/n_dx.png" 5 5)
check "gl pixel (expected 32 24 3 128 70 242, got $gl)" test "$gl" = "32 24 3 128 70 242"
check "dx pixel (expected 32 24 3 128 185 242, got $dx)" test "$dx" = "32 24 3 128 185 242"
# the reference scene: windows and threads
check "whole" run --threads 1 --normal-out "$T/w1.png" --normal-strength 2.5 "$T/dem.pgm" "$T/roads.txt" "$T/o1.png"
check "whole, 3 threads" run --threads 3 --normal-out "$T/w3.png" --normal-strength 2.5 "$T/dem.pgm" "$T/roads.txt" "$T/o3.png"
check "threads: same normal map" cmp -s "$T/w1.png" "$T/w3.png"
check "window" run --window 37,11,50,41 --normal-out "$T/win.png" --normal-strength 2.5 "$T/dem.pgm" "$T/roads.txt" "$T/ow.png"
check "window = the same pixels of the whole" python3 -c "
import sys; sys.path.insert(0, '$(dirname "$PY")'); import png_read as p
W, H, c, a = p.read('$T/w1.png'); w, h, c2, b = p.read('$T/win.png')
assert (c, c2, w, h) == (3, 3, 50, 41)
for y in range(h):
    assert a[((11 + y) * W + 37) * 3:((11 + y) * W + 37 + w) * 3] == b[y * w * 3:(y + 1) * w * 3], y
"
check "same size as the colour output" python3 -c "
import sys; sys.path.insert(0, '$(dirname "$PY")'); import png_read as p
assert p.read('$T/w1.png')[:2] == p.read('$T/o1.png')[:2]"
run --normal-out "$T/x.tif" "$T/dem.pgm" "$T/roads.txt" "$T/o.png" 2>"$T/err" && bad "--normal-out .tif accepted"
check ".png only" grep -q "normal-out: .*is not a .png" "$T/err"
run --normal-out "$T/x.png" --normal-convention up "$T/dem.pgm" "$T/roads.txt" "$T/o.png" 2>"$T/err" && bad "bad convention accepted"
check "bad convention named" grep -q "normal-convention: 'up' is not gl or dx" "$T/err"
run --normal-out "$T/x.png" --normal-strength -1 "$T/dem.pgm" "$T/roads.txt" "$T/o.png" 2>"$T/err" && bad "negative strength accepted"
check "bad strength named" grep -q "normal-strength" "$T/err"
run --normal-strength 2 "$T/dem.pgm" "$T/roads.txt" "$T/o.png" 2>"$T/err" && bad "--normal-strength alone accepted"
check "needs --normal-out" grep -q "need --normal-out" "$T/err"
check "no output on error" test ! -e "$T/x.png" -a ! -e "$T/o.png"
echo "cli_normals: $pass passed, $fail failed"
[ "$fail" = 0 ]
