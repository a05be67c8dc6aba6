#!/bin/sh
# CLI tests of issue 26 ("Hardening, round 3", the CLI rows): paths in
# OUTDIR the run does not own (planted links, FIFOs, another run's
# temporaries), outputs over inputs only known after loading, pipes as
# tiles inputs, the decoded-image budget, GDAL's drivers and network, a
# full disk under --cog, and the messages of row 13. Each check failed on
# b8396fd (docs/ROBUSTNESS.md, "Defect classes of issue 26").
# Usage: sh tests/cli_hostile_test.sh PATH/TO/roadsplat
BIN=${1:?usage: cli_hostile_test.sh ROADSPLAT}
. "$(dirname "$0")/cli_lib.sh"
STRIP=$(dirname "$0")/../docs/examples/asphalt-strip.png
ref_scene "$T"
printf 'secret, not a tile\n' >"$T/victim"
unchanged() { test "$(cat "$T/victim")" = "secret, not a tile"; }

# ---- row 3: links planted in OUTDIR ------------------------------------------------
# the scene is one 240 x 160 tile: OUTDIR/0/0/0.png
mkdir -p "$T/t1/0/0"
ln -s "$T/victim" "$T/t1/0/0/.0.png.part"
"$BIN" tiles --quiet "$T/dem.pgm" "$T/roads.txt" "$T/t1" 2>"$T/e"
check "tiles: a link at a temporary's old fixed name is not followed ($(cat "$T/e"))" unchanged
check "tiles: the run still succeeds" test -s "$T/t1/tiles.json"
mkdir -p "$T/t2/.tiles-log"
ln -s "$T/victim" "$T/t2/.tiles-log/whole.log"
"$BIN" tiles --quiet "$T/dem.pgm" "$T/roads.txt" "$T/t2" 2>"$T/e"
check "tiles: a log that is a link: its target not truncated" unchanged
check "tiles: ... and the link named ($(cat "$T/e"))" grep -q "whole.log: not a regular file" "$T/e"
mkdir -p "$T/t3" "$T/keep"
printf 'mine\n' >"$T/keep/notes.log"
ln -s "$T/keep" "$T/t3/.tiles-log"
"$BIN" tiles --quiet "$T/dem.pgm" "$T/roads.txt" "$T/t3" 2>"$T/e"
check "tiles: .tiles-log linking to a folder: its *.log files kept" test -f "$T/keep/notes.log"
check "tiles: ... and the link named ($(cat "$T/e"))" grep -q "tiles-log: is a symbolic link" "$T/e"
mkdir -p "$T/t4/0"
ln -s "$T/keep" "$T/t4/0/0"
"$BIN" tiles --quiet "$T/dem.pgm" "$T/roads.txt" "$T/t4" 2>"$T/e"
check "tiles: a tile folder that is a link is refused ($(cat "$T/e"))" sh -c "test ! -e '$T/keep/0.png' && grep -q 'is a symbolic link' '$T/e'"

# a kill -9 leftover of an earlier run of the same log goes when its tile is made again
"$BIN" tiles --quiet "$T/dem.pgm" "$T/roads.txt" "$T/k3"
printf 'run 0123456789abcdef\n' >>"$T/k3/.tiles-log/whole.log"
printf 'half a tile' >"$T/k3/0/0/.0.png.0123456789abcdef.part"
rm "$T/k3/0/0/0.png"
check "--resume after a kill: the dead run's temporary is removed" sh -c "'$BIN' tiles --quiet --resume '$T/dem.pgm' '$T/roads.txt' '$T/k3' && test -f '$T/k3/0/0/0.png' && test ! -e '$T/k3/0/0/.0.png.0123456789abcdef.part'"
ln -s "$T/victim" "$T/k3/0/0/.0.png.0123456789abcdef.part"
rm "$T/k3/0/0/0.png"
"$BIN" tiles --quiet --resume "$T/dem.pgm" "$T/roads.txt" "$T/k3"
check "... a link under a dead run's name is neither followed nor its target removed" sh -c "test -L '$T/k3/0/0/.0.png.0123456789abcdef.part' && test -f '$T/victim'"

# ---- row 9: --resume reads back only regular files of a tile's size --------------
"$BIN" tiles --quiet "$T/dem.pgm" "$T/roads.txt" "$T/r9"
cp "$T/r9/0/0/0.png" "$T/tile.png"
rm "$T/r9/0/0/0.png" && mkfifo "$T/r9/0/0/0.png"
check "--resume with a FIFO as a tile: remade, no hang" timeout 30 "$BIN" tiles --quiet --resume "$T/dem.pgm" "$T/roads.txt" "$T/r9"
check "... the tile is the same as before" timeout 10 cmp -s "$T/tile.png" "$T/r9/0/0/0.png"
rm "$T/r9/0/0/0.png" && ln -s /dev/zero "$T/r9/0/0/0.png"
# a memory cap keeps a reader of /dev/zero from taking the machine (not under
# ASan, whose shadow memory needs terabytes of address space)
cap="ulimit -v 1000000;"; ldd "$BIN" 2>/dev/null | grep -q libasan && cap=
check "--resume with a link to /dev/zero as a tile: remade, no read" sh -c "$cap timeout 30 '$BIN' tiles --quiet --resume '$T/dem.pgm' '$T/roads.txt' '$T/r9'"
check "... the tile is the same as before" timeout 10 cmp -s "$T/tile.png" "$T/r9/0/0/0.png"

# ---- row 10: another run's temporaries are left alone ------------------------------
mkdir -p "$T/r10/0/0"
printf 'another run is writing this\n' >"$T/r10/0/0/.0.png.part"
check "tiles beside another run's temporary" "$BIN" tiles --quiet "$T/dem.pgm" "$T/roads.txt" "$T/r10"
check "... which it neither truncates nor renames" grep -q "another run" "$T/r10/0/0/.0.png.part"
ok10=1
for k in 1 2 3; do
    "$BIN" tiles --quiet --dense --texels 40 "$T/dem.pgm" "$T/roads.txt" "$T/c10" & p1=$!
    "$BIN" tiles --quiet --dense --texels 40 "$T/dem.pgm" "$T/roads.txt" "$T/c10" & p2=$!
    "$BIN" tiles --quiet --dense --texels 40 "$T/dem.pgm" "$T/roads.txt" "$T/c10" & p3=$!
    wait $p1 || ok10=0; wait $p2 || ok10=0; wait $p3 || ok10=0
done
check "three runs into one OUTDIR at once, three times: all exit 0" test $ok10 = 1
check "... and leave no temporaries" sh -c "! find '$T/c10' -name '*.part' -o -name '.rs-*' | grep -q ."
ok10=1
for k in 1 2; do
    for j in 0 1 2; do
        "$BIN" tiles --quiet --dense --texels 40 --shard $j/3 "$T/dem.pgm" "$T/roads.txt" "$T/s10" & eval "q$j=\$!"
        "$BIN" tiles --quiet --dense --texels 40 --resume --shard $j/3 "$T/dem.pgm" "$T/roads.txt" "$T/s10" & eval "u$j=\$!"
    done
    for j in 0 1 2; do eval "wait \$q$j" || ok10=0; eval "wait \$u$j" || ok10=0; done
done
check "a shard and its --resume at once, each shard, twice: all exit 0" test $ok10 = 1
check "... and the merge equals one run" sh -c "'$BIN' tiles --quiet --dense --texels 40 --from-children '$T/dem.pgm' '$T/roads.txt' '$T/s10' && diff -r -x .tiles-log '$T/s10' '$T/c10' >/dev/null"

# ---- row 6: tiles from pipes -------------------------------------------------------
"$BIN" tiles --quiet "$T/dem.pgm" "$T/roads.txt" "$T/p6f"
printf 'style wide\n  casing 1 #202020\nend\n' >"$T/st.txt"
sed 's/^road main width 6$/road main width 6 style=wide/' "$T/roads.txt" >"$T/roads_st.txt"
"$BIN" tiles --quiet --styles "$T/st.txt" "$T/dem.pgm" "$T/roads_st.txt" "$T/p6s"
if command -v bash >/dev/null 2>&1; then
    bash -c "'$BIN' tiles --quiet '$T/dem.pgm' <(cat '$T/roads.txt') '$T/p6p'"
    check "tiles: ROADS from a pipe = from the file" cmp -s "$T/p6f/0/0/0.png" "$T/p6p/0/0/0.png"
    h=$(sha256sum <"$T/roads.txt" | cut -c1-64)
    check "tiles: the manifest has the pipe's SHA-256" grep -q "$h" "$T/p6p/tiles.json"
    bash -c "'$BIN' tiles --quiet --styles <(cat '$T/st.txt') '$T/dem.pgm' '$T/roads_st.txt' '$T/p6q'"
    check "tiles: --styles from a pipe = from the file" cmp -s "$T/p6s/0/0/0.png" "$T/p6q/0/0/0.png"
else
    echo "SKIP: no bash for process substitution: tiles from pipes not run"
fi

# ---- row 4: outputs over inputs known only after loading -----------------------------
cp "$T/st.txt" "$T/styles.png"; cp "$T/styles.png" "$T/styles.orig"
"$BIN" --quiet --styles "$T/styles.png" "$T/dem.pgm" "$T/roads_st.txt" "$T/styles.png" 2>"$T/e"
check "OUT over --styles refused ($(cat "$T/e"))" sh -c "cmp -s '$T/styles.png' '$T/styles.orig' && grep -q 'is also the --styles' '$T/e'"
cp "$STRIP" "$T/strip.png"; cp "$STRIP" "$T/strip.orig"
printf 'style s\n  surface strip.png\nend\nroad main width 6 style=s\n2 2\n28 20\nend\n' >"$T/rs.txt"
"$BIN" --quiet "$T/dem.pgm" "$T/rs.txt" "$T/strip.png" 2>"$T/e"
check "OUT over a style's surface image refused ($(cat "$T/e"))" sh -c "cmp -s '$T/strip.png' '$T/strip.orig' && grep -q 'surface image' '$T/e'"
"$BIN" --quiet --normal-out "$T/strip.png" "$T/dem.pgm" "$T/rs.txt" "$T/o4.png" 2>"$T/e"
check "--normal-out over a surface image refused ($(cat "$T/e"))" sh -c "cmp -s '$T/strip.png' '$T/strip.orig' && test ! -e '$T/o4.png'"
GEN=$(dirname "$BIN")/atlasgen
if [ -x "$GEN" ] && "$GEN" "$T/atlas.c" "$T/atlas.png" "$T/atlas.txt"; then
    cp "$T/atlas.png" "$T/atlas.orig"
    "$BIN" --quiet --atlas "$T/atlas.png" --atlas-index "$T/atlas.txt" --normal-out "$T/atlas.png" "$T/dem.pgm" \
        "$T/roads.txt" "$T/o5.png" 2>"$T/e"
    check "--normal-out over --atlas refused ($(cat "$T/e"))" sh -c "cmp -s '$T/atlas.png' '$T/atlas.orig' && grep -q 'is also the --atlas' '$T/e'"
    # ---- row 12: a custom atlas without the automatic types ----
    cp "$T/atlas.orig" "$T/atlas.png"
    grep -v '^arrow\|^stop_line\|^give_way_line\|^zebra' "$T/atlas.txt" >"$T/atlas_few.txt"
    "$BIN" --quiet --atlas "$T/atlas.png" --atlas-index "$T/atlas_few.txt" "$T/dem.pgm" "$T/roads.txt" "$T/o12.png" 2>"$T/e"
    check "custom atlas without the automatic types: a warning naming them ($(cat "$T/e"))" grep -q "warning: .*atlas_few.txt: the atlas has no stop_line, give_way_line, zebra" "$T/e"
    "$BIN" --quiet --no-auto-markings --atlas "$T/atlas.png" --atlas-index "$T/atlas_few.txt" "$T/dem.pgm" "$T/roads.txt" "$T/o12.png" 2>"$T/e"
    check "... none with --no-auto-markings" test ! -s "$T/e"
else
    echo "SKIP: no atlasgen beside $BIN (make $(dirname "$BIN")/atlasgen): atlas checks not run"
fi
if "$BIN" tiles --quiet --format mbtiles "$T/dem.pgm" "$T/roads.txt" "$T/probe.mbtiles" 2>/dev/null; then
    cp "$STRIP" "$T/tex.mbtiles"
    "$BIN" tiles --quiet --format mbtiles --terrain-texture "$T/tex.mbtiles" "$T/dem.pgm" "$T/roads.txt" "$T/tex.mbtiles" 2>"$T/e"
    check "MBTiles OUT over --terrain-texture refused ($(cat "$T/e"))" sh -c "cmp -s '$T/tex.mbtiles' '$STRIP' && grep -q 'is also the --terrain-texture' '$T/e'"
else
    echo "SKIP: MBTiles not available: the MBTiles collision is not run"
fi

# ---- row 8: surface images: only used ones, each file once, a total budget ---------------
printf 'style used\n  surface strip.png\nend\nstyle unused\n  surface missing.png\nend\nroad main width 6 style=used\n2 2\n28 20\nend\n' >"$T/r8.txt"
check "an unused style's image is not read" "$BIN" --quiet "$T/dem.pgm" "$T/r8.txt" "$T/o8.png"
px=$(python3 -c "
import struct; d = open('$STRIP', 'rb').read(24); w, h = struct.unpack('>II', d[16:24]); print(w * h)")
printf 'style a\n  surface strip.png\nend\nstyle b\n  surface ./strip.png\nend\nroad main width 6 style=a\n2 2\n28 20\nend\nroad side width 3 style=b\n0 15\n30 15\nend\n' >"$T/r8b.txt"
check "one file under two names is decoded once (budget of one image, $px pixels)" "$BIN" --quiet --max-image-pixels $((px + 1)) "$T/dem.pgm" "$T/r8b.txt" "$T/o8b.png"
"$BIN" --quiet --max-image-pixels $((px + 1)) --terrain-texture "$STRIP" "$T/dem.pgm" "$T/r8b.txt" "$T/o8c.png" 2>"$T/e"
check "over the budget: refused, naming it and the option ($(cat "$T/e"))" sh -c "grep -q 'over the budget of $((px + 1)) (--max-image-pixels N raises it)' '$T/e' && test ! -e '$T/o8c.png'"
for k in 1 2 3 4 5 6; do printf 'style s%d\n  surface strip.png\nend\n' $k; done >"$T/r8d.txt"
printf 'road main width 6 style=s1\n2 2\n28 20\nend\n' >>"$T/r8d.txt"
check "six styles naming one image, one road: fits the budget of one" "$BIN" --quiet --max-image-pixels $((px + 1)) "$T/dem.pgm" "$T/r8d.txt" "$T/o8d.png"

# ---- rows 5, 13: a full disk under --cog ------------------------------------------------
if "$BIN" --quiet "$T/dem.pgm" "$T/roads.txt" "$T/probe.tif" 2>/dev/null; then
    mkdir -p "$T/full"
    if mount -t tmpfs -o size=200k tmpfs "$T/full" 2>/dev/null; then
        printf 'P2\n201 201\n255\n' >"$T/big.pgm"
        awk 'BEGIN { for (i = 0; i < 201 * 201; i++) printf "%d ", (i * 7919) % 251 }' >>"$T/big.pgm"
        printf 'road a width 6\n2 2\n190 190\nend\n' >"$T/rbig.txt"
        head -c 190k /dev/zero >"$T/full/filler"
        "$BIN" --quiet --cell-size 1 --texels 2 --cog "$T/big.pgm" "$T/rbig.txt" "$T/full/o.tif" 2>"$T/e"; rc=$?
        check "--cog on a nearly full disk: exit 1, no OUT ($(cat "$T/e"))" sh -c "test $rc = 1 && test ! -e '$T/full/o.tif'"
        check "... the message names the full file system, not libtiff" sh -c "grep -q 'file system is full' '$T/e' && ! grep -q TIFF '$T/e'"
        check "... no temporary left" sh -c "! ls -a '$T/full' | grep -q '^\.rs-'"
        umount "$T/full"
    else
        echo "SKIP: cannot mount a tmpfs (not root?): the full-disk --cog checks are not run"
    fi
else
    echo "SKIP: no GDAL module: GeoTIFF checks not run"
fi

# ---- rows 11, 13: GDAL inputs --------------------------------------------------------------
if command -v gdal_translate >/dev/null 2>&1 && "$BIN" --quiet "$T/dem.pgm" "$T/roads.txt" "$T/probe2.tif" 2>/dev/null; then
    printf 'ncols 4\nnrows 3\nxllcorner 500000\nyllcorner 5000000\ncellsize 1\n1 2 3 4\n5 6 7 8\n9 10 11 12\n' >"$T/g.asc"
    gdal_translate -q -a_srs EPSG:32632 "$T/g.asc" "$T/g.tif"
    head -c 100000 /dev/urandom >"$T/secret.bin"
    cat >"$T/raw.vrt" <<V
<VRTDataset rasterXSize="8" rasterYSize="8">
  <GeoTransform>500000, 1, 0, 5000000, 0, -1</GeoTransform>
  <VRTRasterBand dataType="Byte" band="1" subClass="VRTRawRasterBand">
    <SourceFilename relativetoVRT="0">$T/secret.bin</SourceFilename>
  </VRTRasterBand>
</VRTDataset>
V
    "$BIN" mesh "$T/raw.vrt" "$T/m.obj" 2>"$T/e"
    check "VRT reading raw bytes of a local file refused ($(cat "$T/e"))" sh -c "test ! -e '$T/m.obj' && grep -q -- '--gdal-trust' '$T/e'"
    check "... read with --gdal-trust" "$BIN" mesh --gdal-trust "$T/raw.vrt" "$T/m.obj"
    cat >"$T/abs.vrt" <<V
<VRTDataset rasterXSize="4" rasterYSize="3">
  <VRTRasterBand dataType="Float32" band="1">
    <SimpleSource><SourceFilename relativeToVRT="0">$T/g.tif</SourceFilename><SourceBand>1</SourceBand></SimpleSource>
  </VRTRasterBand>
</VRTDataset>
V
    "$BIN" --quiet "$T/abs.vrt" "$T/roads.txt" "$T/o11.png" 2>"$T/e"
    check "VRT naming a file by an absolute path refused ($(cat "$T/e"))" sh -c "test ! -e '$T/o11.png' && grep -q 'not a file beside it' '$T/e'"
    sed 's|<SourceFilename relativeToVRT="0">[^<]*</SourceFilename>|<SourceFilename relativeToVRT="1">abs.vrt</SourceFilename>|' "$T/abs.vrt" >"$T/outer.vrt"
    "$BIN" --quiet "$T/outer.vrt" "$T/roads.txt" "$T/o11n.png" 2>"$T/e"
    check "a VRT beside it that names a file by an absolute path: refused too ($(cat "$T/e"))" sh -c "test ! -e '$T/o11n.png' && grep -q 'abs.vrt: the VRT reads' '$T/e'"
    # ROADS as a URL: no request may reach the server
    port=$(python3 -c "import socket; s = socket.socket(); s.bind(('127.0.0.1', 0)); print(s.getsockname()[1])")
    (cd "$T" && exec python3 -m http.server "$port" --bind 127.0.0.1 >"$T/http.log" 2>&1) & hp=$!
    for k in 1 2 3 4 5 6 7 8 9 10; do grep -q Serving "$T/http.log" 2>/dev/null && break; sleep 0.3; done
    printf '{"type":"FeatureCollection","features":[]}' >"$T/r.geojson"
    "$BIN" --quiet "$T/g.tif" "http://127.0.0.1:$port/r.geojson" "$T/o11b.png" 2>"$T/e"
    "$BIN" --quiet "$T/g.tif" "/vsicurl/http://127.0.0.1:$port/r.geojson" "$T/o11c.png" 2>>"$T/e"
    sleep 0.3
    check "ROADS as a URL: refused, no request made ($(cat "$T/e"))" sh -c "! grep -q 'GET' '$T/http.log' && grep -q 'a URL; roadsplat reads only local files' '$T/e'"
    kill $hp 2>/dev/null; wait $hp 2>/dev/null
    # row 13: Float64 beyond the float range, a huge origin, GDAL's own errors
    printf 'ncols 4\nnrows 3\nxllcorner 500000\nyllcorner 5000000\ncellsize 1\n1 2 3 4\n5 1e300 7 8\n9 10 11 12\n' >"$T/f64.asc"
    gdal_translate -q -oo DATATYPE=Float64 -ot Float64 -a_srs EPSG:32632 "$T/f64.asc" "$T/f64.tif"
    "$BIN" mesh "$T/f64.tif" "$T/f64.obj" 2>"$T/e"
    check "Float64 sample beyond the float range named, not nodata ($(cat "$T/e"))" sh -c "test ! -e '$T/f64.obj' && grep -q 'column 1, row 1 is 1e+300,' '$T/e'"
    printf 'ncols 4\nnrows 3\nxllcorner 1e300\nyllcorner 5000000\ncellsize 1\n1 2 3 4\n5 6 7 8\n9 10 11 12\n' >"$T/o300.asc"
    "$BIN" mesh "$T/o300.asc" "$T/o300.obj" 2>"$T/e"
    check "mesh refuses a 1e300 origin like the main command ($(cat "$T/e"))" sh -c "test ! -e '$T/o300.obj' && grep -q 'not within 1e12 m' '$T/e'"
    printf 'ncols 4\nnrows 3\nxllcorner 0\nyllcorner 2e12\ncellsize 1\n1 2 3 4\n5 6 7 8\n9 10 11 12\n' >"$T/y.asc"
    "$BIN" --quiet "$T/y.asc" "$T/roads.txt" "$T/y.png" 2>"$T/e"
    check "an origin out of range is printed with y as in the file ($(cat "$T/e"))" sh -c "grep -q 'y 2e+12 (y north)' '$T/e' && ! grep -q -- '-2e+12' '$T/e'"
    printf 'ncols 4\nnrows -3\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3 4\n' >"$T/bad.asc"
    "$BIN" --quiet "$T/bad.asc" "$T/roads.txt" "$T/bad.png" 2>"$T/e"
    check "a GDAL failure is reported as GDAL's ($(cat "$T/e"))" sh -c "grep -q 'GDAL (AAIGrid driver)' '$T/e' && ! grep -qi 'OpenImageIO\|format reader' '$T/e'"
else
    echo "SKIP: no GDAL module or tools: GDAL checks not run"
fi
echo "cli_hostile: $pass passed, $fail failed"
[ "$fail" = 0 ]
