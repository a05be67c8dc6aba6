#!/bin/sh
# CLI tests for road-aligned surface images and --lighting (issue 16,
# docs/surface.md): `surface IMG` is read relative to the folder of the file
# holding the style (--styles FILE or the road file); a missing or
# undecodable image, or one name for two files, fails naming the file, the
# line and the path, leaving no output; --lighting gives the same bytes
# for any --threads and --window; its options are checked.
# Usage: sh tests/cli_surface_test.sh PATH/TO/roadsplat
BIN=${1:?usage: cli_surface_test.sh ROADSPLAT}
. "$(dirname "$0")/cli_lib.sh"
PY=$(dirname "$0")/png_read.py
STRIP=$(dirname "$0")/../docs/examples/asphalt-strip.png
ref_scene "$T"
run() { "$BIN" --quiet "$@"; }
mkdir -p "$T/styles/img" "$T/roads"
cp "$STRIP" "$T/styles/img/strip.png"; cp "$STRIP" "$T/styles/strip.png"
cp "$STRIP" "$T/roads/strip.png"
printf 'style s\n  surface img/strip.png length 20\nend\n' >"$T/styles/s.txt"
cat >"$T/roads/r.txt" <<'R'
style t
  surface strip.png
  line 0 0.15 #FFFFFF dash 3 6
end
road main width 6 style=s
2 2
28 20
end
road side width 3 style=t
0 15
30 15
end
R
check "styles relative to their files" run --styles "$T/styles/s.txt" "$T/dem.pgm" "$T/roads/r.txt" "$T/a.png"
run "$T/dem.pgm" "$T/roads.txt" "$T/plain.png" 2>/dev/null
check "surface differs from plain asphalt" python3 -c "
import sys; sys.path.insert(0, '$(dirname "$PY")'); import png_read as p
a = p.read('$T/a.png'); b = p.read('$T/plain.png'); assert a[:3] == b[:3] and a[3] != b[3]"
# threads and windows, with lighting
check "lit, 1 thread" run --threads 1 --lighting --specular 0.2 --styles "$T/styles/s.txt" "$T/dem.pgm" "$T/roads/r.txt" "$T/l1.png"
check "lit, 3 threads" run --threads 3 --lighting --specular 0.2 --styles "$T/styles/s.txt" "$T/dem.pgm" "$T/roads/r.txt" "$T/l3.png"
check "threads: same bytes" cmp -s "$T/l1.png" "$T/l3.png"
check "lit window" run --window 37,11,50,41 --lighting --specular 0.2 --styles "$T/styles/s.txt" "$T/dem.pgm" \
    "$T/roads/r.txt" "$T/lw.png"
check "window = the same pixels of the whole" python3 -c "
import sys; sys.path.insert(0, '$(dirname "$PY")'); import png_read as p
W, H, c, a = p.read('$T/l1.png'); w, h, c2, b = p.read('$T/lw.png')
assert (c, c2, w, h) == (3, 3, 50, 41)
for y in range(h):
    assert a[((11 + y) * W + 37) * 3:((11 + y) * W + 37 + w) * 3] == b[y * w * 3:(y + 1) * w * 3], y
"
check "lighting changes the picture" sh -c "! cmp -s '$T/a.png' '$T/l1.png'"
check "--sun" run --lighting --sun 90,30 --normal-strength 3 --styles "$T/styles/s.txt" "$T/dem.pgm" "$T/roads/r.txt" "$T/sun.png"
check "another sun, another picture" sh -c "! cmp -s '$T/sun.png' '$T/l1.png'"
# errors: file, line and path; nothing written
rm -f "$T/styles/img/strip.png"
run --styles "$T/styles/s.txt" "$T/dem.pgm" "$T/roads/r.txt" "$T/e1.png" 2>"$T/err" && bad "missing image accepted"
check "missing image: file, line, path ($(cat "$T/err"))" grep -q "s.txt line 2: surface image: .*styles/img/strip.png: No such file" "$T/err"
check "no output after a missing image" test ! -e "$T/e1.png"
echo "not a png" >"$T/roads/strip.png"
run "$T/dem.pgm" "$T/roads/r.txt" "$T/e2.png" 2>"$T/err" && bad "undecodable image accepted"
check "undecodable image: file, line, path ($(cat "$T/err"))" grep -q "r.txt line 2: surface image: .*roads/strip.png" "$T/err"
check "one line" test "$(wc -l <"$T/err")" = 1
check "no output after a bad image" test ! -e "$T/e2.png"
cp "$STRIP" "$T/roads/strip.png"
cp "$STRIP" "$T/styles/img/strip.png"; cp "$STRIP" "$T/styles/strip.png"
printf 'style u\n  surface strip.png\nend\n' >"$T/styles/u.txt"
run --styles "$T/styles/u.txt" "$T/dem.pgm" "$T/roads/r.txt" "$T/e3.png" 2>"$T/err" && bad "one name for two files accepted"
check "one name, two files ($(cat "$T/err"))" grep -q "r.txt line 2: surface image 'strip.png' is .*roads/strip.png here but .*styles/strip.png" "$T/err"
printf 'style s\n  surface img/strip.png length 0\nend\n' >"$T/styles/bad.txt"
run --styles "$T/styles/bad.txt" "$T/dem.pgm" "$T/roads/r.txt" "$T/e4.png" 2>"$T/err" && bad "length 0 accepted"
check "bad length named ($(cat "$T/err"))" grep -q "bad.txt: line 2: surface length '0' must be" "$T/err"
# lighting options
run --sun 90,30 "$T/dem.pgm" "$T/roads.txt" "$T/e5.png" 2>"$T/err" && bad "--sun without --lighting accepted"
check "--sun needs --lighting" grep -q "need --lighting" "$T/err"
run --lighting --sun 90,0 "$T/dem.pgm" "$T/roads.txt" "$T/e6.png" 2>"$T/err" && bad "altitude 0 accepted"
check "bad sun named" grep -q -- "--sun: '90,0'" "$T/err"
run --lighting --sun 90 "$T/dem.pgm" "$T/roads.txt" "$T/e7.png" 2>"$T/err" && bad "one number accepted"
run --lighting --specular 2 "$T/dem.pgm" "$T/roads.txt" "$T/e8.png" 2>"$T/err" && bad "specular 2 accepted"
check "bad specular named" grep -q -- "--specular: '2' must be in \[0, 1\]" "$T/err"
run --lighting=yes "$T/dem.pgm" "$T/roads.txt" "$T/e9.png" 2>"$T/err" && bad "--lighting=yes accepted"
check "no outputs after errors" test ! -e "$T/e3.png" -a ! -e "$T/e4.png" -a ! -e "$T/e5.png" -a ! -e "$T/e6.png" \
    -a ! -e "$T/e7.png" -a ! -e "$T/e8.png" -a ! -e "$T/e9.png"
check "--help lists --lighting" sh -c "'$BIN' --help | grep -q -- '--lighting'"
echo "cli_surface: $pass passed, $fail failed"
[ "$fail" = 0 ]
