#!/bin/sh
# CLI tests for road markings (issue 14): --atlas/--atlas-index with the
# built-in atlas written as files (same bytes as the built-in one),
# --no-auto-markings, --no-markings, --stats counts, bad index lines and
# mark lines named. Usage: sh tests/cli_markings_test.sh PATH/TO/roadsplat
BIN=${1:?usage: cli_markings_test.sh ROADSPLAT}
. "$(dirname "$0")/cli_lib.sh"
GEN=$(dirname "$BIN")/atlasgen
cat >"$T/roads.txt" <<'R'
road main width 8 class=primary
0 20
20 20 crossing=zebra
60 20
end
road side width 6 class=residential turn:lanes=left|right
30 40
30 20
end
mark word_bus road=main s=45 t=-2
R
printf 'P2\n31 21\n255\n' >"$T/dem.pgm"
awk 'BEGIN { for (i = 0; i < 651; i++) printf "%d%s", 50, (i % 31 == 30) ? "\n" : " " }' >>"$T/dem.pgm"
run() { "$BIN" --quiet --cell-size 2 --texels 10 "$@"; }
check "default run" run --stats "$T/s.json" "$T/dem.pgm" "$T/roads.txt" "$T/a.png"
check "stats count explicit markings" grep -q '"markings": {"explicit": 1, "auto": [1-9]' "$T/s.json"
check "--no-auto-markings" run --no-auto-markings --stats "$T/s2.json" "$T/dem.pgm" "$T/roads.txt" "$T/b.png"
check "stats without automatic ones" grep -q '"markings": {"explicit": 1, "auto": 0,' "$T/s2.json"
check "--no-markings" run --no-markings "$T/dem.pgm" "$T/roads.txt" "$T/c.png"
check "markings change the image" sh -c "! cmp -s '$T/a.png' '$T/c.png'"
check "auto markings change the image" sh -c "! cmp -s '$T/a.png' '$T/b.png'"
if [ -x "$GEN" ]; then
    check "atlasgen writes the atlas files" "$GEN" "$T/atlas.c" "$T/atlas.png" "$T/atlas.txt"
    check "--atlas with the built-in atlas as files" run --atlas "$T/atlas.png" --atlas-index "$T/atlas.txt" \
        "$T/dem.pgm" "$T/roads.txt" "$T/d.png"
    check "same bytes as the built-in atlas" cmp -s "$T/a.png" "$T/d.png"
    printf 'arrow 0 0 8 8 5 1\nbad 0 0 8\n' >"$T/bad.txt"
    run --atlas "$T/atlas.png" --atlas-index "$T/bad.txt" "$T/dem.pgm" "$T/roads.txt" "$T/e.png" 2>"$T/err" && bad "bad index accepted"
    check "bad index line named" grep -q "bad.txt: atlas index line 2: expected NAME X Y W H LENGTH WIDTH" "$T/err"
    check "no output on error" test ! -e "$T/e.png"
else
    echo "SKIP: $GEN not built (make test builds it)"
fi
run --atlas "$T/atlas.png" "$T/dem.pgm" "$T/roads.txt" "$T/f.png" 2>"$T/err" && bad "--atlas alone accepted"
check "--atlas needs --atlas-index" grep -q "go together" "$T/err"
printf 'road a width 4\n0 5\n50 5\nend\nmark nosuch road=a s=3 t=0\n' >"$T/badmark.txt"
run "$T/dem.pgm" "$T/badmark.txt" "$T/g.png" 2>"$T/err" && bad "unknown mark type accepted"
check "unknown mark type named with its line" grep -q "line 5: mark: the atlas has no type 'nosuch'" "$T/err"
printf 'road a width 4\n0 5\n50 5\nend\nmark arrow_left road=b s=3 t=0\n' >"$T/badmark2.txt"
run "$T/dem.pgm" "$T/badmark2.txt" "$T/g.png" 2>"$T/err" && bad "mark on a missing road accepted"
check "missing road named with its line" grep -q "badmark2.txt: line 5: mark: no road named 'b'" "$T/err"
# --driving-side (issue 27): left-hand traffic moves the lanes' markings;
# the option is the default of the road attribute driving_side=
check "--driving-side left" run --driving-side left "$T/dem.pgm" "$T/roads.txt" "$T/l.png"
check "left-hand traffic differs" sh -c "! cmp -s '$T/a.png' '$T/l.png'"
check "--driving-side right is the default" run --driving-side=right "$T/dem.pgm" "$T/roads.txt" "$T/r.png"
check "right gives the default bytes" cmp -s "$T/a.png" "$T/r.png"
sed 's/^road \([^ ]*\) width \([^ ]*\) \(.*\)$/road \1 width \2 \3 driving_side=left/' "$T/roads.txt" >"$T/left.txt"
check "driving_side=left attribute" run "$T/dem.pgm" "$T/left.txt" "$T/la.png"
check "attribute and option agree" cmp -s "$T/l.png" "$T/la.png"
check "the attribute wins over the option" run --driving-side right "$T/dem.pgm" "$T/left.txt" "$T/lb.png"
check "... same bytes" cmp -s "$T/l.png" "$T/lb.png"
run --driving-side middle "$T/dem.pgm" "$T/roads.txt" "$T/m.png" 2>"$T/err" && bad "--driving-side middle accepted"
check "bad --driving-side named" grep -q "driving-side: 'middle' is not 'left' or 'right'" "$T/err"
check "no output on a bad option" test ! -e "$T/m.png"
echo "cli_markings: $pass passed, $fail failed"
[ "$fail" = 0 ]
