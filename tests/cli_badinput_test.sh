#!/bin/sh
# Bad-input catalogue of the CLI (issue 4). Every malformed DEM (PGM, and
# PNG through OpenImageIO) and road file must: exit 1 (not hang, not crash),
# print exactly one stderr line naming the file (and the line) and the
# problem, leave no output and no temporary file, and leave an existing OUT
# byte-identical - for `roadsplat` and, with the DEMs, `roadsplat mesh`.
# Unusual but valid input must succeed; write errors (full disk simulated
# with RLIMIT_FSIZE, unwritable targets) must keep the old OUT.
# Cases tests/cli_test.sh already runs (empty/truncated P5/maxval-0 DEM,
# 'bogus' keyword, missing 'end', zero width, comma in a point, empty road
# file) are not repeated here, except through `mesh`.
# Usage: sh tests/cli_badinput_test.sh PATH/TO/roadsplat
# With CLI_CATALOGUE=FILE set, appends "case<TAB>stderr line" for every refusal.
RS=${1:?usage: cli_badinput_test.sh ROADSPLAT}
. "$(dirname "$0")/cli_lib.sh"
# Under LeakSanitizer (make sanitize-test), OpenImageIO's PNG reader leaks a
# string on every corrupt PNG; tests/lsan.supp names its frame, which only
# full stacks reach (too slow for the render tests, so only here).
if [ -n "${LSAN_OPTIONS:-}" ]; then LSAN_OPTIONS="$LSAN_OPTIONS:fast_unwind_on_malloc=0"; export LSAN_OPTIONS; fi
O=$T/out   # OUT lives alone in here, so any leftover file is visible
D=$T/in
mkdir "$D"

# --- inputs -------------------------------------------------------------------
# Reference scene: a 31x21 DEM and two roads (as in cli_test.sh).
ref_scene "$D"
printf 'P2\n3 3\n9\n0 0 0 0 0 0 0 0 0\n' >"$D/flat.pgm"
: >"$D/none.txt"
"$RS" --quiet "$D/dem.pgm" "$D/roads.txt" "$T/ref.png" || bad "reference run failed"
"$RS" --quiet "$D/dem.pgm" "$D/none.txt" "$T/terrain.png" || bad "terrain-only run failed"
printf 'old contents of OUT\n' >"$T/old"

# verdict NAME PATTERN RC : exit 1, one stderr line matching PATTERN (grep -E)
verdict() {
    if [ "$3" -eq 124 ]; then bad "$1: hung (killed after 20 s)"; return 1; fi
    if [ "$3" -gt 128 ]; then bad "$1: crashed (signal $(($3 - 128)))"; return 1; fi
    if [ "$3" -ne 1 ]; then bad "$1: exit $3, expected 1"; return 1; fi
    n=$(wc -l <"$T/stderr")
    if [ "$n" -ne 1 ] || [ "$(wc -c <"$T/stderr")" -gt 1000 ]; then
        bad "$1: $n stderr lines: $(head -c 300 "$T/stderr")"; return 1
    fi
    if ! grep -Eq -- "$2" "$T/stderr"; then bad "$1: stderr '$(cat "$T/stderr")' does not match '$2'"; return 1; fi
    return 0
}

# refuse NAME PATTERN OUTNAME ARGS... : ARGS name $O/OUTNAME as the output.
# $mode "fresh": run without OUT (nothing may appear in $O); "old": run with
# an existing OUT (it must stay byte-identical and alone in $O); "both".
# Every CLI start costs ~0.2 s (OpenImageIO, OSMesa), so a bad DEM runs
# "old" through `roadsplat` and "fresh" through `roadsplat mesh`.
refuse() {
    name=$1; pat=$2; out=$3; shift 3
    rm -rf "$O"; mkdir "$O"
    if [ "$mode" != old ]; then
        timeout 20 "$RS" "$@" >/dev/null 2>"$T/stderr"
        verdict "$name" "$pat" $? || return
        if [ -n "$(ls -A "$O")" ]; then bad "$name: left $(ls -A "$O") behind"; return; fi
    fi
    if [ "$mode" != fresh ]; then
        cp "$T/old" "$O/$out"
        timeout 20 "$RS" "$@" >/dev/null 2>"$T/stderr"
        verdict "$name (existing OUT)" "$pat" $? || return
        cmp -s "$T/old" "$O/$out" || { bad "$name: the existing OUT changed"; return; }
        [ "$(ls -A "$O")" = "$out" ] || { bad "$name: left $(ls -A "$O") behind"; return; }
    fi
    [ -n "$CLI_CATALOGUE" ] && printf '%s\t%s\n' "$name" "$(cat "$T/stderr")" >>"$CLI_CATALOGUE"
    ok
}
# A bad DEM, through `roadsplat` and `roadsplat mesh`; the pattern is
# prefixed with the file's name.
bad_dem() {
    mode=old refuse "DEM $1" "^roadsplat: $D/$1: $2\$" o.png --quiet "$D/$1" "$D/roads.txt" "$O/o.png"
    bad_mesh "$1" "$2"
}
bad_mesh() { mode=fresh refuse "mesh DEM $1" "^roadsplat: $D/$1: $2\$" m.obj mesh "$D/$1" "$O/m.obj"; }
bad_roads() { mode=both refuse "roads $1" "^roadsplat: $D/$1: $2\$" o.png --quiet "$D/dem.pgm" "$D/$1" "$O/o.png"; }
# Deterministic junk bytes: junk FILE COUNT SEED [PREFIX]
junk() {
    python3 - "$2" "$3" "${4:-}" >"$D/$1" <<'PY'
import os, random, sys
r = random.Random(int(sys.argv[2]))
sys.stdout.buffer.write(os.fsencode(sys.argv[3]) + bytes(r.randrange(256) for _ in range(int(sys.argv[1]))))
PY
}
mb2() { head -c 2000000 /dev/zero | tr '\0' "$1"; } # a 2 MB run of one character

# --- bad DEMs (PGM) -------------------------------------------------------------
: >"$D/empty.pgm"; bad_mesh empty.pgm 'not a PGM file.*'
printf 'P5\n4 4\n255\n\001\002' >"$D/trunc5.pgm"; bad_mesh trunc5.pgm 'PGM truncated: 4x4 samples need 16 bytes, only 2 present.*'
printf 'P2\n3 3\n0\n0 0 0 0 0 0 0 0 0\n' >"$D/maxval0.pgm"; bad_mesh maxval0.pgm 'PGM line 3: maxval 0 is outside 1..65535'
printf 'P2\n31' >"$D/trunc-header.pgm"; bad_dem trunc-header.pgm 'PGM line 2: header truncated: height missing'
printf 'P2\n3 3\n9\n1 2 3\n4 5\n' >"$D/trunc-short.pgm"
bad_dem trunc-short.pgm 'PGM truncated: 3x3 samples cannot fit in the 11 bytes after the header'
printf 'P2\n3 3\n999\n100 200 300\n400 500\n' >"$D/trunc-samples.pgm"
bad_dem trunc-samples.pgm 'PGM line 6: truncated: 5 of 9 samples present'
printf 'P7\n3 3\n255\n0 0 0 0 0 0 0 0 0\n' >"$D/magic.pgm"; bad_dem magic.pgm 'not a PGM file \(expected "P2" or "P5" at the start\)'
printf 'hello, I am no image\n' >"$D/magic.dat"; bad_dem magic.dat 'cannot read image: .*'
printf 'P2\n99999999999999999999999 3\n255\n1\n' >"$D/huge-digits.pgm"
bad_dem huge-digits.pgm 'PGM line 2: width is too large \(more than 64 bits\)'
printf 'P2\n4294967297 4294967297\n255\n1\n' >"$D/overflow.pgm"
bad_dem overflow.pgm 'PGM line 3: DEM is 4294967297x4294967297; the limit is 16384 samples per side'
printf 'P5\n100000 100000\n255\n\001' >"$D/over-limit.pgm"
bad_dem over-limit.pgm 'PGM line 3: DEM is 100000x100000; the limit is 16384 samples per side'
printf 'P5\n16384 16384\n65535\n\001' >"$D/huge-claim.pgm"
bad_dem huge-claim.pgm 'PGM truncated: 16384x16384 samples need 536870912 bytes, only 1 present.*'
if truncate -s 9G "$D/sparse9g.pgm" 2>/dev/null; then # refused by size, before reading or allocating
    bad_dem sparse9g.pgm 'file is larger than the 8589934592-byte limit'
    rm -f "$D/sparse9g.pgm"
fi
printf 'P2\n3 3\n65536\n0 0 0 0 0 0 0 0 0\n' >"$D/maxval-big.pgm"; bad_dem maxval-big.pgm 'PGM line 3: maxval 65536 is outside 1..65535'
printf 'P2\n3 3\n10\n0 0 0\n0 11 0\n0 0 0\n' >"$D/above.pgm"
bad_dem above.pgm 'PGM line 5: sample 4 \(row 1, column 1\) is 11, above maxval 10'
printf 'P5\n2 2\n1000\n\000\000\003\351\000\000\000\000' >"$D/above16.pgm"
bad_dem above16.pgm 'PGM sample 1 \(row 0, column 1\) is 1001, above maxval 1000'
printf 'P5\n2 2\n10\n\000\013\000\000' >"$D/above8.pgm"
bad_dem above8.pgm 'PGM sample 1 \(row 0, column 1\) is 11, above maxval 10'
printf 'P2\n31 abc\n255\n' >"$D/garbage-header.pgm"
bad_dem garbage-header.pgm "PGM line 2: height must be a decimal number, got 'a'"
printf 'P2\n3 3\n10\n0 0 0\n0 x 0\n0 0 0\n' >"$D/garbage.pgm"; bad_dem garbage.pgm "PGM line 5: sample 4: expected a number, got 'x'"
printf 'P2\n3 3 10 0 0 0 0 0 0 0 0 0 7\n' >"$D/extra.pgm"
bad_dem extra.pgm "PGM line 2: unexpected '7' after the last of 9 samples; width/height wrong\?"
printf 'P2\n2 2\n10\n0 nan\n0 0\n' >"$D/nan.pgm"; bad_dem nan.pgm "PGM line 4: sample 1: expected a number, got 'n'"
printf 'P2\n2 2\n10\ninf 0\n0 0\n' >"$D/inf.pgm"; bad_dem inf.pgm "PGM line 4: sample 0: expected a number, got 'i'"
printf 'P2\n2 2\n10\n0 0\n1e999 0\n' >"$D/1e999.pgm"; bad_dem 1e999.pgm "PGM line 5: sample 2: unexpected 'e' after the number"
printf 'P2\n2 2\n10\n0 1,5\n0 0\n' >"$D/comma.pgm"; bad_dem comma.pgm "PGM line 4: sample 1: unexpected ',' after the number"
printf 'P2\n2 2\n10\n0 1.5\n0 0\n' >"$D/point.pgm"; bad_dem point.pgm "PGM line 4: sample 1: unexpected '.' after the number"
printf 'P2\n0 21\n255\n' >"$D/width0.pgm"; bad_dem width0.pgm 'PGM line 3: DEM is 0x21; width and height must be >= 2'
printf 'P2\n-31 21\n255\n' >"$D/width-neg.pgm"; bad_dem width-neg.pgm "PGM line 2: width must be a decimal number, got '-'"
printf 'P2\n1 3\n9\n1 2 3\n' >"$D/width1.pgm"; bad_dem width1.pgm 'PGM line 3: DEM is 1x3; width and height must be >= 2'
junk junk.pgm 4096 1; bad_dem junk.pgm 'not a PGM file.*'
junk junk-body.pgm 64 2 'P2 4 4 255 '; bad_dem junk-body.pgm 'PGM line 1: sample 0: expected a number, got (byte 0x..|.*)'
printf 'P2\n2 2\n9\n0 0\n0 \0000\n' >"$D/nul.pgm"; bad_dem nul.pgm 'PGM line 5: sample 3: expected a number, got byte 0x00'
printf 'P5\n2 2\n255\n\001\002\003\004junk' >"$D/trailing.pgm"
bad_dem trailing.pgm 'PGM: 4 unexpected bytes after the last sample \(offset 15\); width/height wrong\?'
{ printf 'P2\n2 2\n9\n'; mb2 7; printf ' 0 0 0\n'; } >"$D/2mb-digits.pgm"
bad_dem 2mb-digits.pgm 'PGM line 4: sample 0 \(row 0, column 0\) is too large, above maxval 9'
{ printf 'P2\n2 2\n9\n'; i=0; while [ $i -lt 4 ]; do mb2 ' ' | head -c 500000; printf '1 '; i=$((i + 1)); done; printf '2\n'; } \
    >"$D/2mb-samples.pgm"
bad_dem 2mb-samples.pgm "PGM line 4: unexpected '2' after the last of 4 samples; width/height wrong\?"

# --- bad DEMs through OpenImageIO (PNG) -----------------------------------------------
python3 - "$D" <<'PY' || bad "could not write the PNG inputs"
import struct, sys, zlib
d = sys.argv[1]
def chunk(t, b): return struct.pack('>I', len(b)) + t + b + struct.pack('>I', zlib.crc32(t + b) & 0xffffffff)
def png(w, h, raw): return (b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, 0, 0, 0, 0))
                            + chunk(b'IDAT', zlib.compress(raw)) + chunk(b'IEND', b''))
good = png(31, 21, b''.join(b'\0' + bytes((y * 31 + x) % 97 for x in range(31)) for y in range(21)))
open(d + '/good.png', 'wb').write(good)
open(d + '/trunc-idat.png', 'wb').write(good[:60])
open(d + '/trunc-ihdr.png', 'wb').write(good[:20])
open(d + '/signature.png', 'wb').write(good[:8])
open(d + '/empty.png', 'wb').write(b'')
open(d + '/huge.png', 'wb').write(png(100000, 100000, b'\0' * 1000))
open(d + '/bad-crc.png', 'wb').write(good[:29] + bytes([good[29] ^ 0xFF]) + good[30:])
PY
junk garbage.png 3000 3 "$(printf '\211PNG\r\n\032\n')"
bad_dem trunc-idat.png 'cannot read pixels: .*'
bad_dem trunc-ihdr.png 'cannot read image: .*'
bad_dem signature.png 'cannot read image: .*'
bad_dem empty.png 'cannot read image: .*'
bad_dem garbage.png 'cannot read (image|pixels): .*'
bad_dem bad-crc.png 'cannot read (image|pixels): .*'
bad_dem huge.png 'image too large \(100000x100000\)'
mode=old refuse "mesh DEM garbage.png" "^roadsplat: $D/garbage.png: cannot read (image|pixels): .*" m.obj \
    mesh "$D/garbage.png" "$O/m.obj"
"$RS" --quiet "$D/good.png" "$D/roads.txt" "$T/good.png" && cmp -s "$T/good.png" "$T/ref.png" && ok \
    || bad "the PNG twin of the reference DEM gives another image"
# DEM and ROADS swapped (the road file starts with comments)
{ printf '# roads\n\n'; cat "$D/roads.txt"; } >"$D/commented-roads.txt"
bad_dem commented-roads.txt 'this is a road file, not a DEM \(arguments in the wrong order\?\)'
# a broken texture costs one line too (libpng's own "libpng error: ..." is filtered)
mode=both refuse "terrain texture trunc-idat.png" "^roadsplat: $D/trunc-idat.png: cannot read pixels: .*" o.png \
    --quiet --terrain-texture "$D/trunc-idat.png" "$D/dem.pgm" "$D/roads.txt" "$O/o.png"
mode=fresh refuse "road texture bad-crc.png" "^roadsplat: $D/bad-crc.png: cannot read (image|pixels): .*" o.png \
    --quiet --road-texture "$D/bad-crc.png" "$D/dem.pgm" "$D/roads.txt" "$O/o.png"

# --- TIFF layouts that make OpenImageIO 2.4 allocate far beyond the image ---------
# Its strip reader sizes a buffer by RowsPerStrip even past the image height
# (a 161-byte fuzz input asked for 24.7 GB); tiles and rows are buffered whole.
python3 - "$D" <<'PY' || bad "could not write the TIFF inputs"
import struct, sys, zlib
d = sys.argv[1]
def tiff(name, w, h, spp, bits, fmt, extra, data):
    e = [(256, 4, w), (257, 4, h), (258, 3, bits), (259, 3, 8), (262, 3, 1), (277, 3, spp),
         (284, 3, 1), (339, 3, fmt)] + extra
    off = 8 + 2 + 12 * len(e) + 4
    out = b'II*\0' + struct.pack('<IH', 8, len(e))
    for tag, typ, val in sorted(e):
        val = off if val == 'DATA' else len(data) if val == 'SIZE' else val
        out += struct.pack('<HHIHH' if typ == 3 else '<HHII', tag, typ, 1, *((val, 0) if typ == 3 else (val,)))
    open(d + '/' + name, 'wb').write(out + struct.pack('<I', 0) + data)
dem = bytes((y * 31 + x) % 97 for y in range(21) for x in range(31))  # the reference DEM
strips = [(273, 4, 'DATA'), (279, 4, 'SIZE')]
tiff('rows-per-strip-385M.tif', 31, 21, 1, 8, 1, strips + [(278, 4, 385875970)], zlib.compress(dem))
tiff('tile-32768.tif', 31, 21, 1, 8, 1, [(322, 4, 32768), (323, 4, 32768), (324, 4, 'DATA'), (325, 4, 'SIZE')],
     zlib.compress(dem))
tiff('channels-1000.tif', 300000, 2, 1000, 8, 1, strips + [(278, 4, 1)], zlib.compress(b'\0' * 64))
PY
# the valid one must load without the huge buffer: under a 4 GB address-space
# limit when the binary runs under one (sanitizer builds reserve more)
if (ulimit -v 4000000 && "$RS" --version) >/dev/null 2>&1; then lim="ulimit -v 4000000"; else lim=:; fi
(eval "$lim"; "$RS" --quiet "$D/rows-per-strip-385M.tif" "$D/roads.txt" "$T/rps.png") && cmp -s "$T/rps.png" "$T/ref.png" \
    && ok || bad "a TIFF with RowsPerStrip above its height (the reference DEM) fails or differs"
bad_dem tile-32768.tif 'tiles of 32768x32768 pixels are too large \(at most 256 MiB each\)'
bad_dem channels-1000.tif 'unsupported image layout \(1000 channels of 300000 pixels per row\)'

# --- bad road files ---------------------------------------------------------------
printf 'road a width 4\n1 1\n2' >"$D/trunc-point.txt"; bad_roads trunc-point.txt "line 3: point needs 'X Y', got only '2'"
printf 'road a wid' >"$D/trunc-keyword.txt"; bad_roads trunc-keyword.txt "line 1: road 'a': expected 'width', got 'wid'"
printf 'road a width\n' >"$D/no-width.txt"; bad_roads no-width.txt "line 1: road 'a': the width value is missing"
cp "$D/good.png" "$D/magic.txt"; bad_roads magic.txt 'line 1: invalid UTF-8 byte 0x89 at column 1 \(binary file\?\)'
printf 'road a width 4\n1e999 1\n2 2\nend\n' >"$D/1e999.txt"; bad_roads 1e999.txt "line 2: x '1e999' is out of range"
printf 'road a width 1e999\n1 1\n2 2\nend\n' >"$D/width-1e999.txt"; bad_roads width-1e999.txt "line 1: width '1e999' is out of range"
{ echo 'road many width 2'; yes '1 1' | head -n 10000001; echo end; } >"$D/too-many-points.txt"
bad_roads too-many-points.txt 'line 10000002: more than 10000000 road points in total'
rm -f "$D/too-many-points.txt"
if truncate -s 700M "$D/sparse700m.txt" 2>/dev/null; then
    bad_roads sparse700m.txt 'file is larger than the [0-9]+-byte limit'
    rm -f "$D/sparse700m.txt"
fi
printf 'road a width 4\n1 1\n2 2x\nend\n' >"$D/garbage-y.txt"; bad_roads garbage-y.txt "line 3: y '2x' is not a number"
printf 'road a width 4\n@@ 1\nend\n' >"$D/garbage-x.txt"; bad_roads garbage-x.txt "line 2: x '@@' is not a number"
printf 'road a width 4 lanes 2\n1 1\n2 2\nend\n' >"$D/extra-token.txt"; bad_roads extra-token.txt "line 1: extra token 'lanes' after the width"
printf 'road a width 4\n1 1 1\n2 2\nend\n' >"$D/three-numbers.txt"; bad_roads three-numbers.txt "line 2: extra token '1' after the point"
printf 'road a width 4\n1 1\n2 2\nend now\n' >"$D/end-extra.txt"; bad_roads end-extra.txt "line 4: extra token 'now' after 'end'"
printf 'road a width nan\n1 1\n2 2\nend\n' >"$D/nan.txt"; bad_roads nan.txt "line 1: width 'nan' is not a number"
printf 'road a width 4\ninf 1\n2 2\nend\n' >"$D/inf.txt"; bad_roads inf.txt "line 2: x 'inf' is not a number"
printf 'road a width 4\n1 1\n2 -inf\nend\n' >"$D/minus-inf.txt"; bad_roads minus-inf.txt "line 3: y '-inf' is not a number"
printf 'road a width 4\n0x10 1\n2 2\nend\n' >"$D/hex.txt"; bad_roads hex.txt "line 2: x '0x10' is not a number"
printf 'road a width 2,5\n1 1\n2 2\nend\n' >"$D/comma-width.txt"
bad_roads comma-width.txt "line 1: width '2,5' is not a number \(use '.' as the decimal point and spaces between values\)"
printf 'road a width 4\n1,2\nend\n' >"$D/comma-pair.txt"
bad_roads comma-pair.txt "line 2: x '1,2' is not a number \(use '.' as the decimal point and spaces between values\)"
printf 'road a width -3\n1 1\n2 2\nend\n' >"$D/width-neg.txt"; bad_roads width-neg.txt "line 1: width '-3' must be > 0"
printf 'road a width -0\n1 1\n2 2\nend\n' >"$D/width-neg0.txt"; bad_roads width-neg0.txt "line 1: width '-0' must be > 0"
printf 'road a width 4\n1 1\nend\n' >"$D/one-point.txt"
bad_roads one-point.txt "line 3: road 'a' \(line 1\) has 1 point; a road needs at least 2"
printf 'road a width 4\n1 1\n1 1 # same point twice is still one place\n' >"$D/one-point-noend.txt"
bad_roads one-point-noend.txt "line 3: road 'a' \(started on line 1\) has no 'end'"
printf 'road a width 4\nend\n' >"$D/no-points.txt"; bad_roads no-points.txt "line 2: road 'a' \(line 1\) has 0 points; a road needs at least 2"
printf 'Road a width 4\n1 1\n2 2\nend\n' >"$D/keyword-case.txt"
bad_roads keyword-case.txt "line 1: unknown keyword 'Road' \(expected 'road', 'end' or a point 'X Y'\)"
printf 'lane a width 4\n' >"$D/keyword-lane.txt"; bad_roads keyword-lane.txt "line 1: unknown keyword 'lane' .*"
printf '5 5\n' >"$D/point-outside.txt"; bad_roads point-outside.txt "line 1: point '5' outside a road block .*"
printf 'road a width 4\n1 1\nroad b width 3\n2 2\n3 3\nend\nend\n' >"$D/nested.txt"
bad_roads nested.txt "line 3: 'road' inside road 'a' \(line 1\); missing 'end'\?"
printf 'road a width 4\n1 1\n2 2\nend\nroad b width 3\n5 5\n6 6\n' >"$D/unterminated-2nd.txt"
bad_roads unterminated-2nd.txt "line 7: road 'b' \(started on line 5\) has no 'end'"
printf 'end\n' >"$D/end-only.txt"; bad_roads end-only.txt "line 1: 'end' without a matching 'road'"
printf 'road a width 4\n1 1\n2 2\nend\nend\n' >"$D/end-twice.txt"; bad_roads end-twice.txt "line 5: 'end' without a matching 'road'"
junk junk.txt 3000 4; bad_roads junk.txt 'line [0-9]+: (invalid UTF-8 byte|NUL byte|control character) .*'
printf 'road a width 4\n1 1\0\n2 2\nend\n' >"$D/nul.txt"; bad_roads nul.txt 'line 2: NUL byte at column 4 \(binary file\?\)'
printf 'road a width 4\n1 1\033\n2 2\nend\n' >"$D/control.txt"; bad_roads control.txt 'line 2: control character 0x1b at column 4'
printf 'road \377 width 4\n1 1\n2 2\nend\n' >"$D/bad-utf8.txt"; bad_roads bad-utf8.txt 'line 1: invalid UTF-8 byte 0xff at column 6 .*'
{ printf 'road a width 4\n1 1\n'; mb2 ' '; printf '\n2 2\nend\n'; } >"$D/2mb-blank.txt"
bad_roads 2mb-blank.txt 'line 3: longer than 65536 bytes'
{ printf 'road a width 4\n1 1\n2 2\nend\n#'; mb2 '#'; } >"$D/2mb-comment.txt"
bad_roads 2mb-comment.txt 'line 5: longer than 65536 bytes'
{ printf 'road a width 4\n1 1\n'; mb2 7; printf ' 2\nend\n'; } >"$D/2mb-number.txt"
bad_roads 2mb-number.txt 'line 3: longer than 65536 bytes'

# --- unusual but valid input --------------------------------------------------------
# accept NAME ARGS... : exit 0, silent, OUT ($T/v.png) written
accept() {
    name=$1; shift
    rm -f "$T/v.png"
    timeout 20 "$RS" "$@" >/dev/null 2>"$T/stderr"; rc=$?
    if [ $rc -ne 0 ]; then bad "valid $name: exit $rc: $(head -c 300 "$T/stderr")"; return 1; fi
    if [ -s "$T/stderr" ]; then bad "valid $name: stderr '$(head -c 300 "$T/stderr")'"; return 1; fi
    if [ ! -s "$T/v.png" ]; then bad "valid $name: no output"; return 1; fi
    ok
}
# valid NAME REF DEM ROADS : accepted, and the image equals REF (or just accepted when REF is -);
# the roads are in metres on 1 m cells here: wide ones get the --cell-size warning
# (issue 28), so it is given
valid() {
    accept "$1" --quiet --cell-size 1 "$D/$3" "$D/$4" "$T/v.png" || return
    [ "$2" = - ] || { cmp -s "$T/v.png" "$2" && ok || bad "valid $1: image differs from $(basename "$2")"; }
}
# DEM variants of the reference that must read as the same samples
{ printf 'P2 # comment right after the magic\n# a comment line\n31#width\n  21 # height\n#\n255# maxval\n'
  awk 'BEGIN { for (i = 0; i < 651; i++) printf "%d%s", i % 97, (i % 31 == 30) ? " # row end\n" : (i % 7 == 3 ? "#x\n" : " ") }'
} >"$D/comments.pgm"
valid "comments between PGM tokens" "$T/ref.png" comments.pgm roads.txt
sed 's/$/\r/' "$D/dem.pgm" >"$D/crlf.pgm"; valid "CRLF PGM" "$T/ref.png" crlf.pgm roads.txt
printf '%s' "$(cat "$D/dem.pgm")" >"$D/nonl.pgm"; valid "PGM without a final newline" "$T/ref.png" nonl.pgm roads.txt
python3 - "$D/dem.pgm" "$D/p5.pgm" <<'PY' || bad "could not write the P5 twin"
import sys
t = open(sys.argv[1]).read().split()
open(sys.argv[2], 'wb').write(b'P5\n# binary twin\n31 21\n# comment before maxval\n255\n' + bytes(int(v) for v in t[4:]))
PY
valid "P5 with comments in the header" "$T/ref.png" p5.pgm roads.txt
{ printf 'P2\n31 21\n255\n'; mb2 ' ' ; awk 'BEGIN { for (i = 0; i < 651; i++) printf "%d ", i % 97 }'; } >"$D/2mb-blank.pgm"
valid "PGM with a 2 MB run of blanks" "$T/ref.png" 2mb-blank.pgm roads.txt
# road-file variants of the reference
sed 's/$/\r/' "$D/roads.txt" >"$D/crlf.txt"; valid "CRLF road file" "$T/ref.png" dem.pgm crlf.txt
printf '%s' "$(cat "$D/roads.txt")" >"$D/nonl.txt"; valid "road file without a final newline" "$T/ref.png" dem.pgm nonl.txt
{ printf '\357\273\277# BOM, tabs, comments\n'; sed 's/^/\t /; s/$/   # c/' "$D/roads.txt"; } >"$D/decorated.txt"
valid "BOM, indentation, trailing comments" "$T/ref.png" dem.pgm decorated.txt
printf '# only comments\n\n   \n\t# and blanks\n' >"$D/comments-only.txt"; valid "comment-only road file" "$T/terrain.png" dem.pgm comments-only.txt
awk '/^road|^end/ { print; next } { print; print; print }' "$D/roads.txt" >"$D/dups.txt"
valid "duplicate points" "$T/ref.png" dem.pgm dups.txt
printf 'road r width 6\n2 2\n28 20\n15 11\n28 20\nend\nroad side width 3\n0 15\n30 15\n0 15\nend\n' >"$D/reversal.txt"
valid "180-degree reversals (retracing a segment)" "$T/ref.png" dem.pgm reversal.txt
printf 'road a width 4\n2 10\n29 11\n2 12\nend\nroad b width 1\n15 1\n16 19\n15.1 1\nend\n' >"$D/acute.txt"
valid "very acute turns" - dem.pgm acute.txt
printf 'road a width 5\n-100 -100\n-50 -80\n-200 500\nend\nroad b width 3\n1e6 1e6\n1e6 -1e6\nend\n' >"$D/outside.txt"
# roads wholly outside the map: the same terrain-only image, and one warning line
# naming the road file and both extents (issue 17); --strict makes it an error
rm -f "$T/v.png"
"$RS" --quiet "$D/dem.pgm" "$D/outside.txt" "$T/v.png" 2>"$T/stderr" && cmp -s "$T/v.png" "$T/terrain.png" &&
    [ "$(wc -l <"$T/stderr")" -eq 1 ] &&
    grep -q "^roadsplat: warning: $D/outside.txt: no road touches the map: the roads span x -200..1000000, y -1000000..1000000; the map ($D/dem.pgm) spans x 0..30, y 0..20" "$T/stderr" &&
    ok || bad "roads wholly outside the map: $(head -c 300 "$T/stderr")"
rm -f "$T/v.png"
"$RS" --quiet --strict "$D/dem.pgm" "$D/outside.txt" "$T/v.png" 2>"$T/stderr"
[ $? -eq 1 ] && [ ! -e "$T/v.png" ] && [ "$(wc -l <"$T/stderr")" -eq 1 ] &&
    grep -q "^roadsplat: $D/outside.txt: no road touches the map" "$T/stderr" && ok || bad "--strict: roads outside the map"
printf 'road a width 5\n-50 10\n15 10\n15 500\nend\n' >"$D/partly.txt"; valid "a road partly outside the map" - dem.pgm partly.txt
printf 'road thin width 0.01\n2 2\n28 18\nend\nroad hair width 1e-9\n2 18\n28 2\nend\n' >"$D/thin.txt"
valid "very thin roads" - dem.pgm thin.txt
printf 'road wide width 1000\n15 10\n16 10\nend\nroad wider width 1e300\n0 0\n1 1\nend\n' >"$D/wide.txt"
valid "very wide roads" - dem.pgm wide.txt
awk 'BEGIN { print "road long width 2"; for (i = 0; i < 20000; i++) printf "%.6f %.6f\n", 15 + 12 * cos(i * 0.0031) * i / 20000, 10 + 8 * sin(i * 0.0031) * i / 20000; print "end" }' \
    >"$D/20000.txt"
valid "20 000 points in one road" - dem.pgm 20000.txt
printf 'road a width 4\n2 10\n28 10\nend\nroad b width 3\n15 10\n15 20\nend\nroad c width 2\n15 0\n15 20\nend\nroad d width 5\n5 2\n25 18\nend\n' \
    >"$D/junctions.txt"
valid "T and X junctions" - dem.pgm junctions.txt
printf 'road ring width 3\n5 5\n25 5\n25 15\n5 15\n5 5\nend\n' >"$D/loop.txt"; valid "a closed loop" - dem.pgm loop.txt
valid "mixed CRLF PGM + CRLF roads" "$T/ref.png" crlf.pgm crlf.txt
"$RS" mesh "$D/comments.pgm" "$T/c.obj" 2>"$T/stderr" && "$RS" mesh "$D/dem.pgm" "$T/r.obj" && cmp -s "$T/c.obj" "$T/r.obj" \
    && [ ! -s "$T/stderr" ] && ok || bad "mesh of a PGM with comments differs: $(cat "$T/stderr")"

# --- locale: a decimal-comma locale in the environment changes nothing ---------------
if LC_ALL=de_DE.UTF-8 locale decimal_point 2>/dev/null | grep -qx ','; then
    LC_ALL=de_DE.UTF-8 "$RS" --quiet --cell-size 1.0 --z-scale 1.0 "$D/dem.pgm" "$D/roads.txt" "$T/de.png" 2>"$T/stderr" \
        && cmp -s "$T/de.png" "$T/ref.png" && ok || bad "de_DE.UTF-8: the image differs: $(cat "$T/stderr")"
    printf 'road a width 2.5\n0.5 1.25\n30.5 20.75\nend\n' >"$D/frac.txt"
    "$RS" --quiet "$D/dem.pgm" "$D/frac.txt" "$T/c.png" &&
        LC_ALL=de_DE.UTF-8 "$RS" --quiet "$D/dem.pgm" "$D/frac.txt" "$T/de.png" && cmp -s "$T/c.png" "$T/de.png" && ok \
        || bad "de_DE.UTF-8: fractional road file reads differently"
    LC_ALL=de_DE.UTF-8 "$RS" --quiet --cell-size 2,5 "$D/dem.pgm" "$D/roads.txt" "$T/de.png" 2>"$T/stderr"
    [ $? -eq 1 ] && grep -q "cell-size: '2,5' is not a number" "$T/stderr" && ok || bad "de_DE.UTF-8 accepts --cell-size 2,5"
    LC_ALL=de_DE.UTF-8 "$RS" --quiet "$D/dem.pgm" "$D/comma-width.txt" "$T/de.png" 2>"$T/stderr"
    [ $? -eq 1 ] && ok || bad "de_DE.UTF-8 accepts width 2,5"
else
    echo "SKIP cli locale: no de_DE.UTF-8 locale (tests/run.sh builds one with localedef into LOCPATH)"
fi

# --- write errors ----------------------------------------------------------------------
# limited BYTES CMD... : CMD with a file-size limit and SIGXFSZ ignored, so
# write() fails with EFBIG exactly as on a full disk (works as root, no mount).
limited() {
    n=$1; shift
    if command -v prlimit >/dev/null 2>&1; then
        timeout 20 sh -c 'trap "" XFSZ; exec prlimit --fsize="$0" "$@"' "$n" "$@"
    else
        timeout 20 python3 -c 'import os, resource, signal, sys
signal.signal(signal.SIGXFSZ, signal.SIG_IGN); n = int(sys.argv[1])
resource.setrlimit(resource.RLIMIT_FSIZE, (n, n)); os.execv(sys.argv[2], sys.argv[2:])' "$n" "$@"
    fi
}
# write_fail NAME PATTERN OUTNAME LIMIT ARGS... : like refuse, under limited LIMIT
# (LIMIT 0: no limit). OUTNAME is the file that must keep its old bytes.
write_fail() {
    name=$1; pat=$2; out=$3; lim=$4; shift 4
    rm -rf "$O"; mkdir "$O"; cp "$T/old" "$O/$out"
    if [ "$lim" = 0 ]; then timeout 20 "$RS" "$@" >/dev/null 2>"$T/stderr"; else limited "$lim" "$RS" "$@" >/dev/null 2>"$T/stderr"; fi
    verdict "$name" "$pat" $? || return
    [ -n "$CLI_CATALOGUE" ] && printf '%s\t%s\n' "$name" "$(cat "$T/stderr")" >>"$CLI_CATALOGUE"
    cmp -s "$T/old" "$O/$out" || { bad "$name: the old $out changed"; return; }
    if ls -A "$O" | grep -q '^\.'; then bad "$name: left a temporary file: $(ls -A "$O")"; return; fi
    ok
}
if command -v prlimit >/dev/null 2>&1 || python3 -c 'import resource' 2>/dev/null; then
    # the reference PNG is ~20 kB; 2 kB do not hold it
    write_fail "full disk: PNG" "^roadsplat: $O/o.png: write failed: .*" o.png 2048 \
        --quiet "$D/dem.pgm" "$D/roads.txt" "$O/o.png"
    rm -rf "$O"; mkdir "$O"
    limited 2048 "$RS" --quiet "$D/dem.pgm" "$D/roads.txt" "$O/o.png" 2>/dev/null
    [ $? -eq 1 ] && [ -z "$(ls -A "$O")" ] && ok || bad "full disk, no old OUT: left $(ls -A "$O")"
    # a flat 3x3 DEM without roads: PNG ~130 bytes, weights 2 kB (texels 16), stats ~430 bytes
    write_fail "full disk: --weight-out" "^roadsplat: $O/w.pgm: write failed: File too large\$" w.pgm 1024 \
        --quiet --texels 16 --weight-out "$O/w.pgm" "$D/flat.pgm" "$D/none.txt" "$O/o.png"
    write_fail "full disk: --stats" "^roadsplat: $O/s.json: write failed: File too large\$" s.json 300 \
        --quiet --stats "$O/s.json" "$D/flat.pgm" "$D/none.txt" "$O/o.png"
    write_fail "full disk: mesh OBJ" "^roadsplat: $O/m.obj: write failed.*" m.obj 1024 mesh "$D/dem.pgm" "$O/m.obj"
    write_fail "full disk: mesh PLY" "^roadsplat: $O/m.ply: write failed.*" m.ply 1024 mesh "$D/dem.pgm" "$O/m.ply"
    write_fail "full disk: mesh --stats" "^roadsplat: $O/s.json: write failed.*" s.json 300 \
        mesh --stats "$O/s.json" "$D/flat.pgm" "$O/m.obj"
else
    echo "SKIP write errors (full disk): neither prlimit nor python3 resource"
fi
# unwritable targets: the parent is a regular file, a folder is missing, OUT is a folder or a FIFO
# (as root, permissions do not stop writes; cli_test.sh covers a read-only folder for non-root)
: >"$T/file"
write_fail "parent is a file: PNG" "^roadsplat: $T/file/o.png: cannot create a temporary file next to it: Not a directory\$" \
    o.png 0 --quiet "$D/dem.pgm" "$D/roads.txt" "$T/file/o.png"
write_fail "parent is a file: --weight-out" "^roadsplat: $T/file/w.pgm: .*Not a directory\$" \
    o.png 0 --quiet --weight-out "$T/file/w.pgm" "$D/dem.pgm" "$D/roads.txt" "$O/o.png"
write_fail "parent is a file: --stats" "^roadsplat: $T/file/s.json: .*Not a directory\$" \
    o.png 0 --quiet --stats "$T/file/s.json" "$D/flat.pgm" "$D/none.txt" "$O/o.png"
write_fail "parent is a file: mesh OBJ" "^roadsplat: $T/file/m.obj: .*Not a directory\$" m.obj 0 mesh "$D/dem.pgm" "$T/file/m.obj"
write_fail "parent is a file: mesh PLY" "^roadsplat: $T/file/m.ply: .*Not a directory\$" m.ply 0 mesh "$D/dem.pgm" "$T/file/m.ply"
write_fail "missing folder: mesh --stats" "^roadsplat: $T/nodir/s.json: .*No such file or directory\$" m.obj 0 \
    mesh --stats "$T/nodir/s.json" "$D/flat.pgm" "$O/x.obj"
write_fail "missing folder: --weight-out" "^roadsplat: $T/nodir/w.pgm: .*No such file or directory\$" o.png 0 \
    --quiet --weight-out "$T/nodir/w.pgm" "$D/dem.pgm" "$D/roads.txt" "$O/x.png"
rm -rf "$O"; mkdir -p "$O/dir.png"
"$RS" --quiet "$D/dem.pgm" "$D/roads.txt" "$O/dir.png" 2>"$T/stderr"
verdict "OUT is a folder" "^roadsplat: $O/dir.png: is a directory; the output must be a regular file\$" $? &&
    [ -d "$O/dir.png" ] && [ "$(ls -A "$O")" = dir.png ] && ok
if mkfifo "$O/fifo.png" 2>/dev/null; then
    timeout 20 "$RS" --quiet "$D/dem.pgm" "$D/roads.txt" "$O/fifo.png" 2>"$T/stderr"
    verdict "OUT is a FIFO" "^roadsplat: $O/fifo.png: exists and is not a regular file; the output must be a regular file\$" $? &&
        [ -p "$O/fifo.png" ] && ok
    mkfifo "$O/fifo.obj"
    timeout 20 "$RS" mesh "$D/dem.pgm" "$O/fifo.obj" 2>"$T/stderr"
    verdict "mesh OUT is a FIFO" "^roadsplat: $O/fifo.obj: exists and is not a regular file.*" $? && [ -p "$O/fifo.obj" ] && ok
fi

# --- issue 19: extreme scales, outputs naming inputs, signals, streams, limits -------
# mesh: every value reaching the float output is checked up front, naming the option
mode=fresh refuse "mesh --cell-size 1e-46" "^roadsplat: --cell-size: '1e-46' is below .*smallest cell size a float vertex holds\$" \
    m.obj mesh --cell-size 1e-46 --max-error 0 "$D/dem.pgm" "$O/m.obj"
mode=fresh refuse "mesh --cell-size 1e39" "^roadsplat: --cell-size: '1e\+39' is beyond the float range.*" \
    m.obj mesh --cell-size 1e39 "$D/dem.pgm" "$O/m.obj"
mode=fresh refuse "mesh --cell-size 2e37" "^roadsplat: --cell-size: '2e\+37' puts the map edge at 6e\+38 m, beyond the float range.*" \
    m.obj mesh --cell-size 2e37 "$D/dem.pgm" "$O/m.obj"
mode=fresh refuse "mesh --z-scale 1e40" "^roadsplat: --z-scale: '1e\+40' makes heights of .*beyond the float range.*" \
    m.ply mesh --z-scale 1e40 "$D/dem.pgm" "$O/m.ply"
mode=both refuse "mesh --skirt 1e39" "^roadsplat: --skirt: '1e\+39' is beyond the float range.*" \
    m.ply mesh --skirt 1e39 "$D/dem.pgm" "$O/m.ply"
# splat: the frame and the texture scale are range-checked up front (item 8: these were a
# NaN -> int64, a division by zero and texture overflows inside the library)
for v in 1e308 1e-310 5e-324; do
    mode=both refuse "splat --cell-size $v" "^roadsplat: --cell-size: '$v' must be in \\[1e-9, 1e9\\] metres\$" \
        o.png --quiet --cell-size $v "$D/dem.pgm" "$D/roads.txt" "$O/o.png"
done
mode=both refuse "splat --texture-scale 1e-308" "^roadsplat: --texture-scale: '1e-308' must be in \\[1e-6, 1e9\\] metres\$" \
    o.png --quiet --texture-scale 1e-308 "$D/dem.pgm" "$D/roads.txt" "$O/o.png"
mode=both refuse "splat --z-scale 1e40" "^roadsplat: --z-scale: '1e40' must be in \\[1e-12, 1e12\\] in magnitude\$" \
    o.png --quiet --z-scale 1e40 "$D/dem.pgm" "$D/roads.txt" "$O/o.png"
# an output naming an input or another output: refused before any work, inputs intact
same() { # NAME PATTERN FILE-THAT-MUST-NOT-CHANGE ARGS...
    name=$1; pat=$2; keep=$3; shift 3
    cp "$keep" "$T/keep"
    timeout 20 "$RS" "$@" >/dev/null 2>"$T/stderr"
    verdict "$name" "$pat" $? || return
    cmp -s "$T/keep" "$keep" || { bad "$name: $keep changed"; return; }
    if ls -A "$O" | grep -q '^\.'; then bad "$name: left a temporary file: $(ls -A "$O")"; return; fi
    ok
}
rm -rf "$O"; mkdir "$O"; cp "$D/dem.pgm" "$D/roads.txt" "$O/"; cp "$T/old" "$O/o.png"
same "OUT is the DEM" "^roadsplat: $O/dem.pgm: OUT is also the DEM .*refusing to overwrite an input\$" "$O/dem.pgm" \
    --quiet "$O/dem.pgm" "$O/roads.txt" "$O/dem.pgm"
same "OUT is the road file" "^roadsplat: $O/roads.txt: OUT is also the ROADS .*" "$O/roads.txt" \
    --quiet "$O/dem.pgm" "$O/roads.txt" "$O/roads.txt"
same "--weight-out is OUT" "^roadsplat: $O/o.png: given as both OUT and --weight-out; .*" "$O/o.png" \
    --quiet --weight-out "$O/o.png" "$O/dem.pgm" "$O/roads.txt" "$O/o.png"
same "--stats is OUT (not yet created, another spelling)" "^roadsplat: $O/./n.png: given as both OUT and --stats; .*" "$O/o.png" \
    --quiet --stats "$O/./n.png" "$O/dem.pgm" "$O/roads.txt" "$O/n.png"
same "--weight-out is the DEM" "^roadsplat: $O/dem.pgm: --weight-out is also the DEM .*" "$O/dem.pgm" \
    --quiet --weight-out "$O/dem.pgm" "$O/dem.pgm" "$O/roads.txt" "$O/o.png"
ln "$O/dem.pgm" "$O/hard.png"
same "OUT is a hard link of the DEM" "^roadsplat: $O/hard.png: OUT is also the DEM .*" "$O/dem.pgm" \
    --quiet "$O/dem.pgm" "$O/roads.txt" "$O/hard.png"
same "--terrain-texture is OUT" "^roadsplat: $O/o.png: OUT is also the --terrain-texture .*" "$O/o.png" \
    --quiet --terrain-texture "$O/o.png" "$O/dem.pgm" "$O/roads.txt" "$O/o.png"
same "mesh OUT is the DEM" "^roadsplat: $O/dem.pgm: OUT is also the DEM .*" "$O/dem.pgm" mesh "$O/dem.pgm" "$O/dem.pgm"
same "mesh --stats is OUT" "^roadsplat: $O/m.obj: given as both OUT and --stats; .*" "$O/dem.pgm" \
    mesh --stats "$O/m.obj" "$O/dem.pgm" "$O/m.obj"
# an empty side-output name fails before OUT is touched (it used to fail after OUT was replaced)
mode=both refuse "--weight-out=" "^roadsplat: --weight-out: the file name is empty\$" o.png \
    --quiet --weight-out= "$D/dem.pgm" "$D/roads.txt" "$O/o.png"
mode=both refuse "--stats ''" "^roadsplat: --stats: the file name is empty\$" o.png \
    --quiet --stats '' "$D/dem.pgm" "$D/roads.txt" "$O/o.png"
mode=both refuse "mesh --stats ''" "^roadsplat: --stats: the file name is empty\$" m.obj mesh --stats '' "$D/dem.pgm" "$O/m.obj"
mode=both refuse "OUT ends in /" "^roadsplat: $O/x/: names a folder; the output must be a file\$" x \
    --quiet "$D/dem.pgm" "$D/roads.txt" "$O/x/"
# a bad input leaves no temporary behind in an output folder that holds other files
rm -rf "$O"; mkdir "$O"; cp "$T/old" "$O/o.png"; : >"$O/.hidden"; ls -A "$O" >"$T/before"
"$RS" --quiet --weight-out "$O/w.pgm" --stats "$O/s.json" "$D/dem.pgm" "$D/trunc-point.txt" "$O/o.png" 2>/dev/null
[ $? -eq 1 ] && ls -A "$O" | cmp -s - "$T/before" && cmp -s "$T/old" "$O/o.png" && ok \
    || bad "bad road file: output folder changed: $(ls -A "$O")"
# signals: SIGTERM / SIGHUP stop the run, remove every temporary, exit 128 + signal
python3 - "$D/big.pgm" <<'PY' || bad "could not write big.pgm"
import sys
w, h = 700, 600
open(sys.argv[1], 'wb').write(b'P5\n%d %d\n255\n' % (w, h) + bytes((i * 7 + i // w) % 251 for i in range(w * h)))
PY
# (a signal this shell got ignored, as under nohup, stays ignored in the CLI
# by design: the run then completes, exit 0, with every output in place)
hup_ignored=$(python3 -c 'import signal; print(int(signal.getsignal(signal.SIGHUP) == signal.SIG_IGN))' 2>/dev/null || echo 0)
for sig in 15 1; do # SIGTERM, SIGHUP
    rm -rf "$O"; mkdir "$O"; cp "$T/old" "$O/o.png"
    "$RS" --quiet --texels 8 --weight-out "$O/w.pgm" --stats "$O/s.json" "$D/big.pgm" "$D/roads.txt" "$O/o.png" 2>/dev/null &
    pid=$!; n=0
    while [ "$(ls -A "$O" | grep -c '^\.rs-')" -lt 3 ] && [ $n -lt 200 ]; do sleep 0.05; n=$((n + 1)); done
    kill -$sig $pid; wait $pid; rc=$?
    if [ $sig -eq 1 ] && [ "$hup_ignored" = 1 ]; then
        [ $rc -eq 0 ] && [ "$(ls -A "$O" | tr '\n' ' ')" = "o.png s.json w.pgm " ] && ok \
            || bad "SIGHUP ignored on entry (nohup): exit $rc (expected 0, the run completes), left: $(ls -A "$O")"
        continue
    fi
    want=$((128 + sig))
    [ $rc -eq $want ] && [ "$(ls -A "$O")" = o.png ] && cmp -s "$T/old" "$O/o.png" && ok \
        || bad "SIG$sig: exit $rc (expected $want), left: $(ls -A "$O")"
done
rm -f "$D/big.pgm"
# a texture's declared size is checked against the limit before decoding (875 KB -> 4.5 GB before)
python3 - "$D" <<'PY' || bad "could not write the images"
import struct, sys, zlib
d = sys.argv[1]
def chunk(t, b): return struct.pack('>I', len(b)) + t + b + struct.pack('>I', zlib.crc32(t + b) & 0xffffffff)
def png(w, h, depth, colour, raw):
    return (b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, depth, colour, 0, 0, 0))
            + chunk(b'IDAT', zlib.compress(raw)) + chunk(b'IEND', b''))
open(d + '/tex-30000.png', 'wb').write(png(30000, 30000, 8, 2, b'\0' * 1000))
open(d + '/rgb.png', 'wb').write(png(31, 21, 8, 2, b''.join(b'\0' + bytes(93) for y in range(21))))
# 1-bit grey: heights 0/1, and its PGM twin
rows = [[(x * 3 + y) % 5 == 0 for x in range(16)] for y in range(6)]
raw = b''.join(b'\0' + bytes(sum(r[8 * k + b] << (7 - b) for b in range(8)) for k in range(2)) for r in rows)
open(d + '/bit1.png', 'wb').write(png(16, 6, 1, 0, raw))
open(d + '/bit1.pgm', 'w').write('P2\n16 6\n1\n' + '\n'.join(' '.join(str(int(v)) for v in r) for r in rows) + '\n')
PY
mode=fresh refuse "terrain texture declaring 30000x30000" \
    "^roadsplat: $D/tex-30000.png: 30000x30000 is too large for a texture \(at most 67108864 pixels\)\$" o.png \
    --quiet --terrain-texture "$D/tex-30000.png" "$D/dem.pgm" "$D/roads.txt" "$O/o.png"
bad_mesh rgb.png 'a DEM must have one channel \(or grey \+ alpha\), this image has 3'
"$RS" mesh --max-error 0 "$D/bit1.png" "$T/b1.obj" && "$RS" mesh --max-error 0 "$D/bit1.pgm" "$T/b1p.obj" && cmp -s "$T/b1.obj" "$T/b1p.obj" \
    && ok || bad "a 1-bit PNG does not mesh like its 0/1 PGM twin"
# a sparse 4 GiB PGM declaring 100000x100000: refused from its header (was 4.4 GB read first)
printf 'P5\n100000 100000\n255\n' >"$D/sparse4g.pgm"
if truncate -s 4G "$D/sparse4g.pgm" 2>/dev/null; then
    mode=fresh refuse "sparse 4 GiB PGM" "^roadsplat: $D/sparse4g.pgm: PGM line 3: DEM is 100000x100000; the limit is 16384 samples per side\$" \
        m.obj mesh "$D/sparse4g.pgm" "$O/m.obj"
fi
rm -f "$D/sparse4g.pgm"
# DEMs from a pipe are read once (PGM and PNG); a device is refused, not read forever
if mkfifo "$T/fifo.pgm" "$T/fifo.png" 2>/dev/null; then
    cat "$D/dem.pgm" >"$T/fifo.pgm" &
    timeout 20 "$RS" --quiet "$T/fifo.pgm" "$D/roads.txt" "$T/pipe.png" 2>"$T/stderr" && cmp -s "$T/pipe.png" "$T/ref.png" \
        && ok || bad "PGM DEM from a pipe: $(cat "$T/stderr")"
    cat "$D/good.png" >"$T/fifo.png" &
    timeout 20 "$RS" --quiet "$T/fifo.png" "$D/roads.txt" "$T/pipe.png" 2>"$T/stderr" && cmp -s "$T/pipe.png" "$T/ref.png" \
        && ok || bad "PNG DEM from a pipe: $(cat "$T/stderr")"
    rm -f "$T/fifo.pgm" "$T/fifo.png"
fi
mode=fresh refuse "DEM /dev/zero" "^roadsplat: /dev/zero: is a device; inputs must be regular files or pipes\$" o.png \
    --quiet /dev/zero "$D/roads.txt" "$O/o.png"
mode=fresh refuse "ROADS /dev/zero" "^roadsplat: /dev/zero: is a device; inputs must be regular files or pipes\$" o.png \
    --quiet "$D/dem.pgm" /dev/zero "$O/o.png"
# the longest names the file system takes work (the temporaries have fixed-length names)
long=$(printf '%0251d' 0 | tr 0 x)
rm -rf "$O"; mkdir "$O"
if : >"$O/$long.png" 2>/dev/null; then
    rm -f "$O/$long.png"
    "$RS" --quiet --weight-out "$O/$long.pgm" "$D/dem.pgm" "$D/roads.txt" "$O/$long.png" 2>"$T/stderr" \
        && cmp -s "$O/$long.png" "$T/ref.png" && [ -s "$O/$long.pgm" ] && [ "$(ls -A "$O" | wc -l)" -eq 2 ] && ok \
        || bad "255-byte OUT name: $(cat "$T/stderr")"
    "$RS" mesh --stats "$O/$long.jsn" "$D/dem.pgm" "$O/$long.obj" 2>"$T/stderr" && [ -s "$O/$long.obj" ] && ok \
        || bad "255-byte mesh OUT name: $(cat "$T/stderr")"
fi
# render: OUT and --stats are opened before the work and committed together
if ! "$RS" render --help 2>&1 | grep -q "no OSMesa support"; then
    mode=old refuse "render --stats in a missing folder" "^roadsplat: $T/nodir/s.json: cannot create a temporary file.*" o.png \
        render --quiet --size 64x48 --stats "$T/nodir/s.json" "$D/dem.pgm" "$D/roads.txt" "$O/o.png"
    mode=old refuse "render OUT is the DEM" "^roadsplat: $O/o.png: OUT is also the DEM .*" o.png \
        render --quiet --size 64x48 "$O/o.png" "$D/roads.txt" "$O/o.png"
    mode=fresh refuse "render --camera 1e300,1e300,1e300" "^roadsplat: --camera: '1e300,1e300,1e300' must lie within .*" o.png \
        render --quiet --size 64x48 --camera 1e300,1e300,1e300 "$D/dem.pgm" "$D/roads.txt" "$O/o.png"
fi

echo "cli_badinput: $pass passed, $fail failed"
[ $fail -eq 0 ]
