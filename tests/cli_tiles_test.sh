#!/bin/sh
# CLI tests for `roadsplat tiles` (docs/tiles.md). Usage: sh tests/cli_tiles_test.sh PATH/TO/roadsplat
# Prints "N passed, N failed"; exits non-zero on any failure.
BIN=${1:?usage: cli_tiles_test.sh ROADSPLAT}
D=$(cd "$(dirname "$0")" && pwd)
. "$D/cli_lib.sh"
PY="python3 $D/tiles_check.py"
ref_scene "$T"
O="--texels 40"   # 1200 x 800 pixels: 5 x 4 finest tiles of 256, levels 0..3
same_tree() { diff -r -x .tiles-log "$1" "$2" >/dev/null; }

# 1. the dense pyramid: finest tiles are windows of the whole image, parents box filters
check "dense run exits 0" "$BIN" tiles --quiet --dense $O "$T/dem.pgm" "$T/roads.txt" "$T/dense"
check "dense: manifest hashes = files" $PY manifest "$T/dense"
check "dense: levels 0..3" grep -q '"levels": {"min": 0, "max": 3, "dense_max": 3}' "$T/dense/tiles.json"
for xy in 0,0 1,0 3,1 2,2; do
    x=${xy%,*} y=${xy#*,}
    "$BIN" --quiet $O --window $((x * 256)),$((y * 256)),256,256 "$T/dem.pgm" "$T/roads.txt" "$T/w$x$y.png"
    check "finest tile $x,$y: the window PNG's pixels" $PY same "$T/w$x$y.png" "$T/dense/3/$x/$y.png"
done
"$BIN" --quiet $O --window 1024,768,176,32 "$T/dem.pgm" "$T/roads.txt" "$T/wedge.png"
check "edge tile 4,3 = window + transparent padding" $PY window "$T/dense/3/4/3.png" "$T/wedge.png"
check "parent 2/0/0 = box filter of its children" $PY parent "$T/dense" 2 0 0
check "parent 2/2/1 (edge) = box filter of its children" $PY parent "$T/dense" 2 2 1
check "parent 0/0/0 = box filter of its children" $PY parent "$T/dense" 0 0 0
"$BIN" tiles --quiet --dense --threads 1 $O "$T/dem.pgm" "$T/roads.txt" "$T/dense1"
check "1 thread = all threads (tiles and manifest)" same_tree "$T/dense" "$T/dense1"

# 2. sparse: finer than a DEM cell, only tiles with a road
check "sparse run exits 0" "$BIN" tiles --quiet $O "$T/dem.pgm" "$T/roads.txt" "$T/sp"
"$BIN" --quiet $O --weight-out "$T/wt.pgm" "$T/dem.pgm" "$T/roads.txt" "$T/whole.png"
check "sparse: written iff dense level or holds a road" $PY sparse "$T/sp" "$T/wt.pgm"
check "sparse: manifest hashes = files" $PY manifest "$T/sp"
check "sparse tiles = the dense run's" sh -c "cd '$T/sp' && for f in \$(find . -name '*.png'); do cmp -s \$f '$T/dense/'\$f || exit 1; done"
check "sparse: the manifest states the rule" grep -q 'written only when it holds a road' "$T/sp/tiles.json"
"$BIN" tiles --quiet --scheme tms $O "$T/dem.pgm" "$T/roads.txt" "$T/tms"
check "tms flips y" cmp -s "$T/tms/3/4/4.png" "$T/sp/3/4/3.png"

# 3. shards: 4 shards then --from-children = one run, byte for byte
for i in 0 1 2 3; do "$BIN" tiles --quiet --shard $i/4 $O "$T/dem.pgm" "$T/roads.txt" "$T/sh" || bad "shard $i"; done
check "shards write no manifest" test ! -e "$T/sh/tiles.json"
check "--from-children exits 0" "$BIN" tiles --quiet --from-children $O "$T/dem.pgm" "$T/roads.txt" "$T/sh"
check "4 shards + merge = single run (tiles and tiles.json)" same_tree "$T/sh" "$T/sp"
if command -v parallel >/dev/null 2>&1; then
    check "GNU parallel recipe (4 shards) = single run" sh -c "ROADSPLAT='$BIN' sh '$D/../docs/examples/tiles_parallel.sh' 4 '$T/dem.pgm' '$T/roads.txt' '$T/par' $O && diff -r -x .tiles-log '$T/par' '$T/sp' >/dev/null"
else
    echo "SKIP: GNU parallel not installed (make deps): the parallel recipe is not run"
fi
check "Slurm script passes bash -n" bash -n "$D/../docs/examples/tiles_slurm.sh"
check "Slurm array tasks + merge = single run" sh -c "for i in 0 1 2; do SLURM_ARRAY_TASK_ID=\$i SLURM_ARRAY_TASK_COUNT=3 ROADSPLAT='$BIN' DEM='$T/dem.pgm' ROADS='$T/roads.txt' OUT='$T/slurm' OPTS='$O' bash '$D/../docs/examples/tiles_slurm.sh' || exit 1; done;
  ROADSPLAT='$BIN' DEM='$T/dem.pgm' ROADS='$T/roads.txt' OUT='$T/slurm' OPTS='$O' bash '$D/../docs/examples/tiles_slurm.sh' merge && diff -r -x .tiles-log '$T/slurm' '$T/sp' >/dev/null"

# 4. resume: a shard killed part-way, a tile lost, one changed, a log line cut
"$BIN" tiles --quiet --shard 0/2 $O "$T/dem.pgm" "$T/roads.txt" "$T/rs"
log="$T/rs/.tiles-log/shard-0-of-2.log"
head -n 4 "$log" >"$T/l" && printf '3 1 1 r 12ab' >>"$T/l" && mv "$T/l" "$log"
rm -f "$T/rs/3/0/1.png"; printf x >>"$T/rs/3/0/0.png"
check "resumed shard exits 0" "$BIN" tiles --quiet --resume --shard 0/2 $O "$T/dem.pgm" "$T/roads.txt" "$T/rs"
check "resume kept the finished tiles" sh -c "'$BIN' tiles --resume --shard 0/2 $O '$T/dem.pgm' '$T/roads.txt' '$T/rs' 2>&1 | grep -q ' 0 rendered, 0 written'"
# a real kill at some moment, then --resume: the same tiles whatever the moment
( "$BIN" tiles --quiet --shard 1/2 $O "$T/dem.pgm" "$T/roads.txt" "$T/rs" & p=$!; sleep 0.2; kill -9 $p 2>/dev/null; wait $p ) 2>/dev/null
check "killed shard resumed" "$BIN" tiles --quiet --resume --shard 1/2 $O "$T/dem.pgm" "$T/roads.txt" "$T/rs"
check "no temporaries left" sh -c "! find '$T/rs' -name '.rs-*' -o -name '*.part' | grep -q ."
check "merge after resume = single run" sh -c "'$BIN' tiles --quiet --from-children $O '$T/dem.pgm' '$T/roads.txt' '$T/rs' && diff -r -x .tiles-log '$T/rs' '$T/sp' >/dev/null"
mkdir -p "$T/half" && "$BIN" tiles --quiet --shard 0/2 $O "$T/dem.pgm" "$T/roads.txt" "$T/half"
check "--from-children with a shard missing fails naming a tile" sh -c "! '$BIN' tiles --quiet --from-children $O '$T/dem.pgm' '$T/roads.txt' '$T/half' 2>'$T/e' && grep -q 'run its shard' '$T/e' && test ! -e '$T/half/tiles.json'"
check "--resume with other options refused" sh -c "! '$BIN' tiles --quiet --resume --texels 20 '$T/dem.pgm' '$T/roads.txt' '$T/sp' 2>'$T/e' && grep -q 'other inputs or options' '$T/e'"

# 5. MBTiles
if "$BIN" tiles --quiet --format mbtiles $O "$T/dem.pgm" "$T/roads.txt" "$T/p.mbtiles" 2>"$T/e"; then
    check "MBTiles rows (TMS) = the folder's tiles" $PY mbtiles "$T/p.mbtiles" "$T/sp"
    check "mbtiles with --shard refused" sh -c "! '$BIN' tiles --format mbtiles --shard 0/2 '$T/dem.pgm' '$T/roads.txt' '$T/q.mbtiles' 2>/dev/null"
elif grep -q 'SQLite' "$T/e"; then
    echo "SKIP: MBTiles: $(cat "$T/e")"
    check "without SQLite: one clear line, no file" sh -c "test \$(wc -l <'$T/e') = 1 && test ! -e '$T/p.mbtiles'"
else
    bad "mbtiles: $(cat "$T/e")"
fi

# 6. bad arguments: exit 1 and one line each
: >"$T/file"
for args in "--tile-size 300" "--tile-size x" "--scheme foo" "--format jpg" "--shard 4/4" "--shard 1" "--shard a/b" \
    "--bogus" "--from-children --shard 0/2" "--format mbtiles --resume" "--texels 0"; do
    "$BIN" tiles $args "$T/dem.pgm" "$T/roads.txt" "$T/bad" 2>"$T/e"; rc=$?
    check "tiles $args: exit 1, one line" sh -c "test $rc = 1 && test \$(wc -l <'$T/e') = 1"
done
"$BIN" tiles "$T/dem.pgm" "$T/roads.txt" 2>"$T/e"; rc=$?
check "missing OUTDIR: exit 1, one line" sh -c "test $rc = 1 && test \$(wc -l <'$T/e') = 1"
"$BIN" tiles "$T/dem.pgm" "$T/roads.txt" "$T/file" 2>"$T/e"; rc=$?
check "OUTDIR a file: exit 1, one line naming it" sh -c "test $rc = 1 && test \$(wc -l <'$T/e') = 1 && grep -q 'not a folder' '$T/e'"
"$BIN" tiles "$T/nope.pgm" "$T/roads.txt" "$T/bad2" 2>"$T/e"; rc=$?
check "missing DEM: exit 1, one line naming it" sh -c "test $rc = 1 && test \$(wc -l <'$T/e') = 1 && grep -q nope.pgm '$T/e'"

# 7. the normal map as a second layer ({y}_n.png) and --halo
N="$O --normals"
check "dense --normals run exits 0" "$BIN" tiles --quiet --dense $N "$T/dem.pgm" "$T/roads.txt" "$T/nd"
check "--normals: manifest hashes = files (both layers)" $PY manifest "$T/nd"
check "--normals: the colour tiles are unchanged" sh -c "cd '$T/dense' && for f in \$(find . -name '*.png'); do cmp -s \$f '$T/nd/'\$f || exit 1; done"
for xy in 1,0 2,2; do
    x=${xy%,*} y=${xy#*,}
    "$BIN" --quiet $O --window $((x * 256)),$((y * 256)),256,256 --normal-out "$T/n$x$y.png" "$T/dem.pgm" "$T/roads.txt" "$T/w.png"
    check "finest normal tile $x,$y: the pixels of --normal-out of its window" $PY same "$T/n$x$y.png" "$T/nd/3/$x/${y}_n.png"
done
"$BIN" --quiet $O --window 1024,768,176,32 --normal-out "$T/nedge.png" "$T/dem.pgm" "$T/roads.txt" "$T/w.png"
check "edge normal tile 4,3 = --normal-out window + alpha 0 beyond" $PY normal_window "$T/nd/3/4/3_n.png" "$T/nedge.png"
"$BIN" tiles --quiet --dense $N --threads 1 "$T/dem.pgm" "$T/roads.txt" "$T/nd1"
check "--normals: 1 thread = all threads (tiles and manifest)" same_tree "$T/nd" "$T/nd1"
check "normal parent 2/0/0 = renormalised mean of its children" $PY parent "$T/nd" 2 0 0 n
check "normal parent 2/2/1 (edge) = renormalised mean of its children" $PY parent "$T/nd" 2 2 1 n
check "normal parent 0/0/0 = renormalised mean of its children" $PY parent "$T/nd" 0 0 0 n
"$BIN" tiles --quiet --dense $N --normal-convention dx --normal-strength 3 "$T/dem.pgm" "$T/roads.txt" "$T/ndx"
"$BIN" --quiet $O --window 256,0,256,256 --normal-out "$T/ndx.png" --normal-convention dx --normal-strength 3 "$T/dem.pgm" "$T/roads.txt" "$T/w.png"
check "--normal-convention dx --normal-strength 3: finest tile = --normal-out" $PY same "$T/ndx.png" "$T/ndx/3/1/0_n.png"
H="$N --halo 5"
check "sparse --normals --halo 5 run exits 0" "$BIN" tiles --quiet $H "$T/dem.pgm" "$T/roads.txt" "$T/ha"
"$BIN" --quiet $O --window 251,251,266,266 --normal-out "$T/hn.png" "$T/dem.pgm" "$T/roads.txt" "$T/hc.png"
check "halo: finest tile 1,1 = the 266^2 window (colour)" $PY same "$T/hc.png" "$T/ha/3/1/1.png"
check "halo: finest tile 1,1 = the 266^2 window (normal)" $PY same "$T/hn.png" "$T/ha/3/1/1_n.png"
check "halo: every halo pixel = the neighbour tile's pixel, all levels, both layers" $PY halo "$T/ha"
check "halo: parent 1/0/0 = box filter of its children's cores" $PY parent "$T/ha" 1 0 0
check "halo: normal parent 2/0/0 = mean of its children's cores" $PY parent "$T/ha" 2 0 0 n
check "halo: manifest hashes = files, halo stated" sh -c "$PY manifest '$T/ha' && grep -q '\"halo\": 5' '$T/ha/tiles.json'"
for i in 0 1 2; do "$BIN" tiles --quiet --shard $i/3 $H "$T/dem.pgm" "$T/roads.txt" "$T/hsh" || bad "halo shard $i"; done
"$BIN" tiles --quiet --shard 0/3 $H "$T/dem.pgm" "$T/roads.txt" "$T/hsh"
rm -f "$T/hsh/3/0/1_n.png"; printf x >>"$T/hsh/3/1/0_n.png"
check "--resume remakes a lost and a changed normal tile under an intact parent" "$BIN" tiles --quiet --resume --shard 0/3 $H "$T/dem.pgm" "$T/roads.txt" "$T/hsh"
check "3 shards + merge = one run (--normals --halo)" sh -c "'$BIN' tiles --quiet --from-children $H '$T/dem.pgm' '$T/roads.txt' '$T/hsh' && diff -r -x .tiles-log '$T/hsh' '$T/ha' >/dev/null"
if "$BIN" tiles --quiet --format mbtiles $H "$T/dem.pgm" "$T/roads.txt" "$T/ha.mbtiles" 2>"$T/e"; then
    check "MBTiles --normals --halo: tiles and normal_tiles rows = the folder's" $PY mbtiles "$T/ha.mbtiles" "$T/ha"
fi
for args in "--halo 129" "--halo -1" "--normal-strength 0 --normals" "--normal-convention up --normals" "--normal-convention dx"; do
    "$BIN" tiles $args "$T/dem.pgm" "$T/roads.txt" "$T/bad" 2>"$T/e"; rc=$?
    check "tiles $args: exit 1, one line" sh -c "test $rc = 1 && test \$(wc -l <'$T/e') = 1"
done

# 8. terrain-only subtrees: a 513^2-cell DEM at 4 texels (2048^2 pixels, levels 0..3, complete
# up to 1) with roads in one corner: 3 of the 4 level-1 tiles are rendered directly at 1 texel
python3 -c "
import sys
W = 513
sys.stdout.buffer.write(b'P5\n%d %d\n255\n' % (W, W) + bytes(((i % W) // 16 + (i // W) // 24) % 200 for i in range(W * W)))" >"$T/r.pgm"
awk 'BEGIN { for (i = 0; i < 3; i++) { printf "road h%d width 6\n10 %d\n120 %d\nend\nroad v%d width 6\n%d 10\n%d 120\nend\n", i, 20 + 40 * i, 20 + 40 * i, i, 20 + 40 * i, 20 + 40 * i } }' >"$T/r.txt"
R="--texels 4"
check "terrain-only run exits 0" sh -c "'$BIN' tiles $R '$T/r.pgm' '$T/r.txt' '$T/rt' 2>'$T/e' && grep -q ', 3 terrain-only rendered at level 1' '$T/e'"
"$BIN" tiles --quiet --dense $R "$T/r.pgm" "$T/r.txt" "$T/rd"
"$BIN" --quiet --texels 1 --window 256,0,256,256 "$T/r.pgm" "$T/r.txt" "$T/r1.png"
check "terrain-only tile 1/1/0 = the 1-texel splat's window" $PY same "$T/r1.png" "$T/rt/1/1/0.png"
"$BIN" --quiet $R --weight-out "$T/rw.pgm" "$T/r.pgm" "$T/r.txt" "$T/r.png"
check "terrain-only: written iff dense level or holds a road" $PY sparse "$T/rt" "$T/rw.pgm"
check "terrain-only: finer tiles = the dense run's" sh -c "cd '$T/rt' && for f in 2/*/*.png 3/*/*.png; do cmp -s \$f '$T/rd/'\$f || exit 1; done"
check "terrain-only: seam against the box-filtered tiles < 1/255" $PY seam "$T/rt" "$T/rd" 1 1.0
check "terrain-only: the manifest states the rule" grep -q 'terrain only: it is rendered directly' "$T/rt/tiles.json"
"$BIN" tiles --quiet --render-all $R "$T/r.pgm" "$T/r.txt" "$T/ra"
check "--render-all: every tile written = the --dense run's" sh -c "cd '$T/ra' && test \$(find . -name '*.png' | wc -l) = 10 && for f in \$(find . -name '*.png'); do cmp -s \$f '$T/rd/'\$f || exit 1; done"
for i in 0 1 2; do "$BIN" tiles --quiet --shard $i/3 $R "$T/r.pgm" "$T/r.txt" "$T/rsh" || bad "terrain-only shard $i"; done
check "terrain-only: 3 shards + merge = one run" sh -c "'$BIN' tiles --quiet --from-children $R '$T/r.pgm' '$T/r.txt' '$T/rsh' && diff -r -x .tiles-log '$T/rsh' '$T/rt' >/dev/null"
# lit tiles (--lighting): finest tiles = windows of the lit image; no terrain-only shortcut
L="--texels 1 --lighting --sun 200,30"
check "lit run exits 0" "$BIN" tiles --quiet $L "$T/r.pgm" "$T/r.txt" "$T/lit"
"$BIN" --quiet $L --window 256,0,256,256 "$T/r.pgm" "$T/r.txt" "$T/l1.png"
check "lit tile 1/1/0 = the lit splat's window" $PY same "$T/l1.png" "$T/lit/1/1/0.png"
"$BIN" tiles --quiet --texels 1 "$T/r.pgm" "$T/r.txt" "$T/unlit"
check "lit tiles differ from unlit ones" sh -c "! cmp -s '$T/lit/1/1/0.png' '$T/unlit/1/1/0.png'"
check "lit: the manifest records --lighting and --sun" grep -q '"--lighting", "--sun", "200,30"' "$T/lit/tiles.json"
check "tiles: --sun without --lighting is refused" sh -c "! '$BIN' tiles --quiet --sun 200,30 '$T/r.pgm' '$T/r.txt' '$T/x' 2>'$T/e' && grep -q 'need --lighting' '$T/e'"
work() { "$BIN" tiles $R --shard $1/2 "$T/r.pgm" "$T/r.txt" "$T/rw$1" 2>&1 | sed -n 's/.*tiles: \([0-9]*\) rendered.*, \([0-9]*\) terrain-only.*/\1 + \2/p' | bc; }
check "terrain-only: 2 shards of equal work (renders + terrain-only tiles: $(work 0) and $(work 1))" test $(( $(work 0) - $(work 1) )) -le 1 -a $(( $(work 1) - $(work 0) )) -le 1
rm -f "$T/rsh/1/1/1.png" "$T/rsh/tiles.json"
check "terrain-only: --resume remakes a lost direct tile" sh -c "'$BIN' tiles --quiet --resume $R '$T/r.pgm' '$T/r.txt' '$T/rsh' && diff -r -x .tiles-log '$T/rsh' '$T/rt' >/dev/null"
E="$D/../docs/examples"
if [ -f "$E/surface.txt" ]; then
    if "$BIN" tiles --quiet --texels 2 "$E/dem.pgm" "$E/surface.txt" "$T/su" 2>"$T/e"; then
        check "the styles' surface images are inputs of the manifest" grep -q '"role": "surface", "path": "[^"]*asphalt-strip.png", "sha256": "[0-9a-f]\{64\}' "$T/su/tiles.json"
    elif grep -q 'OpenImageIO module' "$T/e"; then
        echo "SKIP: surface images: $(cat "$T/e")"
    else
        bad "surface images: $(cat "$T/e")"
    fi
fi
check "terrain-only with --halo 3: every halo pixel = the neighbour's" sh -c "'$BIN' tiles --quiet --halo 3 $R '$T/r.pgm' '$T/r.txt' '$T/rh' && $PY halo '$T/rh'"

# 9. a large pyramid (2049 x 2049 cells at 16 texels: 32784 x 32784 pixels, 4.3 GB as
# RGBA) within a fixed memory bound: a city of roads in one corner, the rest terrain
if [ -x /usr/bin/time ]; then
    python3 -c "
import sys
W = 2050
sys.stdout.buffer.write(b'P5\n%d %d\n255\n' % (W, W) + bytes(((i % W) // 16 + (i // W) // 24) % 200 for i in range(W * W)))" >"$T/big.pgm"
    awk 'BEGIN { for (i = 0; i < 6; i++) { printf "road h%d width 8\n20 %d\n300 %d\nend\nroad v%d width 8\n%d 20\n%d 300\nend\n", i, 30 + 50 * i, 30 + 50 * i, i, 30 + 50 * i, 30 + 50 * i } }' >"$T/city.txt"
    /usr/bin/time -f %M -o "$T/rss" "$BIN" tiles --quiet --texels 16 --tile-size 1024 "$T/big.pgm" "$T/city.txt" "$T/big" 2>"$T/e"
    rss=$(tail -n 1 "$T/rss")
    check "32784^2 pyramid built" grep -q '"levels": {"min": 0, "max": 6, "dense_max": 2}' "$T/big/tiles.json"
    check "32784^2 pyramid within 400 MB (peak $rss KB; the image is 4.3 GB)" test "$rss" -lt 400000
    check "32784^2 pyramid sparse: only city tiles on the finest level" test "$(ls "$T/big/6"/*/ | grep -c png)" -lt 40
    check "32784^2 pyramid: manifest hashes = files" $PY manifest "$T/big"
else
    echo "SKIP: /usr/bin/time not installed: the large pyramid's memory is not measured"
fi

echo "$pass passed, $fail failed"
[ "$fail" = 0 ]
