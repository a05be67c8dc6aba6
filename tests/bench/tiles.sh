#!/bin/sh
# `make bench`: the tile pyramid (docs/tiles.md). A 2049 x 2049-cell DEM at
# 8 texels (16392 x 16392 pixels, 4225 finest tiles of 256) with a small
# city of 12 roads in one corner. Reports finest tiles per second per core
# (--threads 1), the sparse saving (default against --dense: files, bytes,
# time) and 1 against 2 processes (--shard 0/2 and 1/2 side by side, each
# --threads 1, then --from-children; the same tiles). Writes OUT/tiles.md.
set -e
OUT=${1:-build/bench}
B=${BUILD:-build}
BIN=$B/roadsplat
W=$(mktemp -d); trap 'rm -rf "$W"' EXIT
python3 -c "
import sys
W = 2050
sys.stdout.buffer.write(b'P5\n%d %d\n255\n' % (W, W) + bytes(((i % W) // 16 + (i // W) // 24) % 200 for i in range(W * W)))" >"$W/dem.pgm"
awk 'BEGIN { for (i = 0; i < 6; i++) { printf "road h%d width 8\n20 %d\n300 %d\nend\nroad v%d width 8\n%d 20\n%d 300\nend\n", i, 30 + 50 * i, 30 + 50 * i, i, 30 + 50 * i, 30 + 50 * i } }' >"$W/city.txt"
O="--quiet --texels 8 --threads 1"
now() { date +%s.%N; }
best() { # command...: the fastest of 3 runs, seconds
    b=
    for k in 1 2 3; do
        rm -rf "$W/o" "$W/o2"; t0=$(now); "$@"; t=$(echo "$(now) - $t0" | bc -l)
        if [ -z "$b" ] || [ "$(echo "$t < $b" | bc -l)" = 1 ]; then b=$t; fi
    done
    printf %.2f "$b"
}
sparse=$(best "$BIN" tiles $O "$W/dem.pgm" "$W/city.txt" "$W/o")
sp_files=$(find "$W/o" -name '*.png' | wc -l); sp_bytes=$(du -sk "$W/o" | cut -f1)
dense=$(best "$BIN" tiles $O --dense "$W/dem.pgm" "$W/city.txt" "$W/o")
de_files=$(find "$W/o" -name '*.png' | wc -l); de_bytes=$(du -sk "$W/o" | cut -f1)
two() {
    "$BIN" tiles $O --shard 0/2 "$W/dem.pgm" "$W/city.txt" "$W/o" & p=$!
    "$BIN" tiles $O --shard 1/2 "$W/dem.pgm" "$W/city.txt" "$W/o"; wait $p
    "$BIN" tiles $O --from-children "$W/dem.pgm" "$W/city.txt" "$W/o"
}
two=$(best two)
cores=$(nproc)
finest=4225
{
    echo "## Tile pyramid (roadsplat tiles)"
    echo
    echo "\`tests/bench/tiles.sh\`: 2049 x 2049-cell DEM at 8 texels (16392 x 16392 pixels, $finest finest"
    echo "tiles of 256, levels 0..7, complete up to level 4), a city of 12 roads in one corner; fastest of 3 runs,"
    echo "\`--threads 1\`; $cores cores."
    echo
    echo "| run | seconds | finest tiles per second per core | files | KiB on disk |"
    echo "|---|---|---|---|---|"
    echo "| sparse (default) | $sparse | $(echo "$finest / $sparse" | bc -l | xargs printf %.0f) | $sp_files | $sp_bytes |"
    echo "| --dense | $dense | $(echo "$finest / $dense" | bc -l | xargs printf %.0f) | $de_files | $de_bytes |"
    echo "| 2 processes (--shard 0/2, 1/2 together) + --from-children | $two | $(echo "$finest / $two / 2" | bc -l | xargs printf %.0f) | | |"
    echo
    echo "Sparse saving: $(echo "$de_files / $sp_files" | bc -l | xargs printf %.1f)x fewer files,"
    echo "$(echo "$de_bytes / $sp_bytes" | bc -l | xargs printf %.1f)x fewer bytes, $(echo "$dense / $sparse" | bc -l | xargs printf %.2f)x the speed"
    echo "(every finest tile is still rendered in memory for its parent: the saving is encoding and writing)."
    echo "2 processes against 1: $(echo "$sparse / $two" | bc -l | xargs printf %.2f)x (ideal 2.00 on 2 free cores; the merge step is included)."
} >"$OUT/tiles.md"
cat "$OUT/tiles.md"
