#!/bin/sh
# Writes the large, trivially generated crasher inputs into OUTDIR/<target>/
# (tests/run.sh replays OUTDIR/<target> after tests/crashers/<target>): they
# used to be stored in git (6.6 MB). Byte-identical to the stored files they
# replace. Usage: sh tests/gen_crashers.sh OUTDIR
set -e
OUT=${1:?usage: gen_crashers.sh OUTDIR}
mkdir -p "$OUT/roads" "$OUT/pgm"
# 2 MiB of digits on one line: a number token far past any limit.
[ -f "$OUT/roads/line_2mb.txt" ] || {
    { printf 'road a width 1\n'; awk 'BEGIN { s = "1"; for (i = 0; i < 21; i++) s = s s; printf "%s", s }'
      printf ' 0\n2 2\nend\n'; } > "$OUT/roads/line_2mb.txt.tmp" && mv "$OUT/roads/line_2mb.txt.tmp" "$OUT/roads/line_2mb.txt"; }
# 50001 two-point roads.
[ -f "$OUT/roads/many_roads.txt" ] || {
    awk 'BEGIN { for (i = 0; i <= 50000; i++) printf "road r%d width 1\n0 0\n1 1\nend\n", i }' \
        > "$OUT/roads/many_roads.txt.tmp" && mv "$OUT/roads/many_roads.txt.tmp" "$OUT/roads/many_roads.txt"; }
# One road of 100001 points (over the default point limit).
[ -f "$OUT/roads/points_over_limit.txt" ] || {
    awk 'BEGIN { printf "road a width 1\n"; for (i = 0; i <= 100000; i++) printf "%d 0\n", i; printf "end\n" }' \
        > "$OUT/roads/points_over_limit.txt.tmp" && mv "$OUT/roads/points_over_limit.txt.tmp" "$OUT/roads/points_over_limit.txt"; }
# A P2 header with a 2 MiB comment.
[ -f "$OUT/pgm/p2_2mb_comment.pgm" ] || {
    { printf 'P2 2 2 10\n#'; awk 'BEGIN { s = "x"; for (i = 0; i < 21; i++) s = s s; printf "%s", s }'
      printf '\n1 2 3 4\n'; } > "$OUT/pgm/p2_2mb_comment.pgm.tmp" && mv "$OUT/pgm/p2_2mb_comment.pgm.tmp" "$OUT/pgm/p2_2mb_comment.pgm"; }
exit 0
