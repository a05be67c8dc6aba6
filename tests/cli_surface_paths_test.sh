#!/bin/sh
# The AVX-512 paths of lib/splat/surface.c (tints, shades, bilinear step)
# and lib/splat/composite.c, and the AVX2 paths (composite, bilinear
# terrain, tints, shades where the CPU has AVX2 but not AVX-512; the
# texture sampler on any AVX2 CPU), give the bytes of the portable ones:
# build/tools/splat_dump (the library as built) against splat_dump_portable
# (those two files built with -DRS_NO_AVX512), every output of tests/tools/splat_dump.c (city, nodata,
# synthetic and fractal DEMs at 1 to 5 texels, every option group and tint
# mode). Usage: cli_surface_paths_test.sh BUILD/roadsplat (as tests/run.sh
# calls the CLI tests; the tools are found beside it).
B=$(dirname "$1")
pass=0 fail=0
for t in splat_dump splat_dump_portable; do
    [ -x "$B/tools/$t" ] || { echo "missing $B/tools/$t (make test builds it)"; echo "0 passed, 1 failed"; exit 1; }
done
if ! grep -qw avx512f /proc/cpuinfo 2>/dev/null || ! grep -qw avx512dq /proc/cpuinfo || ! grep -qw avx512vl /proc/cpuinfo; then
    if grep -qw avx2 /proc/cpuinfo 2>/dev/null; then
        echo "note: this CPU has AVX2 but no AVX-512 (F, DQ, VL): the AVX2 paths against the portable ones"
    else
        echo "SKIP: this CPU has neither AVX-512 (F, DQ, VL) nor AVX2: both builds take the portable paths"
    fi
fi
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
mkdir -p "$W/a" "$W/b"
"$B/tools/splat_dump" "$W/a" >/dev/null || { echo "splat_dump failed"; fail=$((fail + 1)); }
"$B/tools/splat_dump_portable" "$W/b" >/dev/null || { echo "splat_dump_portable failed"; fail=$((fail + 1)); }
n=0
for f in "$W"/a/*; do
    g="$W/b/$(basename "$f")"
    n=$((n + 1))
    if cmp -s "$f" "$g"; then pass=$((pass + 1)); else
        echo "differs: $(basename "$f") ($(cmp -l "$f" "$g" 2>/dev/null | wc -l) bytes)"
        fail=$((fail + 1))
    fi
done
[ "$n" -ge 100 ] || { echo "only $n outputs compared"; fail=$((fail + 1)); }
echo "$pass passed, $fail failed"
[ "$fail" = 0 ]
