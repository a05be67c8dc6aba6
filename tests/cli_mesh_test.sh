#!/bin/sh
# CLI tests for `roadsplat mesh`. Usage: sh tests/cli_mesh_test.sh PATH/TO/roadsplat
# Prints "N passed, N failed"; exits non-zero on any failure.
BIN=${1:?usage: cli_mesh_test.sh ROADSPLAT}
. "$(dirname "$0")/cli_lib.sh"
# A 33x17 P2 PGM: a ridge plus a bump (not 2^n+1 in height).
awk 'BEGIN { W = 33; H = 17; print "P2"; print W, H; print 1000;
  for (i = 0; i < H; i++) { line = "";
    for (j = 0; j < W; j++) { v = 500 + 300 * exp(-((j - 10) ^ 2 + (i - 8) ^ 2) / 20) - 6 * (j > i * 2 ? j - i * 2 : i * 2 - j);
      if (v < 0) v = 0; line = line " " int(v) }
    print line } }' > "$T/dem.pgm"

check "mesh to OBJ exits 0" "$BIN" mesh --cell-size 2 --z-scale 0.5 --max-error 1 --stats "$T/s.json" "$T/dem.pgm" "$T/m.obj"
check "OBJ has vertices and faces" sh -c "grep -q '^v ' '$T/m.obj' && grep -q '^f ' '$T/m.obj'"
# every v line is at (col*2, h, row*2) with col <= 32, row <= 16; heights are DEM*0.5 exactly
check "OBJ vertices on the grid, y up" awk '/^v /{ if ($2 % 2 != 0 || $4 % 2 != 0 || $2 < 0 || $2 > 64 || $4 < 0 || $4 > 32 || $3 < 0 || $3 > 500) bad = 1 } END { exit bad }' "$T/m.obj"
check "OBJ vertex heights equal the DEM" awk 'NR == FNR { if (FNR > 3) for (k = 1; k <= NF; k++) z[n++] = $k; next }
  /^v / { j = $2 / 2; i = $4 / 2; if ($3 != z[i * 33 + j] * 0.5) bad = 1 } END { exit bad }' "$T/dem.pgm" "$T/m.obj"
# faces counter-clockwise seen from above (y up): normal . (0,1,0) > 0
check "OBJ faces wind counter-clockwise from above" awk '/^v /{ n++; x[n] = $2; z[n] = $4 }
  /^f /{ split($2, a, "/"); split($3, b, "/"); split($4, c, "/");
    ux = x[b[1]] - x[a[1]]; uz = z[b[1]] - z[a[1]]; vx = x[c[1]] - x[a[1]]; vz = z[c[1]] - z[a[1]];
    if (uz * vx - ux * vz <= 0) bad = 1; f++ } END { exit bad || f == 0 }' "$T/m.obj"
check "OBJ covers the map (area 64x32)" awk '/^v /{ n++; x[n] = $2; z[n] = $4 }
  /^f /{ split($2, a, "/"); split($3, b, "/"); split($4, c, "/");
    A += ((x[b[1]] - x[a[1]]) * (z[c[1]] - z[a[1]]) - (x[c[1]] - x[a[1]]) * (z[b[1]] - z[a[1]])) / 2 }
  END { if (A < 0) A = -A; exit !(A > 2047.999 && A < 2048.001) }' "$T/m.obj"
check "stats JSON has the fields" sh -c "grep -q '\"timings_ms\"' '$T/s.json' && grep -q '\"mesh\"' '$T/s.json' && grep -q '\"total\"' '$T/s.json' && grep -q '\"triangles\"' '$T/s.json' && grep -q '\"max_error_measured\"' '$T/s.json' && grep -q '\"pool\"' '$T/s.json'"
check "measured error <= requested" awk -F'[:,]' '/max_error_requested/ { r = $2 } /max_error_measured/ { m = $2 } END { exit !(m <= r + 1e-6) }' "$T/s.json"
tris=$(sed -n 's/.*"triangles": \([0-9]*\).*/\1/p' "$T/s.json")
check "face count matches stats" test "$(grep -c '^f ' "$T/m.obj")" = "$tris"

check "PLY with normals" "$BIN" mesh --max-error 5 --normals "$T/dem.pgm" "$T/m.ply"
check "PLY header" sh -c "head -c 400 '$T/m.ply' | grep -q 'format binary_little_endian 1.0' && head -c 400 '$T/m.ply' | grep -q 'property float nx'"
check "triangle budget respected" sh -c "'$BIN' mesh --triangles 40 --stats '$T/b.json' '$T/dem.pgm' '$T/b.obj' && test \$(grep -c '^f ' '$T/b.obj') -le 40"
check "tiny pool still writes a complete mesh" sh -c "'$BIN' mesh --pool 3 --max-error 0 --stats '$T/p.json' '$T/dem.pgm' '$T/p.obj' 2>'$T/p.err' && grep -q '\"exhausted\": true' '$T/p.json' && grep -q warning '$T/p.err'"
check "skirt adds faces" sh -c "'$BIN' mesh --max-error 1 --cell-size 2 --z-scale 0.5 --skirt 10 '$T/dem.pgm' '$T/k.obj' && test \$(grep -c '^f ' '$T/k.obj') -gt $tris"

# the OBJ's numbers (cli/numfmt.c, not printf): printf's text. numfmt_check
# compares the two on five million values (rounding ties, every style and
# precision); here the OBJ's lines must come back unchanged from printf
# with the formats the writer used before (v %.9g %.10g %.9g, vt %.9g,
# vn %.7g, f integers)
NF="$(dirname "$BIN")/tools/numfmt_check"
if [ -x "$NF" ]; then
    "$NF" >"$T/nf.txt" 2>&1 && ok || bad "numfmt_check: $(grep -m 3 FAIL "$T/nf.txt") $(tail -n 1 "$T/nf.txt")"
else
    bad "$NF not built (make test builds it)"
fi
check "OBJ with normals: its numbers as printf writes them" sh -c "'$BIN' mesh -q --normals --max-error 0.2 --cell-size 0.7 --z-scale 0.013 '$T/dem.pgm' '$T/n.obj' &&
  awk '/^v /{ printf \"v %.9g %.10g %.9g\\n\", \$2, \$3, \$4; next } /^vt /{ printf \"vt %.9g %.9g\\n\", \$2, \$3; next }
    /^vn /{ printf \"vn %.7g %.7g %.7g\\n\", \$2, \$3, \$4; next } { print }' '$T/n.obj' >'$T/n2.obj' &&
  cmp -s '$T/n.obj' '$T/n2.obj' && grep -q '^vn ' '$T/n.obj' && grep -q '^f [0-9]*/[0-9]*/[0-9]* ' '$T/n.obj'"

# --quiet / -q as in the other commands (the bar itself needs a terminal):
# the same bytes, nothing on stderr
check "--quiet and -q accepted, same bytes, silent" sh -c "'$BIN' mesh --quiet --max-error 1 '$T/dem.pgm' '$T/q.obj' 2>'$T/q.err' && '$BIN' mesh -q --max-error 1 '$T/dem.pgm' '$T/q2.obj' 2>>'$T/q.err' && '$BIN' mesh --max-error 1 '$T/dem.pgm' '$T/q3.obj' && cmp -s '$T/q.obj' '$T/q3.obj' && cmp -s '$T/q2.obj' '$T/q3.obj' && test ! -s '$T/q.err'"

# errors: exit 1, one message, nothing written
check "bad number rejected" sh -c "! '$BIN' mesh --max-error abc '$T/dem.pgm' '$T/e.obj' 2>/dev/null && test ! -e '$T/e.obj'"
check "exclusive options rejected" sh -c "! '$BIN' mesh --max-error 1 --triangles 5 '$T/dem.pgm' '$T/e.obj' 2>/dev/null && test ! -e '$T/e.obj'"
check "triangles 0 rejected, not read as unset" sh -c "! '$BIN' mesh --triangles 0 '$T/dem.pgm' '$T/e.obj' 2>'$T/e.err' && grep -q \"^roadsplat: --triangles: '0' must be >= 1\$\" '$T/e.err' && test ! -e '$T/e.obj'"
check "bad extension rejected" sh -c "! '$BIN' mesh '$T/dem.pgm' '$T/e.stl' 2>/dev/null"
check "missing DEM rejected" sh -c "! '$BIN' mesh '$T/nope.pgm' '$T/e.obj' 2>/dev/null && test ! -e '$T/e.obj'"
echo "garbage" > "$T/bad.pgm"
check "failed run leaves an existing output untouched" sh -c "cp '$T/m.obj' '$T/keep.obj' && ! '$BIN' mesh '$T/bad.pgm' '$T/keep.obj' 2>/dev/null && cmp -s '$T/m.obj' '$T/keep.obj'"
check "deterministic output" sh -c "'$BIN' mesh --cell-size 2 --z-scale 0.5 --max-error 1 '$T/dem.pgm' '$T/m2.obj' && cmp -s '$T/m.obj' '$T/m2.obj'"
echo "cli_mesh: $pass passed, $fail failed"
[ "$fail" = 0 ]
