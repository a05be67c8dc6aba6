#!/bin/sh
# CLI tests of the PNG output and the modules (issue 18): --png-level (levels
# give the same pixels, bad values refused), the default level, --stats'
# startup, what `mesh` and `--version` load, and a missing image module.
# Usage: sh tests/cli_png_test.sh path/to/roadsplat
RS=${1:-build/roadsplat}
. "$(dirname "$0")/cli_lib.sh"
ref_scene "$T"
D="$T/dem.pgm"; R="$T/roads.txt"

expect_fail() { # name pattern args...: exit 1, one stderr line matching pattern
    name=$1; pat=$2; shift 2
    "$RS" "$@" >/dev/null 2>"$T/err"; rc=$?
    if [ $rc -ne 1 ]; then bad "$name: exit $rc"; return; fi
    if [ "$(wc -l <"$T/err")" -ne 1 ] || ! grep -q -- "$pat" "$T/err"; then bad "$name: $(cat "$T/err")"; return; fi
    ok
}
expect_fail "--png-level 13" "--png-level: '13' must be 0..12" --png-level 13 "$D" "$R" "$T/x.png"
expect_fail "--png-level abc" "--png-level" --png-level abc "$D" "$R" "$T/x.png"
expect_fail "--png-level -1" "--png-level" --png-level=-1 "$D" "$R" "$T/x.png"
[ ! -e "$T/x.png" ] && ok || bad "a refused run left OUT"

for L in 0 1 6 12; do
    check "--png-level $L" "$RS" --quiet --png-level "$L" --texels 4 "$D" "$R" "$T/l$L.png"
done
check "default level is 1" "$RS" --quiet --texels 4 "$D" "$R" "$T/def.png"
check "default = --png-level 1, byte for byte" cmp -s "$T/def.png" "$T/l1.png"
s0=$(wc -c <"$T/l0.png"); s1=$(wc -c <"$T/l1.png"); s12=$(wc -c <"$T/l12.png")
check "sizes shrink with the level ($s0 > $s1 >= $s12)" [ "$s0" -gt "$s1" -a "$s1" -ge "$s12" ]

TESTS=$(cd "$(dirname "$0")" && pwd)
if command -v python3 >/dev/null 2>&1; then
    # Decode (all five PNG filters) and compare the pixels of every level.
    cat > "$T/png.py" <<'PY'
import sys
from png_read import read
def pixels(path):
    w, h, ch, data = read(path)
    assert ch == 3, 'RGB expected (every pixel is opaque)'
    return (w, h, data)
ref = pixels(sys.argv[1])
for p in sys.argv[2:]:
    assert pixels(p) == ref, p
print('same')
PY
    check "every level decodes to the same pixels" sh -c "PYTHONPATH='$TESTS' python3 '$T/png.py' '$T/l0.png' '$T/l1.png' '$T/l6.png' '$T/l12.png' | grep -q same"
    # --rgba: the same colours with an alpha channel, every pixel opaque
    "$RS" --quiet --texels 4 --rgba "$D" "$R" "$T/rgba.png"
    check "--rgba writes RGBA: the default's RGB and alpha 255" sh -c "PYTHONPATH='$TESTS' python3 -c \"
from png_read import read
w, h, c, a = read('$T/l1.png')
w2, h2, c2, b = read('$T/rgba.png')
n = w * h
assert (c, c2, w, h) == (3, 4, w2, h2)
assert bytes(b[k] for k in range(4 * n) if k % 4 != 3) == bytes(a)
assert set(b[3::4]) == {255}
print('ok')
\" | grep -q ok"
fi

# Several bands (960x640 at --texels 32: five bands compressed apart and
# joined into one stream): the same bytes for every thread count, and the
# same bytes as the one-thread in-memory encoder writes for those pixels.
for L in 1 6; do
    for n in 1 2 3; do "$RS" --quiet --threads $n --texels 32 --png-level $L "$D" "$R" "$T/b$L-$n.png"; done
    check "bands, --png-level $L: --threads 1, 2, 3 give the same bytes" \
        sh -c "cmp -s '$T/b$L-1.png' '$T/b$L-2.png' && cmp -s '$T/b$L-1.png' '$T/b$L-3.png'"
done
if command -v python3 >/dev/null 2>&1; then
    check "bands: the joined streams decode to the same pixels" sh -c "PYTHONPATH='$TESTS' python3 '$T/png.py' '$T/b1-1.png' '$T/b6-1.png' | grep -q same"
fi
PNGT="$(dirname "$RS")/tests/test_png"
if [ -x "$PNGT" ]; then
    check "bands: the CLI writes what cli_png_encode writes" sh -c \
        "'$PNGT' --time-level 1 '$T/b1-1.png' '$T/re.png' 1 >/dev/null && cmp -s '$T/b1-1.png' '$T/re.png'"
else
    echo "SKIP: $PNGT not built"
fi

# A full disk in the middle of the bands (file size limit, SIGXFSZ ignored):
# one error line, exit 1, no OUT and no temporary left.
if command -v prlimit >/dev/null 2>&1; then
    mkdir "$T/full"
    sh -c 'trap "" XFSZ; exec prlimit --fsize=300000 "$@"' sh "$RS" --quiet --threads 2 --texels 32 "$D" "$R" "$T/full/o.png" \
        2>"$T/err"
    rc=$?
    check "bands: a full disk mid-way fails cleanly (exit $rc: $(cat "$T/err"))" sh -c \
        "[ $rc = 1 ] && [ -z \"\$(ls -A '$T/full')\" ] && [ \$(wc -l < '$T/err') = 1 ] && grep -q 'o.png: write failed' '$T/err'"
else
    echo "SKIP: no prlimit"
fi

check "stats: timings_ms.startup" sh -c "'$RS' --quiet --stats '$T/s.json' '$D' '$R' '$T/s.png' && grep -Eq '\"startup\": [0-9]+\\.[0-9]+' '$T/s.json'"

# What gets loaded: LD_DEBUG_OUTPUT, since the CLI redirects fd 2 while OpenImageIO reads.
loaded() { rm -f "$T"/ld.*; LD_DEBUG=libs LD_DEBUG_OUTPUT="$T/ld" "$@" >/dev/null 2>&1; cat "$T"/ld.* 2>/dev/null | grep 'calling init:'; }
if loaded "$RS" --version | grep -q .; then
    n=$(loaded "$RS" --version | grep -Ec 'OpenImageIO|OSMesa|LLVM')
    check "--version loads neither OpenImageIO nor OSMesa ($n)" [ "$n" = 0 ]
    check "mesh of a PGM runs" sh -c "'$RS' mesh '$D' '$T/m.obj' >/dev/null"
    n=$(loaded "$RS" mesh "$D" "$T/m.obj" | grep -Ec 'OpenImageIO|OSMesa|LLVM')
    check "mesh of a PGM loads neither OpenImageIO nor OSMesa ($n)" [ "$n" = 0 ]
    n=$(loaded "$RS" --quiet "$T/l1.png" "$R" "$T/p.png" | grep -c 'roadsplat-image.so')
    check "a PNG DEM loads the image module" [ "$n" = 1 ]
else
    echo "SKIP: LD_DEBUG output unavailable"
fi

# The executable alone, without its modules beside it.
mkdir "$T/alone" && cp "$RS" "$T/alone/roadsplat"
check "alone: --version" sh -c "'$T/alone/roadsplat' --version >/dev/null"
check "alone: a PGM DEM" "$T/alone/roadsplat" --quiet "$D" "$R" "$T/a.png"
"$T/alone/roadsplat" --quiet "$T/l1.png" "$R" "$T/b.png" 2>"$T/err"; rc=$?
if [ $rc = 0 ]; then
    echo "SKIP: an installed roadsplat-image.so was found; the missing-module message is not tested"
else
    check "alone: a PNG DEM fails with one line naming the module" sh -c \
        "[ $rc = 1 ] && [ \$(wc -l < '$T/err') = 1 ] && grep -q 'l1.png: .*roadsplat-image.so' '$T/err'"
fi
echo "cli_png: $pass passed, $fail failed"
[ "$fail" = 0 ]
