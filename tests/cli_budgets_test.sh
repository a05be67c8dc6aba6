#!/bin/sh
# CLI tests for the budgets of issue 26 (library side, docs/ROBUSTNESS.md):
# --max-field-work and --max-atlas-mb set the library's budgets; going over
# one is one line naming the budget and the option, exit 1, no output; a
# crowded road (20000 points on 100 m) splats with the defaults; bad values
# are refused. Usage: sh tests/cli_budgets_test.sh PATH/TO/roadsplat
BIN=${1:?usage: cli_budgets_test.sh ROADSPLAT}
. "$(dirname "$0")/cli_lib.sh"
ref_scene "$T"
awk 'BEGIN { print "road a width 6"; for (k = 0; k < 20000; k++) printf "%.6f 10\n", 2 + 26 * k / 19999; print "end" }' >"$T/crowd.txt"
awk 'BEGIN { print "road a width 8 class=primary"; for (k = 0; k < 20000; k++) printf "%.6f %.6f\n", 2 + 26 * k / 19999, 10 + (k % 2) * 0.01; print "end" }' >"$T/crowdp.txt"
run() { "$BIN" --quiet --cell-size 1 "$@"; }
check "crowded road, default budget" run --texels 2 "$T/dem.pgm" "$T/crowd.txt" "$T/c.png"
run --texels 2 --max-field-work 1000 "$T/dem.pgm" "$T/crowd.txt" "$T/w.png" 2>"$T/err"
check "over --max-field-work: exit 1" test $? = 1
check "one line" test "$(wc -l <"$T/err")" = 1
check "names the budget and the option" grep -q "rs_limits.max_field_work); --max-field-work N raises it" "$T/err"
check "no output" test ! -e "$T/w.png"
# the other commands that take the splat options
"$BIN" tiles --quiet --texels 2 --max-field-work 1000 "$T/dem.pgm" "$T/crowd.txt" "$T/tiles" 2>"$T/err"
check "tiles: exit 1 over the budget" test $? = 1
check "tiles: names the option" grep -q "; --max-field-work N raises it" "$T/err"
check "tiles: no output" test ! -e "$T/tiles/metadata.json"
"$BIN" render --texels 2 --max-field-work 1000 "$T/dem.pgm" "$T/crowd.txt" "$T/r.png" 2>"$T/err"
check "render: exit 1 over the budget" test $? = 1
check "render: names the option" grep -q "; --max-field-work N raises it" "$T/err"
check "render: no output" test ! -e "$T/r.png"
# an atlas whose types need 2 x ~1.4 MB of mip levels, over 2 MB; the same
# rectangle twice is shared and fits
printf 'P6\n512 512\n255\n' >"$T/atlas.ppm"
head -c $((512 * 512 * 3)) /dev/zero | tr '\0' '\377' >>"$T/atlas.ppm"
printf 'a 0 0 300 300 3 1\nb 1 0 300 300 3 1\n' >"$T/two.idx"
printf 'a 0 0 300 300 3 1\nb 0 0 300 300 3 1\n' >"$T/same.idx"
run --max-atlas-mb 2 --atlas "$T/atlas.ppm" --atlas-index "$T/two.idx" "$T/dem.pgm" "$T/roads.txt" "$T/a.png" 2>"$T/err"
check "over --max-atlas-mb: exit 1" test $? = 1
check "atlas: names line 2, the budget and the option" \
    grep -q "two.idx: atlas index line 2: type 'b'.*rs_limits.max_atlas_bytes); --max-atlas-mb N raises it" "$T/err"
check "atlas: no output" test ! -e "$T/a.png"
check "same rectangle twice fits 2 MB" run --max-atlas-mb 2 --atlas "$T/atlas.ppm" --atlas-index "$T/same.idx" \
    "$T/dem.pgm" "$T/roads.txt" "$T/s.png"
for v in 0 -1 1.5 abc 1e300; do
    run --max-field-work "$v" "$T/dem.pgm" "$T/roads.txt" "$T/v.png" 2>"$T/err" && bad "--max-field-work $v accepted"
    check "--max-field-work $v: message" grep -q "^roadsplat: --max-field-work" "$T/err"
done
run --max-atlas-mb 2000000 "$T/dem.pgm" "$T/roads.txt" "$T/v.png" 2>"$T/err" && bad "--max-atlas-mb 2000000 accepted"
check "--max-atlas-mb range" grep -q "must be a whole number in \[1, 1048576\]" "$T/err"
check "no output on bad values" test ! -e "$T/v.png"
# the line symbols' total: a dashed primary of 20000 points over 1 MB
run --texels 2 --max-linesym-mb 1 "$T/dem.pgm" "$T/crowdp.txt" "$T/l.png" 2>"$T/err"
check "over --max-linesym-mb: exit 1" test $? = 1
check "over --max-linesym-mb: names the budget and the option" grep -q "rs_limits.max_linesym_bytes.*; --max-linesym-mb N raises it" "$T/err"
check "over --max-linesym-mb: no output" test ! -e "$T/l.png"
check "the same within the default budget" run --texels 2 "$T/dem.pgm" "$T/crowdp.txt" "$T/l.png"
echo "cli_budgets: $pass passed, $fail failed"
[ "$fail" = 0 ]
