#!/bin/sh
# splat_identity.sh REF_BUILD NEW_BUILD WORKDIR: byte-compares two builds'
# splats - tests/tools/splat_dump.c's list (city, 1025^2 fractal, nodata,
# synthetic DEMs, every option group) and the CLI on the bundled example
# (docs/examples) with every option group. Prints one line per output that
# differs (with the count of differing bytes) and exits 1 if any does.
# Both builds need `make BUILD=... all BUILD/tools/splat_dump`.
set -e
A=$1; B=$2; W=$3
[ -n "$W" ] || { echo "usage: splat_identity.sh REF_BUILD NEW_BUILD WORKDIR" >&2; exit 2; }
mkdir -p "$W/a" "$W/b"
"$A/tools/splat_dump" "$W/a" >/dev/null
"$B/tools/splat_dump" "$W/b" >/dev/null
E=docs/examples
"$A/roadsplat" --quiet --cell-size 5 --z-scale 0.01 --texels 2 --png-level 0 $E/dem.pgm $E/roads.txt "$W/tex.png"
i=0
while read -r opts; do
    i=$((i + 1))
    for v in a b; do
        bin="$A/roadsplat"; [ $v = b ] && bin="$B/roadsplat"
        # shellcheck disable=SC2086
        "$bin" --quiet --cell-size 5 --z-scale 0.01 --png-level 0 --weight-out "$W/$v/cli$i.pgm" $opts \
            $E/dem.pgm $E/roads.txt "$W/$v/cli$i.png"
    done
done <<OPTS
--texels 8
--texels 4 --terrain-texture $W/tex.png
--texels 4 --road-texture $W/tex.png --texture-scale 7
--texels 4 --terrain-texture $W/tex.png --road-texture $W/tex.png
--texels 4 --jitter 7
--texels 4 --buffer dilate
--texels 4 --transition 0
--texels 4 --edges analytic
--texels 3 --edges analytic --terrain-texture $W/tex.png
--texels 5 --alpha-res 16 --threads 1
--texels 4 --window 33,17,301,257 --z-scale 1
--texels 1
--texels 2
--texels 2 --window 33,17,151,101 --z-scale 1
--texels 1 --window 7,5,101,80 --lighting
--texels 2 --edges analytic --window 1,2,203,101
OPTS
bad=0 n=0
for f in "$W"/a/*; do
    g="$W/b/$(basename "$f")"
    n=$((n + 1))
    if ! cmp -s "$f" "$g"; then
        echo "differs: $(basename "$f") ($(cmp -l "$f" "$g" 2>/dev/null | wc -l) bytes)"
        bad=1
    fi
done
echo "splat_identity: compared $n outputs"
exit $bad
