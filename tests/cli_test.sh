#!/bin/sh
# CLI tests for `roadsplat DEM ROADS OUT.png`: usage, bad input (exit 1, one
# clear line naming the file, no output left behind), atomic replacement,
# determinism, the OpenImageIO DEM path. Usage: cli_test.sh path/to/roadsplat
RS=${1:-build/roadsplat}
. "$(dirname "$0")/cli_lib.sh"
# the read-only folder test leaves a folder rm cannot empty without u+w
trap 'chmod -R u+w "$T" 2>/dev/null; rm -rf "$T"' EXIT
# expect_fail NAME PATTERN ARGS... : exit 1, stderr one line matching PATTERN, no $T/out.png
expect_fail() {
    name=$1; pat=$2; shift 2
    rm -f "$T/out.png"
    "$RS" "$@" >"$T/stdout" 2>"$T/stderr"; rc=$?
    lines=$(wc -l <"$T/stderr")
    if [ $rc -ne 1 ]; then bad "$name: exit $rc, expected 1"; return; fi
    if [ "$lines" -ne 1 ]; then bad "$name: $lines stderr lines: $(cat "$T/stderr")"; return; fi
    if ! grep -q -- "$pat" "$T/stderr"; then bad "$name: stderr '$(cat "$T/stderr")' lacks '$pat'"; return; fi
    if [ -e "$T/out.png" ]; then bad "$name: left out.png behind"; return; fi
    if ls "$T" | grep -q '\.tmp'; then bad "$name: left a temporary file"; return; fi
    ok
}

E=docs/examples
ref_scene "$T"

# --- usage ---
"$RS" --help >"$T/o" 2>"$T/e" && grep -q "Usage: roadsplat" "$T/o" && [ ! -s "$T/e" ] && ok || bad "--help"
"$RS" --version >"$T/o" 2>&1 && grep -Eq "^roadsplat [0-9]+\.[0-9]+\.[0-9]+$" "$T/o" && ok || bad "--version"
expect_fail "no arguments" "expected DEM ROADS OUT.png"
expect_fail "unknown option" "unknown option '--frobnicate'" --frobnicate "$T/dem.pgm" "$T/roads.txt" "$T/out.png"
expect_fail "missing value" "option --texels needs a value" "$T/dem.pgm" "$T/roads.txt" "$T/out.png" --texels
expect_fail "texels junk" "--texels" --texels 4x "$T/dem.pgm" "$T/roads.txt" "$T/out.png"
expect_fail "decimal comma" "--cell-size" --cell-size 2,5 "$T/dem.pgm" "$T/roads.txt" "$T/out.png"
expect_fail "nan cell size" "--cell-size" --cell-size nan "$T/dem.pgm" "$T/roads.txt" "$T/out.png"
expect_fail "huge number" "--z-scale" --z-scale 1e999 "$T/dem.pgm" "$T/roads.txt" "$T/out.png"
expect_fail "negative cell" "--cell-size" --cell-size -5 "$T/dem.pgm" "$T/roads.txt" "$T/out.png"
expect_fail "bad buffer" "'distance' or 'dilate'" --buffer blur "$T/dem.pgm" "$T/roads.txt" "$T/out.png"
expect_fail "too many args" "unexpected argument" "$T/dem.pgm" "$T/roads.txt" "$T/out.png" extra

# --- bad input files ---
expect_fail "missing DEM" "$T/nope.pgm" "$T/nope.pgm" "$T/roads.txt" "$T/out.png"
expect_fail "missing roads" "$T/nope.txt" "$T/dem.pgm" "$T/nope.txt" "$T/out.png"
printf 'P5\n4 4\n255\n\001\002' >"$T/trunc.pgm"
expect_fail "truncated PGM" "trunc.pgm" "$T/trunc.pgm" "$T/roads.txt" "$T/out.png"
printf 'P2\n3 3\n0\n0 0 0 0 0 0 0 0 0\n' >"$T/maxval0.pgm"
expect_fail "maxval 0" "maxval0.pgm" "$T/maxval0.pgm" "$T/roads.txt" "$T/out.png"
: >"$T/empty.pgm"
expect_fail "empty DEM" "empty.pgm" "$T/empty.pgm" "$T/roads.txt" "$T/out.png"
printf 'road a width 4\n1 1\nbogus 2 2\nend\n' >"$T/kw.txt"
expect_fail "unknown keyword" "kw.txt: line 3" "$T/dem.pgm" "$T/kw.txt" "$T/out.png"
printf 'road a width 4\n1 1\n2 2\n' >"$T/noend.txt"
expect_fail "missing end" "noend.txt" "$T/dem.pgm" "$T/noend.txt" "$T/out.png"
printf 'road a width 0\n1 1\n2 2\nend\n' >"$T/w0.txt"
expect_fail "zero width" "w0.txt: line 1" "$T/dem.pgm" "$T/w0.txt" "$T/out.png"
printf 'road a width 4\n1,5 1\n2 2\nend\n' >"$T/comma.txt"
expect_fail "decimal comma in roads" "comma.txt: line 2" "$T/dem.pgm" "$T/comma.txt" "$T/out.png"
expect_fail "output too large" "exceeds the limit" --texels 1024 "$T/dem.pgm" "$T/roads.txt" "$T/out.png"
expect_fail "unreadable texture" "nope.png" --road-texture "$T/nope.png" "$T/dem.pgm" "$T/roads.txt" "$T/out.png"

# --- a good run, atomic output, determinism ---
"$RS" --quiet --weight-out "$T/w.pgm" --stats "$T/s.json" "$T/dem.pgm" "$T/roads.txt" "$T/a.png" 2>"$T/e"
[ $? -eq 0 ] && [ ! -s "$T/e" ] && ok || bad "good run: $(cat "$T/e")"
head -c 8 "$T/a.png" | od -An -c | grep -q "P   N   G" && ok || bad "output is not a PNG"
head -c 16 "$T/w.pgm" | grep -q "P5" && head -3 "$T/w.pgm" | grep -q "^240 160$" && ok || bad "weight PGM header"
for k in '"read"' '"roads"' '"splat"' '"write"' '"total"' '"road_cells"' '"boundary_by_type"' '"k"'; do
    grep -q "$k" "$T/s.json" && ok || bad "stats lacks $k"
done
"$RS" --quiet "$T/dem.pgm" "$T/roads.txt" "$T/b.png" && cmp -s "$T/a.png" "$T/b.png" && ok || bad "not deterministic"
cp "$T/a.png" "$T/out.png"
before=$(cksum <"$T/out.png")
printf 'road a width 4\n1 1\n' >"$T/cut.txt"
"$RS" --quiet "$T/dem.pgm" "$T/cut.txt" "$T/out.png" 2>/dev/null
[ $? -eq 1 ] && [ "$(cksum <"$T/out.png")" = "$before" ] && ok || bad "failed run changed the existing OUT"
mkdir "$T/ro" && chmod 555 "$T/ro"
if [ "$(id -u)" != 0 ]; then
    "$RS" --quiet "$T/dem.pgm" "$T/roads.txt" "$T/ro/x.png" 2>"$T/e"
    [ $? -eq 1 ] && grep -q "ro/x.png" "$T/e" && [ ! -e "$T/ro/x.png" ] && ok || bad "unwritable folder"
fi
"$RS" --quiet "$T/dem.pgm" "$T/roads.txt" "$T/nodir/x.png" 2>"$T/e"
[ $? -eq 1 ] && grep -q "nodir" "$T/e" && ok || bad "missing folder: $(cat "$T/e")"
# empty road file is valid: terrain only
: >"$T/none.txt"
"$RS" --quiet "$T/dem.pgm" "$T/none.txt" "$T/n.png" && ok || bad "empty road file"

# --- --origin: the same roads in UTM-like world coordinates give the same image ---
awk '/^road|^end|^#/ {print; next} NF == 2 {printf "%.3f %.3f\n", $1 + 500000, $2 + 5000000; next} {print}' \
    "$T/roads.txt" >"$T/utm.txt"
"$RS" --quiet --origin 500000,5000000 "$T/dem.pgm" "$T/utm.txt" "$T/u.png" && cmp -s "$T/a.png" "$T/u.png" && ok \
    || bad "--origin: translated scene differs"
expect_fail "bad origin" "--origin" --origin 5,x "$T/dem.pgm" "$T/roads.txt" "$T/out.png"

# --- the same DEM as an 8-bit PNG through OpenImageIO gives the same image ---
python3 - "$T/dem.pgm" "$T/dem.png" <<'PY' && ok || bad "could not make a PNG DEM"
import sys, zlib, struct
toks = open(sys.argv[1]).read().split()
w, h = int(toks[1]), int(toks[2]); v = [int(t) for t in toks[4:4 + w * h]]
raw = b''.join(b'\0' + bytes(v[y * w:(y + 1) * w]) for y in range(h))
def chunk(t, d): return struct.pack('>I', len(d)) + t + d + struct.pack('>I', zlib.crc32(t + d) & 0xffffffff)
open(sys.argv[2], 'wb').write(b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, 0, 0, 0, 0))
    + chunk(b'IDAT', zlib.compress(raw)) + chunk(b'IEND', b''))
PY
"$RS" --quiet "$T/dem.png" "$T/roads.txt" "$T/c.png" && cmp -s "$T/a.png" "$T/c.png" && ok || bad "PNG DEM differs from PGM DEM"

# --- threads and windows: the same bytes whatever the cut ---
for n in 1 2 3 7; do
    "$RS" --quiet --threads $n --weight-out "$T/wt$n.pgm" "$T/dem.pgm" "$T/roads.txt" "$T/t$n.png" &&
        cmp -s "$T/a.png" "$T/t$n.png" && cmp -s "$T/w.pgm" "$T/wt$n.pgm" && ok || bad "--threads $n differs"
done
# crop_pgm IN X Y W H OUT: the rows of a 16-bit P5 window, 240 samples a row
crop_pgm() {
    hdr=$(head -3 "$1" | wc -c)
    y=0; : >"$6"
    while [ $y -lt "$5" ]; do
        tail -c +$((hdr + 1 + ( ($3 + y) * 240 + $2) * 2)) "$1" | head -c $(($4 * 2)) >>"$6"
        y=$((y + 1))
    done
}
for win in "0,0,240,160" "17,5,33,41" "239,159,1,1" "101,0,7,160"; do
    set -- $(echo "$win" | tr , ' ')
    "$RS" --quiet --threads 2 --window "$win" --weight-out "$T/ww.pgm" "$T/dem.pgm" "$T/roads.txt" "$T/win.png" 2>"$T/e" ||
        { bad "--window $win: $(cat "$T/e")"; continue; }
    head -3 "$T/ww.pgm" | grep -q "^$3 $4\$" && ok || bad "--window $win: size"
    hdr=$(head -3 "$T/ww.pgm" | wc -c)
    tail -c +$((hdr + 1)) "$T/ww.pgm" >"$T/ww.raw"
    crop_pgm "$T/w.pgm" "$@" "$T/crop.raw"
    cmp -s "$T/ww.raw" "$T/crop.raw" && ok || bad "--window $win is not the crop of the whole image"
done
"$RS" --quiet --window 10,20,30,40 --stats "$T/ws.json" "$T/dem.pgm" "$T/roads.txt" "$T/win.png" &&
    grep -q '"window": {"x": 10, "y": 20, "width": 30, "height": 40}' "$T/ws.json" && ok || bad "--window stats"
for k in '"stages_ms"' '"coverage"' '"surface"' '"overlays"' '"composite"' '"threads"' '"edges"'; do
    grep -q "$k" "$T/ws.json" && ok || bad "stats lacks $k"
done
expect_fail "window outside" "not inside the 240 x 160 output" --window 200,0,41,5 "$T/dem.pgm" "$T/roads.txt" "$T/out.png"
expect_fail "window empty" "width and height must be >= 1" --window 0,0,0,5 "$T/dem.pgm" "$T/roads.txt" "$T/out.png"
expect_fail "window junk" "--window" --window 1,2,3 "$T/dem.pgm" "$T/roads.txt" "$T/out.png"
expect_fail "window negative" "--window" --window -1,2,3,4 "$T/dem.pgm" "$T/roads.txt" "$T/out.png"
expect_fail "threads 0" "--threads" --threads 0 "$T/dem.pgm" "$T/roads.txt" "$T/out.png"
expect_fail "bad edges" "'alphamap' or 'analytic'" --edges smooth "$T/dem.pgm" "$T/roads.txt" "$T/out.png"
"$RS" --quiet --edges analytic --threads 1 "$T/dem.pgm" "$T/roads.txt" "$T/an1.png" &&
    "$RS" --quiet --edges analytic --threads 2 "$T/dem.pgm" "$T/roads.txt" "$T/an2.png" &&
    cmp -s "$T/an1.png" "$T/an2.png" && ok || bad "--edges analytic: threads differ or failed"

# --- the bundled example renders ---
"$RS" --quiet --cell-size 5 --z-scale 0.01 --texels 2 "$E/dem.pgm" "$E/roads.txt" "$T/ex.png" && ok || bad "example"

# --- road styles (issue 13) ---
expect_fail "bad profile" "--profile: 'fr'" --profile fr "$T/dem.pgm" "$T/roads.txt" "$T/out.png"
expect_fail "bad aa" "--aa: 'smooth'" --aa smooth "$T/dem.pgm" "$T/roads.txt" "$T/out.png"
expect_fail "missing styles file" "$T/nostyles.txt" --styles "$T/nostyles.txt" "$T/dem.pgm" "$T/roads.txt" "$T/out.png"
printf 'style s\n  line 0 0.2 #FFFFFF\n  fill #12345\nend\n' >"$T/badstyle.txt"
expect_fail "bad style line" "badstyle.txt: line 3" --styles "$T/badstyle.txt" "$T/dem.pgm" "$T/roads.txt" "$T/out.png"
sed 's/^road \([^ ]*\) width \([^ ]*\)$/road \1 width \2 style=nowhere/' "$T/roads.txt" >"$T/undef.txt"
expect_fail "undefined style" "style 'nowhere' is not defined" "$T/dem.pgm" "$T/undef.txt" "$T/out.png"
# the example's classed roads: styled differs from --no-styles; threads and windows stay byte-identical
"$RS" --quiet --cell-size 5 --z-scale 0.01 --texels 2 --threads 1 "$E/dem.pgm" "$E/roads.txt" "$T/st1.png" &&
    "$RS" --quiet --cell-size 5 --z-scale 0.01 --texels 2 --threads 3 "$E/dem.pgm" "$E/roads.txt" "$T/st3.png" &&
    cmp -s "$T/st1.png" "$T/st3.png" && ok || bad "styled example: threads differ or failed"
"$RS" --quiet --cell-size 5 --z-scale 0.01 --texels 2 --no-styles "$E/dem.pgm" "$E/roads.txt" "$T/plain.png" &&
    ! cmp -s "$T/st1.png" "$T/plain.png" && ok || bad "--no-styles gives the styled image"
"$RS" --quiet --cell-size 5 --z-scale 0.01 --texels 2 --aa hermite --profile us "$E/dem.pgm" "$E/roads.txt" "$T/us.png" &&
    ! cmp -s "$T/st1.png" "$T/us.png" && ok || bad "--aa hermite --profile us"
# the styled, marked junction (casings + lines + markings): windows at odd
# offsets, a 1-px row and the last partial rows are crops of the whole image
# (issue 25: line scratch overwrote the casing coverage per piece)
J="--quiet --cell-size 2 --z-scale 0.01 --texels 20"
"$RS" $J "$E/junction-dem.pgm" "$E/junction.txt" "$T/jw.png" || bad "junction whole"
for win in "3,341,397,1" "0,797,800,3" "77,1,9,798" "41,330,559,70"; do
    "$RS" $J --threads 2 --window "$win" "$E/junction-dem.pgm" "$E/junction.txt" "$T/jwin.png" &&
        python3 - "$T/jw.png" "$T/jwin.png" "$win" <<'PY' && ok || bad "styled junction --window $win is not the crop"
import sys
sys.path.insert(0, 'tests')
from png_read import read
W, H, C, a = read(sys.argv[1])
w, h, c, b = read(sys.argv[2])
x, y, ww, hh = map(int, sys.argv[3].split(','))
assert (w, h, c) == (ww, hh, C)
for j in range(h):
    assert a[((y + j) * W + x) * C:((y + j) * W + x + w) * C] == b[j * w * C:(j + 1) * w * C], 'row %d' % j
PY
done

# --- the README's C example compiles against the header and runs ---
B=$(dirname "$RS")
sed -n '/^```c$/,/^```$/p' README.md | sed '1d;$d' >"$T/example.c"
if ${CC:-cc} -std=c99 -Wall -Werror $SAN -Iinclude "$T/example.c" "$B/libroadsplat.a" -lm -o "$T/example" 2>"$T/e"; then
    "$T/example" && ok || bad "README example failed to run"
else
    bad "README example does not compile: $(head -3 "$T/e")"
fi

echo "cli: $pass passed, $fail failed"
[ $fail -eq 0 ]
