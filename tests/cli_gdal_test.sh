#!/bin/sh
# CLI tests of the GDAL layer (issue 17, docs/gis.md): georeferenced DEMs,
# OGR roads, the world frame, GeoTIFF / world-file output, bad GIS input.
# Usage: sh tests/cli_gdal_test.sh PATH/TO/roadsplat. Every input is made
# here with GDAL's own tools (gdal_translate, ogr2ogr, gdaltransform) from
# text. Prints "N passed, N failed"; skips (0 passed, 0 failed, a SKIP line)
# without the GDAL module or GDAL's tools.
BIN=${1:?usage: cli_gdal_test.sh ROADSPLAT}
. "$(dirname "$0")/cli_lib.sh"

skip() {
    echo "SKIP cli gdal: $1"
    echo "cli_gdal: 0 passed, 0 failed"
    exit 0
}
"$BIN" convert "$T/none.geojson" "$T/none.txt" 2>"$T/e"
grep -q "no GDAL support" "$T/e" && skip "$BIN was built without GDAL (make deps installs libgdal-dev)"
for tool in gdal_translate ogr2ogr gdaltransform gdalinfo gdallocationinfo python3; do
    command -v $tool >/dev/null 2>&1 || skip "$tool is missing (make deps installs gdal-bin)"
done
TESTS=$(cd "$(dirname "$0")" && pwd)
BIN=$(cd "$(dirname "$BIN")" && pwd)/$(basename "$BIN")
cd "$T" || exit 1

# ---- data -------------------------------------------------------------------
# A 61 x 41 DEM of 2 m cells in UTM 32N: the first pixel's corner at
# (500000, 5000080), so sample (0,0) - the first pixel's centre - is at
# (500001, 5000079). A 5 x 5 nodata block in the top-left corner.
X0=500000 Y0=5000080
python3 - <<'PY'
W, H, cs = 61, 41, 2
def grid(name, nodata, fmt, deg=False):
    with open(name, 'w') as f:
        if deg:
            f.write("ncols %d\nnrows %d\nxllcorner 9.0\nyllcorner 45.1\ncellsize 0.0001\n" % (W, H))
        else:
            f.write("ncols %d\nnrows %d\nxllcorner 500000\nyllcorner %d\ncellsize %d\n" % (W, H, 5000080 - H * cs, cs))
        if nodata: f.write("NODATA_value -9999\n")
        for i in range(H):
            f.write(" ".join("-9999" if nodata and i < 5 and j < 5 else fmt % (200 + 0.3 * j + 0.2 * i)
                             for j in range(W)) + "\n")
grid('dem_f.asc', True, '%.2f')
grid('dem_i.asc', False, '%.0f')
grid('dem_deg.asc', False, '%.2f', True)
PY
gdal_translate -q -a_srs EPSG:32632 -ot Float32 dem_f.asc dem_f32.tif
gdal_translate -q -a_srs EPSG:32632 -ot UInt16 dem_i.asc dem_u16.tif
gdal_translate -q -a_srs EPSG:4326 -ot Float32 dem_deg.asc dem_deg.tif
gdal_translate -q -a_srs EPSG:32632 -a_ullr 500000 5000080 500122 5000000 dem_f.asc dem_nonsq.tif
gdal_translate -q -ot Float32 dem_f.asc dem_nocrs.tif
cat >dem_rot.vrt <<'V'
<VRTDataset rasterXSize="61" rasterYSize="41">
  <SRS>EPSG:32632</SRS>
  <GeoTransform>500000, 2, 0.5, 5000080, 0.5, -2</GeoTransform>
  <VRTRasterBand dataType="Float32" band="1">
    <SimpleSource><SourceFilename relativeToVRT="1">dem_f32.tif</SourceFilename><SourceBand>1</SourceBand></SimpleSource>
  </VRTRasterBand>
</VRTDataset>
V
sed 's/, 0.5, 5000080, 0.5, -2/, 0, 5000080, 0, -2/' dem_rot.vrt >dem_ok.vrt
# Roads in the DEM's CRS: "Main" east-west at y = 5000040 (x 500010..500110),
# "Side" north-south at x = 500060 (y 5000010..5000070), and a footpath point.
cat >roads_utm.geojson <<'J'
{"type": "FeatureCollection",
 "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::32632"}},
 "features": [
  {"type": "Feature", "properties": {"name": "Main", "highway": "residential", "width": "6"},
   "geometry": {"type": "LineString", "coordinates": [[500010, 5000040], [500110, 5000040]]}},
  {"type": "Feature", "properties": {"name": "Side", "highway": "service", "lanes": "1", "oneway": "yes"},
   "geometry": {"type": "MultiLineString", "coordinates": [[[500060, 5000010], [500060, 5000070]]]}}
 ]}
J
ogr2ogr -q -t_srs EPSG:4326 roads_wgs84.geojson roads_utm.geojson
ogr2ogr -q -f GPKG roads.gpkg roads_utm.geojson
ogr2ogr -q -f GPKG -t_srs EPSG:4326 roads_wgs84.gpkg roads_utm.geojson
# OSM XML in WGS84, nodes from gdaltransform
ll() { echo "$1 $2" | gdaltransform -s_srs EPSG:32632 -t_srs EPSG:4326 | awk '{ printf "lat=\"%.10f\" lon=\"%.10f\"", $2, $1 }'; }
cat >roads.osm <<O
<?xml version="1.0" encoding="UTF-8"?>
<osm version="0.6" generator="roadsplat test">
  <node id="1" version="1" $(ll 500010 5000040)/>
  <node id="2" version="1" $(ll 500110 5000040)/>
  <node id="3" version="1" $(ll 500060 5000010)/>
  <node id="4" version="1" $(ll 500060 5000070)/>
  <way id="10" version="1"><nd ref="1"/><nd ref="2"/>
    <tag k="highway" v="residential"/><tag k="name" v="Main"/><tag k="width" v="6"/></way>
  <way id="11" version="1"><nd ref="3"/><nd ref="4"/>
    <tag k="highway" v="service"/><tag k="name" v="Side"/><tag k="lanes" v="1"/><tag k="oneway" v="yes"/></way>
</osm>
O

# ---- helpers --------------------------------------------------------------------
# weight W X Y: the --weight-out GeoTIFF W at world point (X, Y), 0..65535
weight() { gdallocationinfo -valonly -geoloc "$1" "$2" "$3"; }
# on_roads W: centre weight >= 0.99 on both centrelines, 0 well away from them
on_roads() {
    for p in "500020 5000040" "500100 5000040" "500060 5000020" "500060 5000065" "500040 5000040"; do
        v=$(weight "$1" $p)
        [ -n "$v" ] && [ "$v" -ge 64880 ] || { echo "weight at $p is '$v'"; return 1; }
    done
    for p in "500020 5000050" "500040 5000065" "500100 5000015"; do
        v=$(weight "$1" $p)
        [ "$v" = 0 ] || { echo "weight at $p is '$v' (off the roads)"; return 1; }
    done
}
# err DESC PATTERN ARGS...: exit 1, one stderr line matching PATTERN, no out.tif
err() {
    d=$1 pat=$2; shift 2
    rm -f out.tif
    "$BIN" --quiet "$@" 2>e; rc=$?
    if [ $rc -eq 1 ] && [ "$(wc -l <e)" -eq 1 ] && grep -Eq "$pat" e && [ ! -e out.tif ]; then ok
    else bad "$d: exit $rc, stderr: $(cat e)"; fi
}

# ---- roads from each source land on the expected pixels ---------------------------
for src in roads_utm.geojson roads_wgs84.geojson roads.gpkg roads_wgs84.gpkg roads.osm; do
    rm -f w.tif
    if "$BIN" --quiet --texels 4 --weight-out w.tif dem_f32.tif "$src" out_$src.tif 2>e && [ ! -s e ]; then
        check "$src: roads on the expected pixels" on_roads w.tif
    else
        bad "$src: run failed: $(cat e)"
    fi
done
check "16-bit DEM: run" "$BIN" --quiet --texels 4 --weight-out w16.tif dem_u16.tif roads.gpkg o16.png
check "16-bit DEM: weight" on_roads w16.tif
check "VRT DEM: roads on the expected pixels" "$BIN" --quiet --texels 4 --weight-out wv.tif dem_ok.vrt roads.osm ov.png
check "VRT DEM: weight" on_roads wv.tif

# ---- the output GeoTIFF's georeference is the texture grid's ----------------------
"$BIN" --quiet --texels 4 dem_f32.tif roads_utm.geojson out.tif 2>e || bad "GeoTIFF run: $(cat e)"
gdalinfo -json out.tif >info.json 2>/dev/null
python3 - info.json <<'PY' && ok || bad "GeoTIFF geotransform / CRS / layout"
import json, sys
j = json.load(open(sys.argv[1]))
gt = j['geoTransform']
want = [500001.0, 0.5, 0.0, 5000079.0, 0.0, -0.5]   # sample (0,0) = first DEM pixel's centre; 2 m / 4 texels
ok = all(abs(a - b) < 1e-9 for a, b in zip(gt, want)) and j['size'] == [240, 160]
wkt = j['coordinateSystem']['wkt']
ok = ok and 'ID["EPSG",32632]' in wkt
ok = ok and j['metadata']['IMAGE_STRUCTURE'].get('COMPRESSION') == 'DEFLATE'
ok = ok and j['bands'][0]['block'] == [256, 256] and len(j['bands']) == 4 and j['bands'][3]['colorInterpretation'] == 'Alpha'
if not ok: print(gt, j['size'], wkt[-40:], j['metadata'], j['bands'][0]['block'])
sys.exit(0 if ok else 1)
PY
# nodata: transparent where the nearest DEM sample is nodata, opaque elsewhere
a_nd=$(gdallocationinfo -valonly -b 4 -geoloc out.tif 500003 5000077)
a_nd2=$(gdallocationinfo -valonly -b 4 -geoloc out.tif 500009.9 5000070.1)
a_ok=$(gdallocationinfo -valonly -b 4 -geoloc out.tif 500011.1 5000068.9)
a_far=$(gdallocationinfo -valonly -b 4 -geoloc out.tif 500100 5000010)
[ "$a_nd" = 0 ] && [ "$a_nd2" = 0 ] && [ "$a_ok" = 255 ] && [ "$a_far" = 255 ] && ok ||
    bad "nodata alpha: $a_nd $a_nd2 $a_ok $a_far (want 0 0 255 255)"
# the same texture as a PNG: the same RGBA; --world-file writes .pgw and .prj
"$BIN" --quiet --texels 4 --world-file dem_f32.tif roads_utm.geojson out.png 2>e || bad "PNG run: $(cat e)"
gdal_translate -q -of PNG out.tif fromtif.png
PYTHONPATH="$TESTS" python3 - out.png fromtif.png <<'PY' && ok || bad "PNG and GeoTIFF pixels differ"
import sys
from png_read import read
a, b = read(sys.argv[1]), read(sys.argv[2])
sys.exit(0 if a[:3] == b[:3] and list(a[3]) == list(b[3]) else 1)
PY
[ "$(tr '\n' ' ' <out.pgw)" = "0.5 0 0 -0.5 500001.25 5000078.75 " ] && ok || bad "world file: $(tr '\n' ' ' <out.pgw)"
grep -q 'PROJCS\["WGS_1984_UTM_Zone_32N"' out.prj && ok || bad ".prj: $(head -c 100 out.prj)"
# --window: the window's own geotransform
"$BIN" --quiet --texels 4 --window 8,4,100,60 dem_f32.tif roads_utm.geojson win.tif 2>e || bad "window run: $(cat e)"
gdalinfo -json win.tif | python3 -c "
import json, sys; gt = json.load(sys.stdin)['geoTransform']
sys.exit(0 if gt == [500005.0, 0.5, 0.0, 5000077.0, 0.0, -0.5] else 1)" && ok || bad "--window geotransform"
# --cog: a Cloud Optimized GeoTIFF with the same georeference
"$BIN" --quiet --texels 4 --cog dem_f32.tif roads_utm.geojson cog.tif 2>e || bad "--cog run: $(cat e)"
gdalinfo cog.tif 2>/dev/null | grep -q "LAYOUT=COG" && ok || bad "--cog: no COG layout"
gdalinfo cog.tif | grep -q "Origin = (500001.000000000000000,5000079.000000000000000)" && ok || bad "--cog: origin"

# --window-world: the same window in world units, snapped outwards to whole pixels
"$BIN" --quiet --texels 4 --window-world 500005,5000047,500055,5000077 dem_f32.tif roads_utm.geojson ww1.tif 2>e &&
    [ "$(gdalinfo -checksum ww1.tif | grep Checksum)" = "$(gdalinfo -checksum win.tif | grep Checksum)" ] &&
    gdalinfo ww1.tif | grep -q "Size is 100, 60" && ok || bad "--window-world = --window 8,4,100,60: $(cat e)"
"$BIN" --quiet --texels 4 --window-world 500005.1,5000047.2,500054.8,5000076.9 dem_f32.tif roads_utm.geojson ww2.tif 2>e &&
    gdalinfo -json ww2.tif | python3 -c "
import json, sys; j = json.load(sys.stdin)
sys.exit(0 if j['geoTransform'] == [500005.0, 0.5, 0.0, 5000077.0, 0.0, -0.5] and j['size'] == [100, 60] else 1)" &&
    ok || bad "--window-world snaps outwards: $(cat e)"
"$BIN" --quiet --texels 4 --window-world 500001,4999999,500121,5000079 dem_f32.tif roads_utm.geojson ww3.tif 2>e &&
    gdalinfo ww3.tif | grep -q "Size is 240, 160" && ok || bad "--window-world of the whole map: $(cat e)"
err "--window-world outside the map" "^roadsplat: --window-world: 500100,5000000,500130,5000020 is not inside the map \(dem_f32.tif\): it spans x 500001..500121, y 4999999..5000079 \(y north, EPSG:32632\)$" \
    --window-world 500100,5000000,500130,5000020 dem_f32.tif roads_utm.geojson out.tif
err "--window-world empty box" "^roadsplat: --window-world: 500050,5000010,500040,5000020 is not XMIN,YMIN,XMAX,YMAX with XMIN < XMAX" \
    --window-world 500050,5000010,500040,5000020 dem_f32.tif roads_utm.geojson out.tif
err "--window-world syntax" "^roadsplat: --window-world: '1,2,3' is not XMIN,YMIN,XMAX,YMAX" --window-world 1,2,3 dem_f32.tif roads_utm.geojson out.tif
err "--window and --window-world" "^roadsplat: --window and --window-world are exclusive" --window 0,0,1,1 --window-world 1,2,3,4 \
    dem_f32.tif roads_utm.geojson out.tif

# ---- convert: road text with a frame line, the same image --------------------------
check "convert --dem" "$BIN" convert --dem dem_f32.tif roads_wgs84.geojson conv.txt
grep -q "^frame world EPSG:32632$" conv.txt && grep -q '^road "Main" width 6 class=residential$' conv.txt &&
    grep -q '^road "Side" class=service lanes=1 oneway=yes$' conv.txt && ok || bad "convert output: $(head -5 conv.txt)"
"$BIN" --quiet --texels 4 --weight-out wc.tif dem_f32.tif conv.txt conv.png 2>e && check "converted text: roads on pixels" on_roads wc.tif ||
    bad "converted text run: $(cat e)"
check "convert (auto UTM zone of degrees)" "$BIN" convert roads.osm conv_osm.txt
grep -q "^frame world EPSG:32632$" conv_osm.txt && ok || bad "convert picks the UTM zone: $(sed -n 2p conv_osm.txt)"
check "convert --t-srs" "$BIN" convert --t-srs EPSG:32632 --where "name = 'Side'" roads_wgs84.gpkg side.txt
[ "$(grep -c '^road ' side.txt)" = 1 ] && ok || bad "convert --where: $(grep '^road' side.txt)"
# --where and --layer in the splat
"$BIN" --quiet --texels 4 --where "name = 'Main'" --weight-out ww.tif dem_f32.tif roads.gpkg wh.png 2>e || bad "--where run: $(cat e)"
[ "$(weight ww.tif 500060 5000020)" = 0 ] && [ "$(weight ww.tif 500020 5000040)" -ge 64880 ] && ok || bad "--where selects"
err "--layer missing" "^roadsplat: roads.gpkg: no layer 'nope' \(layers: 'roads_utm'\)$" --layer nope dem_f32.tif roads.gpkg out.tif
err "--layer on road text" "^roadsplat: conv.txt: --layer and --where select from GIS road sources" --layer x dem_f32.tif conv.txt out.tif

# ---- world frame of road text ------------------------------------------------------
printf 'frame world EPSG:32632\nroad a width 4\n500010 5000040\n500110 5000040\nend\n' >world.txt
"$BIN" --quiet --texels 4 --weight-out wt.tif dem_f32.tif world.txt wt.png 2>e && [ ! -s e ] &&
    [ "$(weight wt.tif 500030 5000040)" -ge 64880 ] && ok || bad "frame world text: $(cat e)"
printf 'P2\n3 3\n9\n1 2 3 4 5 6 7 8 9\n' >dem.pgm
printf 'road a width 1\n0 0\n2 2\nend\n' >local.txt
err "frame world on a PGM" "^roadsplat: world.txt: the roads are in world coordinates \('frame world'\) but the DEM dem.pgm has no georeference" \
    dem.pgm world.txt out.png
sed 's/EPSG:32632/EPSG:32633/' world.txt >world33.txt
err "CRS mismatch" "^roadsplat: world33.txt: the roads are in EPSG:32633 but the DEM dem_f32.tif is in EPSG:32632" dem_f32.tif world33.txt out.tif
# no road on the map: a warning naming the road file and both extents; --strict: an error
printf 'frame world EPSG:32632\nroad far width 4\n600000 6000000\n600100 6000000\nend\n' >far.txt
"$BIN" --quiet dem_f32.tif far.txt far.tif 2>e; rc=$?
[ $rc = 0 ] && grep -q "^roadsplat: warning: far.txt: no road touches the map: the roads span x 600000..600100, y 6000000..6000000; the map (dem_f32.tif) spans x 500001..500121, y 4999999..5000079 (y north, EPSG:32632)$" e &&
    ok || bad "no road on the map: exit $rc: $(cat e)"
err "--strict: no road on the map" "^roadsplat: far.txt: no road touches the map" --strict dem_f32.tif far.txt out.tif
err "--cell-size with a georeferenced DEM" "^roadsplat: dem_f32.tif: --cell-size: the DEM is georeferenced" --cell-size 5 dem_f32.tif roads.gpkg out.tif

# ---- mesh: the DEM's cell size, the world point of sample (0,0), the .mtl ----------
"$BIN" mesh --max-error 0 --texture out.tif dem_f32.tif m.obj 2>e || bad "mesh run: $(cat e)"
grep -q "^# world: sample (0,0) at x 500001, y 5000079 (north up, EPSG:32632);" m.obj && grep -q "^mtllib m.mtl$" m.obj &&
    grep -q "^map_Kd out.tif$" m.mtl && ok || bad "mesh header / .mtl: $(head -4 m.obj)"
awk '$1 == "v" && $2 > mx { mx = $2 } $1 == "v" && $4 > mz { mz = $4 } END { exit !(mx == 120 && mz == 80) }' m.obj &&
    ok || bad "mesh extent is not 120 x 80 m (2 m cells)"
rm -f m2.obj
"$BIN" mesh --cell-size 3 dem_f32.tif m2.obj 2>e; [ $? = 1 ] && [ ! -e m2.obj ] &&
    grep -q "^roadsplat: dem_f32.tif: --cell-size: the DEM is georeferenced" e && ok || bad "mesh --cell-size: $(cat e)"

# ---- OSM crossing nodes: crossing=zebra on the road's point, not on the footway ----
cat >crossings.osm <<O
<?xml version="1.0" encoding="UTF-8"?>
<osm version="0.6" generator="roadsplat test">
  <node id="1" version="1" $(ll 500010 5000040)/>
  <node id="2" version="1" $(ll 500110 5000040)/>
  <node id="5" version="1" $(ll 500030 5000040)><tag k="highway" v="crossing"/><tag k="crossing" v="zebra"/></node>
  <node id="6" version="1" $(ll 500090 5000040)><tag k="highway" v="crossing"/><tag k="crossing" v="uncontrolled"/><tag k="crossing:markings" v="zebra"/></node>
  <node id="7" version="1" $(ll 500045 5000040)><tag k="highway" v="crossing"/><tag k="crossing" v="traffic_signals"/></node>
  <node id="8" version="1" $(ll 500030 5000030)/>
  <node id="9" version="1" $(ll 500030 5000050)/>
  <node id="12" version="1" $(ll 500070 5000060)><tag k="highway" v="crossing"/><tag k="crossing" v="zebra"/></node>
  <way id="10" version="1"><nd ref="1"/><nd ref="5"/><nd ref="7"/><nd ref="6"/><nd ref="2"/>
    <tag k="highway" v="residential"/><tag k="name" v="Main"/><tag k="width" v="6"/></way>
  <way id="11" version="1"><nd ref="8"/><nd ref="5"/><nd ref="9"/>
    <tag k="highway" v="footway"/><tag k="footway" v="crossing"/></way>
</osm>
O
check "convert: OSM crossings" "$BIN" convert --dem dem_f32.tif crossings.osm cx.txt
# Main's points 2 and 4 carry crossing=zebra (x 500030 and 500090, to the centimetre); no other point does
awk '/^road "Main"/ { r = 1; k = 0; next } /^road / { r = 2; next } /^end/ { r = 0 }
     r == 1 && $1 + 0 > 0 { k++; if (($3 == "crossing=zebra") != (k == 2 || k == 4)) bad = 1
                             if ($3 == "crossing=zebra") { d = ($1 - (k == 2 ? 500030 : 500090)); if (d * d > 0.0004) bad = 1 } }
     r == 2 && /crossing/ { bad = 1 }
     /crossing=zebra/ && !/^#/ { n++ }
     END { exit !(n == 2 && !bad) }' cx.txt && grep -q "^# 3 zebra crossing nodes: 2 on roads" cx.txt &&
    ok || bad "convert: crossing=zebra points: $(grep -n crossing cx.txt)"
"$BIN" --quiet --texels 8 --stats cx.json dem_f32.tif crossings.osm cx.png 2>e &&
    python3 -c "import json, sys; sys.exit(0 if json.load(open('cx.json'))['markings']['auto'] == 12 else 1)" && # 2 zebras of 6 bars (issue 27)
    ok || bad "OSM crossings: two zebra markings: $(cat e) $(grep -o '"markings": {[^}]*}' cx.json)"
cat >mixed.geojson <<'J'
{"type": "FeatureCollection",
 "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::32632"}},
 "features": [
  {"type": "Feature", "properties": {"name": "Main", "highway": "residential", "width": "6"},
   "geometry": {"type": "LineString", "coordinates": [[500010, 5000040], [500030, 5000040], [500110, 5000040]]}},
  {"type": "Feature", "properties": {"highway": "crossing", "crossing": "zebra"},
   "geometry": {"type": "Point", "coordinates": [500030, 5000040]}}
 ]}
J
"$BIN" convert mixed.geojson mixed.txt 2>e && grep -q "^500030 5000040 crossing=zebra$" mixed.txt && ok ||
    bad "crossing points in a mixed GeoJSON layer: $(cat e) $(cat mixed.txt)"

# ---- render: the camera in world coordinates (x east, y north) ---------------------
if "$BIN" render --help >/dev/null 2>&1; then
    printf 'frame world EPSG:32632\nroad main width 4\n500010 5000040\n500110 5000040\nend\nroad stub width 4\n500061 5000040\n500061 5000079\nend\n' >stub.txt
    R="$BIN render --quiet --texels 4 --size 160x120"
    # the default view's camera and target, reported in world coordinates, give the same picture
    $R --stats rs.json dem_f32.tif stub.txt r1.png 2>e || bad "render on a GeoTIFF: $(cat e)"
    python3 - rs.json >cam.txt <<'PY' && ok || bad "render --stats: frame and look_at in world coordinates: $(grep -E 'frame|camera|look_at' rs.json)"
import json, sys
j = json.load(open(sys.argv[1]))
c, l = j['camera'], j['look_at']
ok = j['frame'] == 'world' and l[0] == 500061 and l[1] == 5000039 and c[0] == 500061 and c[1] < 5000039
print(' '.join('%.17g,%.17g,%.17g' % tuple(v) for v in (c, l)))
sys.exit(0 if ok else 1)
PY
    read cam look <cam.txt
    $R --camera "$cam" --look-at "$look" dem_f32.tif stub.txt r2.png 2>e && cmp -s r1.png r2.png && ok ||
        bad "render: --camera/--look-at in world coordinates round-trip: $(cat e)"
    # straight down on the map centre: north (the stub) is up in the picture
    $R --camera 500061,5000039,313 --look-at 500061,5000039,200 --lighting off dem_f32.tif stub.txt r3.png 2>e && [ ! -s e ] &&
        PYTHONPATH="$TESTS" python3 - r3.png <<'PY' && ok || bad "render: world top-down view is not north up: $(cat e)"
import sys
from png_read import read
w, h, c, px = read(sys.argv[1])
def grey(x, y):
    r, g, b = px[(y * w + x) * c:(y * w + x) * c + 3]
    return max(r, g, b) < 110 and max(r, g, b) - min(r, g, b) < 12
sys.exit(0 if grey(80, 30) and grey(80, 60) and not grey(80, 90) and not grey(30, 30) else 1)
PY
    # local numbers on a georeferenced DEM: a warning naming the map's world extent
    $R --camera 60,100,300 --look-at 60,40,200 dem_f32.tif stub.txt r4.png 2>e &&
        grep -q "^roadsplat: warning: --look-at 60,40 is far off the map dem_f32.tif, which spans x 500001..500121, y 4999999..5000079 (world coordinates, y north)$" e &&
        ok || bad "render: far --look-at warning: $(cat e)"
else
    echo "SKIP cli gdal: render checks (this build has no OSMesa)"
fi

# ---- bad GIS input: one clear line each ------------------------------------------
err "DEM in degrees" "^roadsplat: dem_deg.tif: the DEM is in geographic degrees \(EPSG:4326\); roadsplat needs metres: gdalwarp -t_srs EPSG:32632 -r bilinear dem_deg.tif dem_utm.tif$" \
    dem_deg.tif roads.gpkg out.tif
err "non-square pixels" "^roadsplat: dem_nonsq.tif: pixels are not square \(2 x 1.95121951" dem_nonsq.tif roads.gpkg out.tif
err "rotated DEM" "^roadsplat: dem_rot.vrt: the geotransform is rotated \(terms 0.5 and 0.5\)" dem_rot.vrt roads.gpkg out.tif
err "GIS roads on a DEM without CRS" "^roadsplat: roads.gpkg: GIS roads are reprojected to the DEM's coordinate system, and the DEM has no CRS" \
    dem_nocrs.tif roads.gpkg out.tif
printf 'WKT,name\n"LINESTRING (500010 5000040,500110 5000040)",a\n' >nocrs.csv
err "roads without CRS" "^roadsplat: nocrs.csv: layer 'nocrs' has no coordinate system; give it one: ogr2ogr -a_srs" dem_f32.tif nocrs.csv out.tif
printf '{"type": "FeatureCollection", "features": []}\n' >empty.geojson
err "empty layer" "^roadsplat: empty.geojson: layer 'empty' has no features$" dem_f32.tif empty.geojson out.tif
printf '{"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {}, "geometry": {"type": "Point", "coordinates": [9, 45]}}]}\n' >points.geojson
err "point layer" "^roadsplat: points.geojson: layer 'points' holds points, not lines \(LineString or MultiLineString\)$" dem_f32.tif points.geojson out.tif
head -c 150 roads_utm.geojson >broken.geojson
err "broken file" "^roadsplat: broken.geojson: not a vector source GDAL can read" dem_f32.tif broken.geojson out.tif
err "unknown output extension" "^roadsplat: out.jpg: OUT has the unknown extension '.jpg': roadsplat writes .png or .tif \(GeoTIFF\)$" \
    dem_f32.tif roads.gpkg out.jpg
rm -f out.png out.pgw out.prj
err "--world-file without georeference" "^roadsplat: --world-file: the DEM has no georeference; give --origin X,Y with roads in .frame world." --world-file dem.pgm local.txt out.png
[ ! -e out.png ] && [ ! -e out.pgw ] && ok || bad "--world-file failure left files"

# ---- read once (issue 26, class 1): GDAL reads the bytes the run registered ----------
# Pipes: a GeoTIFF DEM and a GeoJSON road source from process substitution
# give the picture of the files, and tiles hash the bytes loaded.
"$BIN" --quiet --texels 2 dem_f32.tif roads_utm.geojson ro_file.png 2>e || bad "read once: file run: $(cat e)"
if command -v bash >/dev/null 2>&1; then
    BIN="$BIN" bash -c '"$BIN" --quiet --texels 2 <(cat dem_f32.tif) <(cat roads_utm.geojson) ro_pipe.png' 2>e &&
        cmp -s ro_file.png ro_pipe.png && ok || bad "a pipe GeoTIFF DEM and a pipe GeoJSON give the files' picture: $(cat e)"
    BIN="$BIN" bash -c '"$BIN" tiles --quiet --texels 2 <(cat dem_f32.tif) <(cat roads_utm.geojson) ro_tp' 2>e &&
        python3 - dem_f32.tif roads_utm.geojson ro_tp/tiles.json >e 2>&1 <<'PY' && ok || bad "tiles from pipes: manifest hashes the bytes loaded: $(cat e)"
import hashlib, json, sys
m = json.load(open(sys.argv[3]))
got = {i["role"]: i["sha256"] for i in m["inputs"]}
want = {"DEM": hashlib.sha256(open(sys.argv[1], "rb").read()).hexdigest(),
        "ROADS": hashlib.sha256(open(sys.argv[2], "rb").read()).hexdigest()}
assert got == want, (got, want)
PY
else
    echo "SKIP cli gdal: no bash for process substitution: pipe checks not run"
fi
mkfifo ro_fifo.tif && { cat dem_f32.tif >ro_fifo.tif & } &&
    "$BIN" --quiet --texels 2 ro_fifo.tif roads_utm.geojson ro_fifo.png 2>e && cmp -s ro_file.png ro_fifo.png && ok ||
    bad "a FIFO GeoTIFF DEM: $(cat e)"
wait
# A shapefile: the .shp and its sidecars each opened once, all registered
ogr2ogr -q -f "ESRI Shapefile" ro_shp.shp roads_utm.geojson
"$BIN" --quiet --texels 2 dem_f32.tif ro_shp.shp ro_shp.png 2>e && cmp -s ro_file.png ro_shp.png && ok ||
    bad "shapefile roads (sidecars copied with it): $(cat e)"
# the tiles manifest hashes the sidecars GDAL read too (the .dbf holds the tags)
rm -rf ro_shp_t; "$BIN" tiles --quiet --texels 2 dem_f32.tif ro_shp.shp ro_shp_t 2>e &&
    grep -q "\"ROADS sidecar\", \"path\": \"[^\"]*ro_shp.dbf\", \"sha256\": \"$(sha256sum <ro_shp.dbf | cut -c1-64)\"" ro_shp_t/tiles.json && ok ||
    bad "the tiles manifest lists the shapefile's .dbf with its SHA-256: $(cat e)"
cp ro_shp.prj ro_prj.keep; rm -f ro_shp.png
"$BIN" --quiet --texels 2 --world-file dem_f32.tif ro_shp.shp ro_shp.png 2>e
grep -q "ro_shp.prj: .* is also the ROADS sidecar" e && cmp -s ro_shp.prj ro_prj.keep && [ ! -e ro_shp.png ] && ok ||
    bad "--world-file's .prj over the shapefile's own .prj refused: $(cat e)"
# By construction: under strace, every input name is opened exactly once, so
# no later open can find another file there (a file replaced between two
# opens was loaded from one inode and registered and hashed from another).
if command -v strace >/dev/null 2>&1 && strace -f -o /dev/null true 2>/dev/null; then
    # LeakSanitizer cannot run under ptrace (make sanitize-test): leaks are checked by the other runs
    ro_asan=${ASAN_OPTIONS-}; ASAN_OPTIONS=${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0; export ASAN_OPTIONS
    strace -f -qq -e trace=open,openat -o ro_trace "$BIN" --quiet --texels 2 dem_f32.tif ro_shp.shp ro_st.png 2>e
    for f in dem_f32.tif ro_shp.shp ro_shp.shx ro_shp.dbf ro_shp.prj; do
        n=$(grep -c "\"$f\"" ro_trace)
        [ "$n" = 1 ] && ok || bad "$f opened $n times (once expected): $(grep "\"$f\"" ro_trace | head -5)"
    done
    # Replaced right after the k-th open of its name (strace holds every later
    # open of it 0.3 s; the file is renamed over in the meantime): the run
    # fails naming the replacement, or its tiles are the picture of the
    # file whose SHA-256 the manifest gives. A VRT (GDAL opens its name) and
    # a GeoTIFF (a copy of the descriptor's bytes).
    sed 's/500000, 2, 0, 5000080/500010, 2, 0, 5000090/' dem_ok.vrt >ro_b.vrt
    gdal_translate -q ro_b.vrt ro_b.tif
    shas() { (cd "$1" && find . -name '*.png' | sort | xargs sha256sum); }
    cnt() { n=0; [ -f "$2" ] && n=$(grep -c -- "$1" "$2"); echo "${n:-0}"; }
    for pair in "dem_ok.vrt ro_b.vrt vrt" "dem_f32.tif ro_b.tif tif"; do
        set -- $pair
        rm -rf ro_ra ro_rb
        "$BIN" tiles --quiet --texels 2 "$1" roads_utm.geojson ro_ra 2>e && "$BIN" tiles --quiet --texels 2 "$2" \
            roads_utm.geojson ro_rb 2>>e || bad "race references: $(cat e)"
        sa=$(sha256sum <"$1" | cut -c1-64) sb=$(sha256sum <"$2" | cut -c1-64)
        shas ro_ra >ro_sa; shas ro_rb >ro_sb
        cmp -s ro_sa ro_sb && bad "race: the two DEMs give the same tiles"
        k=1 bad0=$fail
        while [ $k -le 8 ]; do
            rm -rf ro_out ro_log; cp "$1" "ro_in.$3"
            strace -f -qq -o ro_log -P "ro_in.$3" -e trace=open,openat -e inject=openat:delay_enter=300000:when=2+ \
                "$BIN" tiles --quiet --texels 2 "ro_in.$3" roads_utm.geojson ro_out 2>e & sp=$!
            w=0
            while [ "$(cnt "ro_in.$3" ro_log)" -lt $k ] && kill -0 $sp 2>/dev/null && [ $w -lt 500 ]; do
                sleep 0.01; w=$((w + 1))
            done
            opened=$(cnt "ro_in.$3" ro_log)
            cp "$2" ro_new && mv ro_new "ro_in.$3"
            wait $sp; rc=$?
            if [ $rc = 0 ]; then
                m=$(python3 -c "import json; print([i['sha256'] for i in json.load(open('ro_out/tiles.json'))['inputs'] if i['role'] == 'DEM'][0])")
                shas ro_out >ro_so
                if [ "$m" = "$sa" ]; then cmp -s ro_so ro_sa || bad "$3, replaced after open $k: the manifest names the first file, the tiles are not its picture"
                elif [ "$m" = "$sb" ]; then cmp -s ro_so ro_sb || bad "$3, replaced after open $k: the manifest names the second file, the tiles are not its picture"
                else bad "$3, replaced after open $k: the manifest hash is neither file's"; fi
            else
                grep -q "was replaced while it was read" e || bad "$3, replaced after open $k: exit $rc: $(cat e)"
            fi
            [ "$opened" -lt $k ] && break # the run ended before a k-th open
            k=$((k + 1))
        done
        [ $fail = $bad0 ] && ok
    done
    ASAN_OPTIONS=$ro_asan
else
    echo "SKIP cli gdal: strace is missing or cannot trace here: the open-once and replacement checks not run"
fi

echo "cli_gdal: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
