#!/bin/sh
# Issue 28: real OSM and GIS data give the right picture first time.
# An OSM extract (highway ways with their tags in other_tags, a fence, a
# river, a railway, a proposed road, crossing nodes) exported to GeoJSON with
# ogr2ogr as a user would, over a 90 m UTM GeoTIFF DEM with an 88 m hill,
# both made here. Checks OSM semantics (only highway=* ways, other_tags,
# crossings, width units, the skipped counts), --pixel-size and the window
# limit, the absolute terrain colour (crops and tiles, --color-relief) and
# the warnings (camera far off, PGM without --cell-size, world files, the
# PNG's .aux.xml, the COG's colour bands).
# Usage: sh tests/cli_osm_test.sh PATH/TO/roadsplat. Prints "N passed, N failed".
BIN=${1:?usage: cli_osm_test.sh ROADSPLAT}
. "$(dirname "$0")/cli_lib.sh"

need_gdal cli_osm "$BIN" gdal_translate gdalbuildvrt ogr2ogr gdaltransform gdalinfo python3
BIN=$(cd "$(dirname "$BIN")" && pwd)/$(basename "$BIN")
PNGPY=$(cd "$(dirname "$0")" && pwd)/png_read.py
cd "$T" || exit 1
# json FILE EXPR: the python expression on the JSON file j is true
json() { python3 -c "import json, sys; j = json.load(open(sys.argv[1])); sys.exit(0 if ($2) else 1)" "$1"; }
# px FILE X Y: "R G B" of a PNG pixel (tests/png_read.py's decoder)
px() { python3 -c "import sys; sys.path.insert(0, sys.argv[1].rsplit('/', 1)[0]); import png_read
w, h, c, d = png_read.read(sys.argv[2]); i = (int(sys.argv[4]) * w + int(sys.argv[3])) * c
print(' '.join(str(v) for v in d[i:i + 3]))" "$PNGPY" "$@"; }

# ---- data -------------------------------------------------------------------
# A 41 x 31 DEM of 90 m cells in UTM 32N (an SRTM-like grid): the corner at
# (500000, 5002790), a plain at 50 m with an 88 m hill (138 m) at column 30,
# row 10.
python3 - <<'PY'
import math
W, H, cs = 41, 31, 90
with open('dem.asc', 'w') as f:
    f.write("ncols %d\nnrows %d\nxllcorner 500000\nyllcorner 5000000\ncellsize %d\n" % (W, H, cs))
    for i in range(H):
        f.write(" ".join("%.3f" % (50 + 88 * math.exp(-((j - 30) ** 2 + (i - 10) ** 2) / 12.0)) for j in range(W)) + "\n")
PY
gdal_translate -q -a_srs EPSG:32632 -ot Float32 dem.asc dem.tif
# two tiles of it sharing the sample column 28, on the hill's flank
gdal_translate -q -srcwin 0 0 29 31 dem.tif west.tif
gdal_translate -q -srcwin 28 0 13 31 dem.tif east.tif
gdalbuildvrt -q mosaic.vrt west.tif east.tif
# An OSM extract in WGS84 (node positions from UTM through gdaltransform):
# Main (residential, lanes/oneway/turn:lanes/width only in other_tags once
# exported), a footway and a service road ending on it, a track 12' wide, a
# footway 3.5 ft wide, a fence, a river, a railway, a proposed road; a
# marked crossing and a signal crossing on Main.
ll() { echo "$1 $2" | gdaltransform -s_srs EPSG:32632 -t_srs EPSG:4326 | awk '{ printf "lat=\"%.10f\" lon=\"%.10f\"", $2, $1 }'; }
cat >ext.osm <<O
<?xml version="1.0" encoding="UTF-8"?>
<osm version="0.6" generator="roadsplat test">
  <node id="1" version="1" $(ll 500500 5001400)/>
  <node id="2" version="1" $(ll 501000 5001400)><tag k="highway" v="crossing"/><tag k="crossing" v="marked"/></node>
  <node id="3" version="1" $(ll 501500 5001400)/>
  <node id="4" version="1" $(ll 502000 5001400)><tag k="highway" v="crossing"/><tag k="crossing" v="traffic_signals"/></node>
  <node id="5" version="1" $(ll 502500 5001400)/>
  <node id="6" version="1" $(ll 503000 5001400)/>
  <node id="7" version="1" $(ll 501500 5001000)/>
  <node id="8" version="1" $(ll 502500 5001000)/>
  <node id="9" version="1" $(ll 500500 5000500)/>
  <node id="20" version="1" $(ll 503000 5000500)/>
  <node id="21" version="1" $(ll 500500 5002000)/>
  <node id="22" version="1" $(ll 503000 5002000)/>
  <node id="23" version="1" $(ll 500500 5002500)/>
  <node id="24" version="1" $(ll 503000 5002500)/>
  <node id="25" version="1" $(ll 500500 5000200)/>
  <node id="26" version="1" $(ll 503000 5000200)/>
  <way id="10" version="1"><nd ref="1"/><nd ref="2"/><nd ref="3"/><nd ref="4"/><nd ref="5"/><nd ref="6"/>
    <tag k="highway" v="residential"/><tag k="name" v="Main"/><tag k="lanes" v="2"/><tag k="oneway" v="yes"/>
    <tag k="turn:lanes" v="left|through"/></way>
  <way id="11" version="1"><nd ref="7"/><nd ref="3"/><tag k="highway" v="footway"/></way>
  <way id="12" version="1"><nd ref="8"/><nd ref="5"/><tag k="highway" v="service"/></way>
  <way id="13" version="1"><nd ref="9"/><nd ref="20"/><tag k="highway" v="track"/><tag k="width" v="12'"/></way>
  <way id="14" version="1"><nd ref="21"/><nd ref="22"/><tag k="barrier" v="fence"/></way>
  <way id="15" version="1"><nd ref="23"/><nd ref="24"/><tag k="waterway" v="river"/></way>
  <way id="16" version="1"><nd ref="25"/><nd ref="26"/><tag k="railway" v="rail"/></way>
  <way id="17" version="1"><nd ref="21"/><nd ref="24"/><tag k="highway" v="proposed"/></way>
  <way id="18" version="1"><nd ref="9"/><nd ref="1"/><tag k="highway" v="footway"/><tag k="width" v="3.5 ft"/></way>
</osm>
O
# what a user does: ogr2ogr to GeoJSON (lines and the crossing points in one layer)
ogr2ogr -q -f GeoJSON lines.geojson ext.osm lines && ogr2ogr -q -f GeoJSON points.geojson ext.osm points &&
python3 - <<'PY' || echo "FAIL: the OSM GeoJSON export"
import json
l, p = json.load(open('lines.geojson')), json.load(open('points.geojson'))
l['features'] += p['features']
open('ext.geojson', 'w').write(json.dumps(l))
PY
grep -q '"other_tags": "\\"lanes\\"=>\\"2\\"' ext.geojson && ok || bad "ogr2ogr kept lanes in other_tags: $(head -c 600 ext.geojson)"

# ---- 1. OSM semantics -------------------------------------------------------
"$BIN" convert --dem dem.tif ext.geojson ext.txt 2>e && ok || bad "convert: $(cat e)"
n=$(grep -c '^road ' ext.txt)
[ "$n" = 5 ] && ok || bad "5 highway ways are roads, got $n: $(grep '^road ' ext.txt)"
grep -q '^road "Main" class=residential lanes=2 oneway=yes turn:lanes="left|through"$' ext.txt && ok ||
    bad "Main's tags from other_tags: $(grep '^road "Main"' ext.txt)"
grep -q '^road "way13" width 3.6576 class=track$' ext.txt && ok || bad "width 12': $(grep way13 ext.txt)"
grep -q '^road "way18" width 1.0668 class=footway$' ext.txt && ok || bad "width 3.5 ft: $(grep way18 ext.txt)"
grep -Eq 'fence|river|rail|proposed|way1[4-7]' ext.txt && bad "a non-road way became a road" || ok
# the marked crossing is a zebra on Main's second point, the signal crossing is not drawn
[ "$(grep -c '^[0-9].*crossing=zebra' ext.txt)" = 1 ] &&
    awk '$3 == "crossing=zebra" { d = ($1 - 501000) ^ 2 + ($2 - 5001400) ^ 2; exit !(d < 1e-4) }' ext.txt && ok ||
    bad "crossing=marked: $(grep -n crossing ext.txt)"
grep -q "from 11 features (skipped: 2 not lines, 1 not roads, 3 without highway" ext.txt && grep -q "1 traffic_signals, 0 unmarked" ext.txt &&
    ok || bad "convert's counts: $(grep '^#' ext.txt)"
# the splat: one stderr line on the skipped ways, the counts in --stats; the
# footway ending on Main gives no give-way line, the service road does, and
# the zebra: 2 automatic markings
W="--window-world 500900,5000900,502700,5001500"
"$BIN" --quiet --pixel-size 2 $W --stats s1.json dem.tif ext.geojson o1.png 2>e1 && ok || bad "OSM splat: $(cat e1)"
"$BIN" --pixel-size 2 $W dem.tif ext.geojson o1b.png 2>e1b
grep -q "^roadsplat: note: ext.geojson: 5 roads from 11 features; skipped 3 ways without highway=\* .* and 1 whose highway= is not a road$" e1b &&
    ok || bad "the skipped-ways line: $(cat e1b)"
json s1.json "j['roads_source']['skipped_no_highway'] == 3 and j['roads_source']['skipped_not_road'] == 1 and j['roads_source']['roads'] == 5 and j['roads_source']['crossings']['traffic_signals'] == 1 and j['roads_source']['crossings']['zebra_points'] == 1" &&
    ok || bad "--stats roads_source: $(grep -A2 roads_source s1.json)"
# (issue 27: the zebra and the give-way line are rows of elements, each counted: 7 in all)
json s1.json "j['markings']['auto'] == 7" && ok || bad "automatic markings: zebra + the service road's give-way only: $(grep markings s1.json)"
# --where still selects any feature (the river as a 5.5 m road)
"$BIN" convert --dem dem.tif --where "waterway = 'river'" ext.geojson river.txt 2>e &&
    [ "$(grep -c '^road ' river.txt)" = 1 ] && grep -q '^road "way15" width 5.5$' river.txt && ok ||
    bad "--where picks the river: $(cat e; grep '^road' river.txt)"
# hstore quoting: escaped quotes and backslashes before the key wanted
cat >esc.geojson <<'J'
{"type": "FeatureCollection",
 "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::32632"}},
 "features": [
  {"type": "Feature", "properties": {"highway": "service", "other_tags": "\"description\"=>\"a \\\"q\\\" => \\\\ \\\"oneway\\\"=>\\\"no\\\"\", \"oneway\"=>\"-1\",\"width\"=>\"3,5 m\""},
   "geometry": {"type": "LineString", "coordinates": [[501000, 5001000], [501100, 5001000]]}}
 ]}
J
"$BIN" convert esc.geojson esc.txt 2>e && grep -q '^road "feature0" width 3.5 class=service oneway=-1$' esc.txt && ok ||
    bad "other_tags with escapes: $(cat e; grep '^road' esc.txt)"

# tunnels, roundabouts, priority roads, bridges and layers: a tunnel is
# under the ground (not on the texture: skipped and counted), a building
# passage is not; junction=, priority_road=, bridge= and layer= (-5..5)
# come through for the network and the line cuts (docs/gis.md)
cat >lay.osm <<O
<?xml version="1.0" encoding="UTF-8"?>
<osm version="0.6" generator="roadsplat test">
  <node id="1" version="1" $(ll 501000 5001000)/>
  <node id="2" version="1" $(ll 501100 5001000)/>
  <node id="3" version="1" $(ll 501100 5001100)/>
  <node id="4" version="1" $(ll 501000 5001100)/>
  <node id="5" version="1" $(ll 501200 5001000)/>
  <node id="6" version="1" $(ll 501200 5001100)/>
  <way id="30" version="1"><nd ref="1"/><nd ref="2"/><nd ref="3"/><nd ref="4"/><nd ref="1"/>
    <tag k="highway" v="tertiary"/><tag k="junction" v="roundabout"/></way>
  <way id="31" version="1"><nd ref="2"/><nd ref="5"/><tag k="highway" v="primary"/><tag k="tunnel" v="yes"/></way>
  <way id="32" version="1"><nd ref="5"/><nd ref="6"/><tag k="highway" v="secondary"/><tag k="bridge" v="yes"/>
    <tag k="layer" v="1"/><tag k="priority_road" v="designated"/></way>
  <way id="33" version="1"><nd ref="3"/><nd ref="6"/><tag k="highway" v="residential"/><tag k="layer" v="-1"/></way>
  <way id="34" version="1"><nd ref="4"/><nd ref="6"/><tag k="highway" v="service"/><tag k="tunnel" v="building_passage"/>
    <tag k="layer" v="12"/></way>
  <way id="35" version="1"><nd ref="1"/><nd ref="5"/><tag k="highway" v="track"/><tag k="tunnel" v="culvert"/></way>
</osm>
O
ogr2ogr -q -f GeoJSON lay.geojson lay.osm lines 2>e || bad "ogr2ogr lay.osm: $(cat e)"
"$BIN" convert --dem dem.tif lay.geojson lay.txt 2>e && ok || bad "convert lay.geojson: $(cat e)"
grep -q '^road "way30" class=tertiary junction="roundabout"$' lay.txt && ok || bad "junction=roundabout: $(grep way30 lay.txt)"
grep -q '^road "way32" class=secondary priority_road="designated" bridge="yes" layer=1$' lay.txt && ok ||
    bad "bridge, layer, priority_road: $(grep way32 lay.txt)"
grep -q '^road "way33" class=residential layer=-1$' lay.txt && ok || bad "layer=-1: $(grep way33 lay.txt)"
grep -q '^road "way34" class=service$' lay.txt && ok || bad "a building passage is drawn, layer=12 dropped: $(grep way34 lay.txt)"
grep -Eq 'way31|way35' lay.txt && bad "a tunnel became a road: $(grep -E 'way31|way35' lay.txt)" || ok
grep -q "from 6 features (skipped: 0 not lines, 0 not roads, 0 without highway, 2 tunnels, " lay.txt && ok ||
    bad "convert's tunnel count: $(grep '^# ' lay.txt)"
"$BIN" --pixel-size 2 --stats s1b.json dem.tif lay.geojson o1c.png 2>e1c &&
    grep -q "^roadsplat: note: lay.geojson: 4 roads from 6 features; .*, and 2 in tunnels (under the ground)$" e1c &&
    json s1b.json "j['roads_source']['skipped_tunnel'] == 2" && ok || bad "the tunnel note and --stats: $(cat e1c)"

# ---- 2. pixel size -----------------------------------------------------------
"$BIN" --pixel-size 0.1 --window-world 501480,5001380,501520,5001420 --stats s2.json dem.tif ext.geojson o2.png 2>e &&
    json s2.json "j['pixel_size_m'] == 0.1 and j['window']['width'] == 400 and j['window']['height'] == 400 and j['texels'] == 900" &&
    ok || bad "--pixel-size 0.1 with --window-world: $(cat e; head -3 s2.json)"
rm -f o3.png
"$BIN" --quiet --pixel-size 0.1 dem.tif ext.geojson o3.png 2>e; rc=$?
[ $rc = 1 ] && [ ! -e o3.png ] && [ "$(wc -l <e)" = 1 ] &&
    grep -q "36000 x 27000 pixels of 0.1 m exceeds the limit .* --window-world .* 'roadsplat tiles'" e && ok ||
    bad "the limit message: rc $rc: $(cat e)"
"$BIN" --window-world 501000,5001000,501100,5001100 --stats s4.json dem.tif ext.geojson o4.png 2>e &&
    grep -q "^roadsplat: note: dem.tif: 1 m pixels (90 per 90 m DEM cell); choose with --pixel-size M$" e &&
    json s4.json "j['pixel_size_m'] == 1" && ok || bad "the default pixel size: $(cat e)"
"$BIN" --quiet --pixel-size 0.7 --window-world 501000,5001000,501100,5001100 dem.tif ext.geojson o5.png 2>e; rc=$?
[ $rc = 0 ] && ok || bad "--pixel-size 0.7: $(cat e)"
"$BIN" --pixel-size 0.7 --window-world 501000,5001000,501100,5001100 dem.tif ext.geojson o5.png 2>e &&
    grep -q "note: --pixel-size 0.7: pixels are 0.697674419 m (129 per 90 m DEM cell" e && ok || bad "rounded --pixel-size: $(cat e)"
"$BIN" --quiet --pixel-size 1 --texels 4 dem.tif ext.geojson o6.png 2>e; rc=$?
[ $rc = 1 ] && grep -q "give one" e && ok || bad "--pixel-size with --texels: $(cat e)"

# ---- 3. absolute terrain colour ---------------------------------------------
R="$BIN --quiet --texels 4 --no-markings"
$R dem.tif ext.geojson whole.png 2>e && $R west.tif ext.geojson west.png 2>>e && $R east.tif ext.geojson east.png 2>>e &&
    ok || bad "tiles: $(cat e)"
# every pixel of each tile but those of its cells on the shared edge (their
# hillshade reads samples past it, which a tile does not hold) is the whole
# map's, roads and their asphalt grain included
python3 - "$PNGPY" <<'PY' && ok || bad "tiles against the whole map (above)"
import sys
sys.path.insert(0, sys.argv[1].rsplit('/', 1)[0])
import png_read
W, H, ch, whole = png_read.read('whole.png')
bad = edge = 0
for name, x0, skip in (('west.png', 0, range(108, 112)), ('east.png', 112, range(0, 4))):
    w, h, c, t = png_read.read(name)
    for y in range(h):
        for x in range(w):
            i, j = (y * w + x) * c, (y * W + x0 + x) * ch
            same = t[i:i + 3] == whole[j:j + 3]
            if x in skip: edge += not same
            else: bad += not same
print("tiles: %d pixels differ from the whole map off the shared edge, %d in its cells" % (bad, edge))
sys.exit(bad != 0)
PY
# the mosaic's tiles, each rendered by --window-world, are the whole map's crops
$R --window-world 500045,5000045,502565,5002745 mosaic.vrt ext.geojson mw.png 2>e &&
    $R --window 0,0,112,120 dem.tif ext.geojson ww.png 2>>e && cmp -s mw.png ww.png && ok ||
    bad "a tile of the mosaic by --window-world: $(cat e)"
# an 88 m hill over a 50 m plain is green, not snow; the plain is the same green in both tiles
top=$(px whole.png 122 42); set -- $top
[ "$2" -gt "$1" ] && [ "$2" -gt "$3" ] && [ "$1" -lt 160 ] && ok || bad "the hill top is not green: $top"
[ "$(px west.png 20 100)" = "$(px east.png 20 100)" ] && ok || bad "the plain differs between tiles: $(px west.png 20 100) / $(px east.png 20 100)"
# --color-relief: gdaldem's format, heights in metres, any order; the plain at 50 m
printf '# a red-blue ramp\n1000 0 0 255\n0,255,0,0\nnv 0 0 0 0\n' >relief.txt
$R --color-relief relief.txt west.tif ext.geojson cr.png 2>e && [ "$(px cr.png 20 100)" = "242 0 13" ] && ok ||
    bad "--color-relief: $(cat e) $(px cr.png 20 100)"
printf '0 0 0 0\n50%% 255 255 255\n' >pct.txt
$R --color-relief pct.txt west.tif ext.geojson cr2.png 2>e; rc=$?
[ $rc = 1 ] && grep -q "pct.txt line 2: '50%' is a percentage" e && ok || bad "--color-relief percentages: $(cat e)"

# ---- 6. warnings --------------------------------------------------------------------
# a PGM without --cell-size whose roads are wider than 4 (default 1 m) cells
printf 'P2\n21 21\n255\n' >p.pgm
awk 'BEGIN { for (i = 0; i < 441; i++) printf "%d%s", 100, (i % 21 == 20) ? "\n" : " " }' >>p.pgm
printf 'road a width 6\n0 10\n20 10\nend\nroad b width 7\n10 0\n10 20\nend\n' >wide.txt
"$BIN" --quiet p.pgm wide.txt pw.png 2>e && grep -q "warning: p.pgm: no --cell-size" e && ok || bad "PGM without --cell-size: $(cat e)"
"$BIN" --quiet --cell-size 5 p.pgm wide.txt pw.png 2>e && [ ! -s e ] && ok || bad "PGM with --cell-size: $(cat e)"
# world files for a PGM with --origin and world roads (no CRS: no .prj, no .aux.xml)
printf 'frame world\nroad a width 4\n1005 1990\n1095 1990\nend\n' >wroads.txt
"$BIN" --quiet --cell-size 5 --texels 2 --origin 1000,2000 --world-file p.pgm wroads.txt pg.png 2>e &&
    [ "$(tr '\n' ' ' <pg.pgw)" = "2.5 0 0 -2.5 1001.25 1998.75 " ] && [ ! -e pg.prj ] && [ ! -e pg.png.aux.xml ] && ok ||
    bad "world file for a PGM: $(cat e; cat pg.pgw 2>&1)"
# GDAL reads a PNG's CRS from OUT.png.aux.xml
"$BIN" --quiet --texels 2 --world-file dem.tif ext.geojson geo.png 2>e && gdalinfo geo.png >gi.txt &&
    grep -q 'ID\["EPSG",32632\]' gi.txt && grep -q "Origin = (500045.0*,5002745.0*)" gi.txt && ok ||
    bad "the PNG's .aux.xml: $(cat e; grep -E 'Origin|EPSG' gi.txt | head -3)"
# the COG's bands say what they hold
"$BIN" --quiet --texels 2 --cog dem.tif ext.geojson cog.tif 2>e && gdalinfo cog.tif >ci.txt &&
    grep -q "ColorInterp=Red" ci.txt && grep -q "ColorInterp=Alpha" ci.txt && ok || bad "COG ColorInterp: $(grep ColorInterp ci.txt)"
# a render camera far off the map (degrees, local numbers, another place): a warning from 10
# map sizes (here 60 km off a 3.6 km map; the old threshold, 1000 map sizes, let it pass)
if "$BIN" render --help >/dev/null 2>&1; then
    "$BIN" render --quiet --texels 1 --size 64x48 --camera 9.0,45.1,500 --look-at 501800,5001400,50 dem.tif ext.geojson r.png 2>e
    grep -q "warning: --camera 9,45.1 is far off the map dem.tif" e && ok || bad "render camera in degrees: $(cat e)"
    "$BIN" render --quiet --texels 1 --size 64x48 --camera 561800,5001400,500 --look-at 501800,5001400,50 dem.tif ext.geojson r.png 2>e
    grep -q "warning: --camera 561800,5001400 is far off the map dem.tif" e && ok || bad "render camera 60 km off: $(cat e)"
else
    echo "SKIP cli osm: render (no OSMesa)"
fi

echo "cli_osm: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
