#!/bin/sh
# CLI tests for `roadsplat render` (OSMesa). Usage: sh tests/cli_render_test.sh PATH/TO/roadsplat
# Prints "N passed, N failed"; exits non-zero on any failure. Skips (0 passed,
# 0 failed) when the binary was built without OSMesa.
BIN=${1:?usage: cli_render_test.sh ROADSPLAT}
. "$(dirname "$0")/cli_lib.sh"
# Under the sanitizers: LeakSanitizer's tracer crashes (SIGSEGV, "does not
# work under ptrace") reading the static TLS of OSMesa's llvmpipe threads in
# some renders; skip TLS scanning here. That can only report pointers held in
# TLS as leaks (thread-local state of glibc and glib, suppressed in
# tests/lsan.supp), never hide one.
if [ -n "${SAN:-}" ]; then LSAN_OPTIONS="${LSAN_OPTIONS:+$LSAN_OPTIONS:}use_tls=0"; export LSAN_OPTIONS; fi

if "$BIN" render --help 2>&1 | grep -q "no OSMesa support"; then
    echo "cli_render: skipped: $BIN was built without OSMesa (WITH_OSMESA=0)"
    echo "cli_render: 0 passed, 0 failed"
    exit 0
fi
if ! command -v python3 >/dev/null 2>&1; then
    echo "cli_render: skipped: python3 is needed to read the PNGs"
    echo "cli_render: 0 passed, 0 failed"
    exit 0
fi

# Image checks on tests/png_read.py's decoder.
cat > "$T/png.py" <<'PY'
import sys
from png_read import read as decode
def read(path):
    w, h, ch, out = decode(path)
    rgb = [tuple(out[(y * w + x) * ch:(y * w + x) * ch + 3]) if ch >= 3 else (out[y * w + x],) * 3
           for y in range(h) for x in range(w)]
    return w, h, rgb
def px(img, x, y): return img[2][y * img[0] + x]
def lum(c): return 0.299 * c[0] + 0.587 * c[1] + 0.114 * c[2]
cmd = sys.argv[1]
if cmd == 'size':  # file W H
    w, h, _ = read(sys.argv[2]); sys.exit(0 if (w, h) == (int(sys.argv[3]), int(sys.argv[4])) else 1)
if cmd == 'mad':  # a b limit: mean absolute RGB difference <= limit/255
    A, B = read(sys.argv[2]), read(sys.argv[3])
    if A[:2] != B[:2]: print('sizes differ', A[:2], B[:2]); sys.exit(1)
    s = sum(abs(p - q) for a, b in zip(A[2], B[2]) for p, q in zip(a, b)) / (3.0 * len(A[2]))
    print('mean abs diff %.4f / 255' % s); sys.exit(0 if s <= float(sys.argv[4]) else 1)
if cmd == 'band':  # a b y0 y1 limit: rows [y0, y1) of a and b within limit/255 on RGB
    A, B = read(sys.argv[2]), read(sys.argv[3]); y0, y1 = int(sys.argv[4]), int(sys.argv[5])
    if A[:2] != B[:2]: print('sizes differ', A[:2], B[:2]); sys.exit(1)
    w = A[0]; m = max(abs(p - q) for y in range(y0, y1) for x in range(w)
                      for p, q in zip(A[2][y * w + x], B[2][y * w + x]))
    print('rows %d..%d: max diff %d / 255' % (y0, y1 - 1, m)); sys.exit(0 if m <= int(sys.argv[6]) else 1)
if cmd == 'sky':  # the top rows are sky blue; the bottom centre (or row fraction argv[3]) is terrain
    img = read(sys.argv[2]); w, h = img[:2]
    top = [px(img, x, y) for y in range(3) for x in range(0, w, 7)]
    sky = all(c[2] > c[0] + 20 and c[2] >= c[1] for c in top)
    b = px(img, w // 2, int(float(sys.argv[3]) * (h - 1)) if len(sys.argv) > 3 else h - 2)  # a terrain probe
    print('top', top[0], 'bottom', b)
    haze = sum(abs(p - q) for p, q in zip(b, (158, 168, 178))) > 40  # not the below-horizon haze
    sys.exit(0 if sky and haze and not (b[2] > b[0] + 20 and b[2] >= b[1]) else 1)
if cmd == 'road':  # straight-down view of an east-west road through the centre row
    img = read(sys.argv[2]); w, h = img[:2]; r = int(sys.argv[3])
    def row(y): return sum(lum(px(img, x, y)) for x in range(w // 4, 3 * w // 4)) / (w // 2)
    road = max(row(h // 2 + d) for d in range(-r, r + 1))
    land = min(row(h // 2 - 3 * r), row(h // 2 + 3 * r))
    edge = row(h // 2 - 2 * r), row(h // 2 + 2 * r)
    print('road row lum <= %.1f, terrain rows >= %.1f, +-2r rows %.1f %.1f' % (road, land, edge[0], edge[1]))
    # the absolute tint (issue 28) paints this 15..27 m terrain lowland green (luminance
    # about 97, before: the palette spread over its range, brighter): 20 levels apart
    sys.exit(0 if road < 90 and land > road + 20 and min(edge) > road + 20 else 1)
if cmd == 'ramp':  # file: the widest 10-90 % transition at the road edge and at the line's rising side
    # along the centre row of a close-up (docs/render.md "Shader mode"); argv[3], argv[4]: the road
    # and line levels (luminance) the transitions run to; prints both widths in pixels
    img = read(sys.argv[2]); w, h = img[:2]; R, W = float(sys.argv[3]), float(sys.argv[4])
    L = [lum(px(img, x, h // 2)) for x in range(w)]
    A = L[0]
    xe = next(x for x in range(w) if L[x] < (A + R) / 2)
    def count(lo, hi, a, b):
        return sum(1 for x in range(max(lo, 0), min(hi, w)) if min(a, b) + 0.1 * abs(b - a) < L[x] < max(a, b) - 0.1 * abs(b - a))
    edge = count(xe - 40, xe + 40, A, R)
    xl = max(range(xe + 45, min(w, xe + 200)), key=lambda x: L[x])
    line = count(xl - 40, xl + 1, R, W)
    print('%d %d' % (edge, line))
    sys.exit(0)
if cmd == 'bright':  # a b level: of b's pixels with every channel >= level, the share that a
    # shows at >= level - 10 (lines drawn in both); prints it, fails below 0.95
    A, B, L = read(sys.argv[2]), read(sys.argv[3]), int(sys.argv[4])
    sel = [i for i, c in enumerate(B[2]) if min(c) >= L]
    share = sum(1 for i in sel if min(A[2][i]) >= L - 10) / max(len(sel), 1)
    print('%d bright pixels, %.4f of them in both' % (len(sel), share)); sys.exit(0 if sel and share >= 0.95 else 1)
if cmd == 'differ':  # two images differ somewhere by more than 8 levels
    A, B = read(sys.argv[2]), read(sys.argv[3])
    sys.exit(0 if any(abs(p - q) > 8 for a, b in zip(A[2], B[2]) for p, q in zip(a, b)) else 1)
PY
TESTS=$(cd "$(dirname "$0")" && pwd)
export PYTHONPATH="$TESTS"
py() { python3 "$T/png.py" "$@"; }

# Scene: 65x49 samples, 2 m cells (128 m x 96 m), a gentle slope with a bump,
# one 12 m wide straight road east-west along y = 48 (the centre row).
awk 'BEGIN { W = 65; H = 49; print "P2"; print W, H; print 1000;
  for (i = 0; i < H; i++) { line = "";
    for (j = 0; j < W; j++) { v = 300 + 2 * j + 150 * exp(-((j - 50) ^ 2 + (i - 10) ^ 2) / 60); line = line " " int(v) }
    print line } }' > "$T/dem.pgm"
printf 'road main width 12\n-10 48\n140 48\nend\n' > "$T/roads.txt"
S="--cell-size 2 --z-scale 0.05 --texels 4"

# ortho cross-check: GL at the splat's resolution reproduces the CPU splat
check "CPU splat exits 0" "$BIN" $S --quiet "$T/dem.pgm" "$T/roads.txt" "$T/splat.png"
check "render --ortho --lighting off exits 0" "$BIN" render $S --quiet --ortho --lighting off "$T/dem.pgm" "$T/roads.txt" "$T/ortho.png"
check "ortho defaults to the splat's size (256x192)" py size "$T/ortho.png" 256 192
check "ortho reproduces the CPU splat (MAD <= 2/255)" py mad "$T/ortho.png" "$T/splat.png" 2
# the same through 64-texel tiles (forced tiling, clipped geometry, bordered tiles)
# markings (issue 14) reach the render: the junction example at 0.4 m pixels,
# GL ortho against the CPU splat, and against the same render without markings
EX="$(dirname "$0")/../docs/examples"
J="--cell-size 2 --z-scale 0.01 --texels 5"
check "junction: CPU splat with markings" "$BIN" $J --quiet "$EX/junction-dem.pgm" "$EX/junction.txt" "$T/jc.png"
check "junction: render --ortho with markings" "$BIN" render $J --quiet --ortho --lighting off "$EX/junction-dem.pgm" "$EX/junction.txt" "$T/jr.png"
check "junction: render --ortho --no-markings" "$BIN" render $J --quiet --ortho --lighting off --no-markings "$EX/junction-dem.pgm" "$EX/junction.txt" "$T/jn.png"
check "junction: the render shows the CPU splat's markings (MAD <= 2/255)" py mad "$T/jr.png" "$T/jc.png" 2
check "junction: without markings the render differs (MAD > 0.3/255)" sh -c "! python3 '$T/png.py' mad '$T/jr.png' '$T/jn.png' 0.3 >/dev/null"
check "tiled upload renders" "$BIN" render $S --quiet --roads texture --ortho --lighting off --tile-size 64 --stats "$T/tile.json" "$T/dem.pgm" "$T/roads.txt" "$T/tiled.png"
check "tiled stats report 5x4 tiles" sh -c "grep -q '\"tiles_x\": 5, \"tiles_y\": 4' '$T/tile.json'"
check "tiled render matches the CPU splat (MAD <= 2/255)" py mad "$T/tiled.png" "$T/splat.png" 2
check "tiled render matches the untiled one (MAD <= 1/255)" py mad "$T/tiled.png" "$T/ortho.png" 1

# Shader mode (issue 15, docs/render.md "Shader mode"). Cross-check: top-down
# orthographic, lighting off, one screen pixel = one splat pixel, with
# styles and markings: the fragment shader's roads equal the CPU splat
# (mean <= 1/255, 99th percentile <= 8/255 on RGB).
DIFF="$TESTS/tools/png_diff.py"
xcheck() { # name a b: mean <= 1, p99 <= 8
    out=$(python3 "$DIFF" "$2" "$3") || return 1
    echo "$1: $out"
    echo "$out" | awk '{ split($1, m, "="); split($2, p, "="); exit !(m[2] <= 1 && p[2] <= 8) }'
}
check "shader: junction ortho renders in shader mode" sh -c "'$BIN' render $J --quiet --ortho --lighting off --stats '$T/js.json' '$EX/junction-dem.pgm' '$EX/junction.txt' '$T/js.png' && grep -q '\"roads\": \"shader\"' '$T/js.json'"
check "shader: junction (styles, markings) equals the CPU splat" xcheck junction "$T/js.png" "$T/jc.png"
# the T rule (docs/network.md): a side road ending on a through road cuts
# only the through road's edge line; close up (0.125 m) the shader keeps the
# centre line across the T as the CPU does (max 89/255 before)
N="--cell-size 2 --z-scale 0.01 --texels 16"
check "shader: T junction close up equals the CPU splat (max <= 8/255)" sh -c "'$BIN' $N --quiet '$EX/junction-dem.pgm' '$EX/network_tee.txt' '$T/tc.png' && '$BIN' render $N --quiet --ortho --lighting off '$EX/junction-dem.pgm' '$EX/network_tee.txt' '$T/ts.png' && python3 '$DIFF' '$T/ts.png' '$T/tc.png' | awk '{ split(\$3, m, \"=\"); exit !(m[2] <= 8) }'"
# crossings of different classes (issue 27 problem 6): the higher road's
# surface, and a footway cuts no car road's lines, in both renders
check "shader: crossings of different classes equal the CPU splat (max <= 8/255)" sh -c "'$BIN' $N --quiet '$EX/junction-dem.pgm' '$EX/network_crossing.txt' '$T/xc.png' && '$BIN' render $N --quiet --ortho --lighting off '$EX/junction-dem.pgm' '$EX/network_crossing.txt' '$T/xs.png' && python3 '$DIFF' '$T/xs.png' '$T/xc.png' | awk '{ split(\$3, m, \"=\"); exit !(m[2] <= 8) }'"
# a roundabout drawn as one closed way (docs/examples/network_ring.txt): an arm
# at its first point, a two-point arm drawn from the ring outwards; the ring's
# inner edge line runs on past both mouths in both renders (the CPU cut it
# across both until 6 December 2026: 183/255 in these columns), and the
# whole picture matches (mean <= 1/255, p99 <= 8/255)
check "shader: a roundabout's inner edge line at its arms equals the CPU splat (max <= 8/255)" sh -c "'$BIN' $N --quiet '$EX/junction-dem.pgm' '$EX/network_ring.txt' '$T/rc.png' && '$BIN' render $N --quiet --ortho --lighting off '$EX/junction-dem.pgm' '$EX/network_ring.txt' '$T/rs.png' && python3 '$DIFF' '$T/rs.png' '$T/rc.png' 400,448,240,400 | awk '{ split(\$3, m, \"=\"); exit !(m[2] <= 8) }' && python3 '$DIFF' '$T/rs.png' '$T/rc.png' 192,240,240,400 | awk '{ split(\$3, m, \"=\"); exit !(m[2] <= 8) }'"
check "shader: a roundabout drawn as one closed way equals the CPU splat" xcheck ring "$T/rs.png" "$T/rc.png"
# joints (RS_GPU_SEG_JOIN_*): a street split into two records at a 20-degree
# bend (the second record's points once each way; the free ends off the map)
# and the roundabout above in three records; the shader mitres and
# round-joins the lines there as the CPU does (each record ended them square until 6 December 2026: 181/255 at
# the bend, 184/255 at the ring's joints); ring1, the roundabout as one
# closed way at 0.1 m: its arms' edge lines stop where the ring's surface
# does in both (the CPU stopped them 0.46 m early until 6 December 2026,
# docs/linesym.md "Junctions": 183/255)
printf '%s\n' 'road a width 7 class=secondary' '-10 40' '40 40' 'end' 'road a width 7 class=secondary' '40 40' '90 21.8' 'end' \
    'road b width 7 class=secondary' '-10 60' '40 60' 'end' 'road b width 7 class=secondary' '90 78.2' '40 60' 'end' > "$T/bend.txt"
awk '/^road ring/ { f = 1; next } f && /^end/ { exit } f { p[++n] = $0 } END { split("1 9 17 " n, b, " "); for (k = 1; k <= 3; k++) { print "road ring width 7 class=secondary junction=roundabout oneway=yes lanes=1"; for (i = b[k]; i <= b[k + 1]; i++) print p[i]; print "end" } }' "$EX/network_ring.txt" > "$T/ring3.txt"
N="--cell-size 2 --z-scale 0.01 --texels 20"
cp "$EX/network_ring.txt" "$T/ring1.txt"
for JT in bend ring3 ring1; do
    check "shader: the lines through the joints of $JT equal the CPU splat (max <= 8/255)" sh -c "'$BIN' $N --quiet '$EX/junction-dem.pgm' '$T/$JT.txt' '$T/${JT}c.png' && '$BIN' render $N --quiet --ortho --lighting off '$EX/junction-dem.pgm' '$T/$JT.txt' '$T/${JT}s.png' && python3 '$DIFF' '$T/${JT}s.png' '$T/${JT}c.png' | awk '{ split(\$3, m, \"=\"); exit !(m[2] <= 8) }'"
done
# the junction example close up (0.1 m: lanes, stop and give-way lines, the
# zebra's line cuts, strokes through the crossing): max 149/255 before the
# cut table's stride and the cuts' reach were fixed
N="--cell-size 2 --z-scale 0.01 --texels 20"
check "shader: junction at 0.1 m equals the CPU splat (max <= 8/255)" sh -c "'$BIN' $N --quiet '$EX/junction-dem.pgm' '$EX/junction.txt' '$T/jc2.png' && '$BIN' render $N --quiet --ortho --lighting off '$EX/junction-dem.pgm' '$EX/junction.txt' '$T/js2.png' && python3 '$DIFF' '$T/js2.png' '$T/jc2.png' | awk '{ split(\$3, m, \"=\"); exit !(m[2] <= 8) }'"
# ends at a T (docs/network.md "Ends at a T"): 15 m roads ending on a 3 m
# street at 90 and 60 degrees, no round cap beyond its far edge; the shader
# trims them as the CPU does (max 182/255 on db31fd7)
awk 'BEGIN { print "P2"; print 51, 16; print 100; for (i = 0; i < 16; i++) { l = ""; for (j = 0; j < 51; j++) l = l " 50"; print l } }' > "$T/caps-dem.pgm"
check "shader: trimmed T ends at 0.1 m equal the CPU splat (max <= 8/255)" sh -c "'$BIN' $N --quiet '$T/caps-dem.pgm' '$EX/network_caps.txt' '$T/kc.png' && '$BIN' render $N --quiet --ortho --lighting off '$T/caps-dem.pgm' '$EX/network_caps.txt' '$T/ks.png' && python3 '$DIFF' '$T/ks.png' '$T/kc.png' | awk '{ split(\$3, m, \"=\"); exit !(m[2] <= 8) }'"
# a free road end's round cap (docs/examples/network_spike.txt: each road
# ends inside the other): the other road's edge line runs on to the cap's
# edge in both renders (the CPU cut it at the square end's corner, 0.6 m
# short, until 6 December 2026: 184/255 in these columns)
check "shader: a round cap cuts another road's edge line where the cap lies, as in the CPU splat (max <= 24/255)" sh -c "'$BIN' $N --quiet '$T/caps-dem.pgm' '$EX/network_spike.txt' '$T/pc.png' && '$BIN' render $N --quiet --ortho --lighting off '$T/caps-dem.pgm' '$EX/network_spike.txt' '$T/ps.png' && python3 '$DIFF' '$T/ps.png' '$T/pc.png' 280,420,0,80 | awk '{ split(\$3, m, \"=\"); exit !(m[2] <= 24) }'"
check "shader: network_spike equals the CPU splat" xcheck spike "$T/ps.png" "$T/pc.png"
# a bridge over a primary (docs/examples/network_bridge.txt, docs/network.md
# "Bridges and layers"): the shader lays the bridge's surface and lines on
# top and stops the primary's lines under it as the CPU does (both cut the
# bridge's edge lines at the primary on one level until 6 December 2026)
awk 'BEGIN { print "P2"; print 51, 31; print 100; for (i = 0; i < 31; i++) { l = ""; for (j = 0; j < 51; j++) l = l " 50"; print l } }' > "$T/bridge-dem.pgm"
check "shader: a bridge's lines over the road below equal the CPU splat (max <= 8/255)" sh -c "'$BIN' $N --quiet '$T/bridge-dem.pgm' '$EX/network_bridge.txt' '$T/brc.png' && '$BIN' render $N --quiet --ortho --lighting off '$T/bridge-dem.pgm' '$EX/network_bridge.txt' '$T/brs.png' && python3 '$DIFF' '$T/brs.png' '$T/brc.png' 440,560,200,400 | awk '{ split(\$3, m, \"=\"); exit !(m[2] <= 8) }'"
check "shader: network_bridge equals the CPU splat" xcheck bridge "$T/brs.png" "$T/brc.png"
# a bridge mapped as OSM maps one, a record between two ground records of
# its stroke (docs/examples/network_overpass.txt): its lines and casing run
# on over the primary in both renders (the CPU cut its lines there and drew
# no casing over the primary until 7 December 2026: max 149/255 against the
# shader then)
check "shader: an overpass's lines and casing over the road below equal the CPU splat (max <= 8/255)" sh -c "'$BIN' $N --quiet '$T/bridge-dem.pgm' '$EX/network_overpass.txt' '$T/ovc.png' && '$BIN' render $N --quiet --ortho --lighting off '$T/bridge-dem.pgm' '$EX/network_overpass.txt' '$T/ovs.png' && python3 '$DIFF' '$T/ovs.png' '$T/ovc.png' | awk '{ split(\$3, m, \"=\"); exit !(m[2] <= 8) }'"
# the primary's words under the bridge's deck (docs/network.md "Bridges and
# layers"): left out on the deck by both renders, the one out from under it
# cut at the deck's edge (both painted them on the deck until 6 December 2026)
{ cat "$EX/network_bridge.txt"; printf 'mark word_bus road=Hauptstr s=44 t=-2.2 length=6 width=2\nmark word_slow road=Hauptstr s=48 t=2.2 length=6 width=2 flip\n'; } > "$T/bridge-marks.txt"
check "shader: a road's markings under a bridge's deck equal the CPU splat (max <= 8/255)" sh -c "'$BIN' $N --quiet '$T/bridge-dem.pgm' '$T/bridge-marks.txt' '$T/bmc.png' && '$BIN' render $N --quiet --ortho --lighting off '$T/bridge-dem.pgm' '$T/bridge-marks.txt' '$T/bms.png' && python3 '$DIFF' '$T/bms.png' '$T/bmc.png' | awk '{ split(\$3, m, \"=\"); exit !(m[2] <= 8) }'"
# a primary of one 396 m segment crossed by 24 secondaries (docs/linesym.md
# "Junctions"): its edge lines stop at every mouth in both renders (the CPU
# drew them on across the mouths past about the eighth until session 44:
# max 92/255 against the shader)
awk 'BEGIN { print "P2"; print 201, 51; print 100; for (i = 0; i < 51; i++) { l = ""; for (j = 0; j < 201; j++) l = l " 50"; print l } }' > "$T/many-dem.pgm"
awk 'BEGIN { print "road main width 9 class=primary area=rural"; print "2 50"; print "398 50"; print "end"; for (i = 0; i < 24; i++) { x = 10 + 16 * i; print "road s" i " width 6 class=secondary area=rural"; print x, 2; print x, 98; print "end" } }' > "$T/many.txt"
N5="--cell-size 2 --z-scale 0.01 --texels 5"
check "shader: a segment crossed by 24 roads has its edge lines cut at every mouth, as in the CPU splat (max <= 8/255)" sh -c "'$BIN' $N5 --quiet '$T/many-dem.pgm' '$T/many.txt' '$T/mc.png' && '$BIN' render $N5 --quiet --ortho --lighting off '$T/many-dem.pgm' '$T/many.txt' '$T/ms.png' && python3 '$DIFF' '$T/ms.png' '$T/mc.png' | awk '{ split(\$3, m, \"=\"); exit !(m[2] <= 8) }'"
# side roads ending on a primary at 30 and 45 degrees (docs/network.md "The
# through road at a T"): the primary's centre line and the band within
# keep of it (rows 138..161 of 300 at 0.1 m) are those of the primary
# alone, in both renders (before 3 December 2026 the side road's cut copy
# ended square to it and its acute corner cut the centre line, max 111/255
# in the shader, and the give-way line stood inside the primary)
head -7 "$EX/network_oblique.txt" | tail -4 > "$T/ob-main.txt"
check "oblique T: CPU splat" sh -c "'$BIN' $N --quiet '$T/caps-dem.pgm' '$EX/network_oblique.txt' '$T/oc.png' && '$BIN' $N --quiet '$T/caps-dem.pgm' '$T/ob-main.txt' '$T/om.png'"
check "oblique T: shader render" sh -c "'$BIN' render $N --quiet --ortho --lighting off '$T/caps-dem.pgm' '$EX/network_oblique.txt' '$T/os.png' && '$BIN' render $N --quiet --ortho --lighting off '$T/caps-dem.pgm' '$T/ob-main.txt' '$T/oms.png'"
check "oblique T: the CPU splat keeps the primary's inner band (max <= 8/255)" py band "$T/oc.png" "$T/om.png" 138 162 8
check "oblique T: the shader keeps the primary's inner band (max <= 8/255)" py band "$T/os.png" "$T/oms.png" 138 162 8
check "oblique T: the shader equals the CPU splat" xcheck oblique "$T/os.png" "$T/oc.png"
# a side road ending where the primary bends (35 degrees): nothing north of
# the primary's far edge (rows 0..59, y < 6 m) in either render (before 3
# December 2026 the shader ran the side road's flat strip on to the line
# parallel to the bend's chord: asphalt up to 1.2 m past the far edge, 53/255)
printf 'road Hauptstr width 7.5 class=primary\n2 10\n45 10\n77.8 33\nend\nroad Nebenstr width 6.5 class=secondary\n45 29\n45 10\nend\n' > "$T/bent.txt"
check "bent T: CPU splat and shader render" sh -c "'$BIN' $N --quiet '$T/caps-dem.pgm' '$T/bent.txt' '$T/bc.png' && '$BIN' render $N --quiet --ortho --lighting off '$T/caps-dem.pgm' '$T/bent.txt' '$T/bs.png'"
check "bent T: no paint past the primary's far edge in the shader (max <= 8/255)" py band "$T/bs.png" "$T/bc.png" 0 60 8
check "bent T: the shader equals the CPU splat" xcheck bent "$T/bs.png" "$T/bc.png"
# a side road whose last point is repeated (a zero-length last segment, as
# OSM exports have) ending at a T: both renders as without the repeat (the
# CPU's T trim once took it as a strip through every point short of its
# clip line: docs/speed.md "Session 25"; the shader's trim gives it a
# direction, read then, tested now)
printf 'road Hauptstr width 7.5 class=primary\n2 10\n98 10\nend\nroad Nebenstr width 6.5 class=secondary\n45 29\n45 10\nend\nroad Weg width 4 class=residential\n70 29\n70 20\n70 10\nend\n' > "$T/rp-plain.txt"
printf 'road Hauptstr width 7.5 class=primary\n2 10\n98 10\nend\nroad Nebenstr width 6.5 class=secondary\n45 29\n45 10\n45 10\nend\nroad Weg width 4 class=residential\n70 29\n70 20\n70 10\n70 10\nend\n' > "$T/rp-rep.txt"
check "repeated T end: CPU splats and shader renders" sh -c "'$BIN' $N --quiet '$T/caps-dem.pgm' '$T/rp-rep.txt' '$T/rpc.png' && '$BIN' $N --quiet '$T/caps-dem.pgm' '$T/rp-plain.txt' '$T/rpp.png' && '$BIN' render $N --quiet --ortho --lighting off '$T/caps-dem.pgm' '$T/rp-rep.txt' '$T/rps.png' && '$BIN' render $N --quiet --ortho --lighting off '$T/caps-dem.pgm' '$T/rp-plain.txt' '$T/rpq.png'"
check "repeated T end: the CPU splat is the one without the repeat" cmp "$T/rpc.png" "$T/rpp.png"
check "repeated T end: the shader render is the one without the repeat (max <= 1/255)" sh -c "python3 '$DIFF' '$T/rps.png' '$T/rpq.png' | awk '{ split(\$3, m, \"=\"); exit !(m[2] <= 1) }'"
check "repeated T end: the shader equals the CPU splat" xcheck repeated "$T/rps.png" "$T/rpc.png"
C="--cell-size 5 --z-scale 0.01 --texels 4"
check "shader: city CPU splat" "$BIN" $C --quiet "$EX/dem.pgm" "$EX/roads.txt" "$T/cc.png"
# Lit shader mode: the terrain colour comes from the splatter's layers
# (rs_splat_layers_window: the tint alone, at the real heights). Before, the
# bake scaled heights by 1e-12 to drop the hillshade, and the absolute tint
# painted 3000 m ground the colour of 0 m (mean 58 levels from the CPU
# splat here; now 12: the shader's sun is ambient 0.42 + diffuse 0.70).
awk 'BEGIN { print "P2"; print 33, 33; print 3000; for (i = 0; i < 33; i++) { l = ""; for (j = 0; j < 33; j++) l = l " " (j < 16 ? 0 : 3000); print l } }' > "$T/step.pgm"
printf 'road r width 6\n4 40\n60 40\nend\n' > "$T/step.txt"
SO="--cell-size 2 --z-scale 1 --texels 4"
check "shader, lit: the terrain tint follows the heights as the CPU splat's (mean <= 20/255)" sh -c "'$BIN' $SO --quiet --lighting '$T/step.pgm' '$T/step.txt' '$T/stc.png' && '$BIN' render $SO --quiet --ortho '$T/step.pgm' '$T/step.txt' '$T/sts.png' && python3 '$DIFF' '$T/sts.png' '$T/stc.png' | awk '{ split(\$1, m, \"=\"); exit !(m[2] <= 20) }'"
check "shader: city ortho render" "$BIN" render $C --quiet --ortho --lighting off "$EX/dem.pgm" "$EX/roads.txt" "$T/cs.png"
check "shader: city (90 styled roads, casings, joins, crossings) equals the CPU splat" xcheck city "$T/cs.png" "$T/cc.png"
check "shader: --roads texture still reproduces the splat" sh -c "'$BIN' render $J --quiet --roads texture --ortho --lighting off --stats '$T/jt.json' '$EX/junction-dem.pgm' '$EX/junction.txt' '$T/jt.png' && grep -q '\"roads\": \"texture\"' '$T/jt.json' && python3 '$T/png.py' mad '$T/jt.png' '$T/jc.png' 2"
check "shader: bad --roads rejected" sh -c "! '$BIN' render --roads gpu '$T/dem.pgm' '$T/roads.txt' '$T/e.png' 2>'$T/roads.err' && grep -q \"'gpu'\" '$T/roads.err' && test ! -e '$T/e.png'"
# Dense urban roads over a coarse DEM (issue 25 target 3): 8 x 8 samples of
# 90 m (an index cell each), a street every ~45 m (8 m, casing, dashed
# centre line, edge lines) with a sidewalk on each side of every block
# (2.5 m, a dashed 0.5 m line): 30 and more roads share each index cell.
# Before, only the first 8 roads of a cell drew lines and markings (the
# sidewalks' lines vanished) and a pixel took the casing colour of the
# nearest road even when that road had none.
awk 'BEGIN { W = 8; H = 8; print "P2"; print W, H; print 1000;
  for (i = 0; i < H; i++) { l = ""; for (j = 0; j < W; j++) l = l " " int(400 + 30 * sin(i / 2.0) + 20 * cos(j / 3.0)); print l } }' > "$T/dense-dem.pgm"
awk 'BEGIN {
  print "style street\n  casing 0.5 #5A5A5A\n  fill #3A3A3A\n  line 0 0.15 #FFFFFF dash 3 6\n  line 3.2 0.12 #FFFFFF\n  line -3.2 0.12 #FFFFFF\nend"
  print "style walk\n  fill #9A9A90\n  line 0 0.5 #FFFFFF dash 2 2\nend"
  n = 14
  for (k = 0; k < n; k++) c[k] = 20 + 45 * k + 7 * (k % 3)
  c[-1] = -40; c[n] = 690
  # streets with a vertex mid-block, as map data has nodes along a street
  # (the CPU cuts a segment by a few crossing surfaces only, docs/render.md)
  for (k = 0; k < n; k++) {
    printf "road ew%d width 8 style=street\n-20 %g\n", k, c[k]
    for (b = 0; b + 1 < n; b++) printf "%g %g\n", (c[b] + c[b + 1]) / 2, c[k]
    printf "650 %g\nend\n", c[k]
    printf "road ns%d width 8 style=street\n%g -20\n", k, c[k]
    for (b = 0; b + 1 < n; b++) printf "%g %g\n", c[k], (c[b] + c[b + 1]) / 2
    printf "%g 650\nend\n", c[k]
  }
  for (k = 0; k < n; k++)
    for (b = -1; b < n; b++) { # both sides of each block; round ends clear of the streets
      a0 = c[b] + 6.5; a1 = c[b + 1] - 6.5
      for (s = -1; s <= 1; s += 2) {
        printf "road ew%d_%d_%d width 2.5 style=walk\n%g %g\n%g %g\nend\n", k, b, s, a0, c[k] + 6.5 * s, a1, c[k] + 6.5 * s
        printf "road ns%d_%d_%d width 2.5 style=walk\n%g %g\n%g %g\nend\n", k, b, s, c[k] + 6.5 * s, a0, c[k] + 6.5 * s, a1
      }
    }
  print "mark word_bus road=ew3 s=200 t=-2 length=3 width=2"
  print "mark cycle road=ns4 s=300 t=1.5"
}' > "$T/dense.txt"
DN="--cell-size 90 --z-scale 0.1 --texels 90"
check "dense: CPU splat" "$BIN" $DN --quiet "$T/dense-dem.pgm" "$T/dense.txt" "$T/dc.png"
check "dense: shader ortho render" sh -c "'$BIN' render $DN --quiet --ortho --lighting off --stats '$T/ds.json' '$T/dense-dem.pgm' '$T/dense.txt' '$T/ds.png' && grep -q '\"roads\": \"shader\"' '$T/ds.json'"
check "dense: 90 m cells, 30+ roads per cell: the shader equals the CPU splat" xcheck dense "$T/ds.png" "$T/dc.png"
check "dense: every road's lines are drawn (the sidewalks' too)" py bright "$T/ds.png" "$T/dc.png" 195
# the same streets of one segment each (no vertex mid-block): the CPU cuts
# their lines at every crossing as the shader does (mean 0.32/255, p99
# 15/255 until 6 December 2026: a piece stayed whole from about the third
# crossing on; docs/render.md)
awk '/^road (ew|ns)[0-9]+ width 8/ { print; n = 0; st = 1; next } st && /^end/ { print last; print; st = 0; next } st { if (n++ == 0) print; last = $0; next } { print }' "$T/dense.txt" > "$T/dense1.txt"
check "dense, one segment a street: the shader equals the CPU splat" sh -c "'$BIN' $DN --quiet '$T/dense-dem.pgm' '$T/dense1.txt' '$T/d1c.png' && '$BIN' render $DN --quiet --ortho --lighting off '$T/dense-dem.pgm' '$T/dense1.txt' '$T/d1s.png' && python3 '$DIFF' '$T/d1s.png' '$T/d1c.png' | awk '{ split(\$1, m, \"=\"); split(\$2, p, \"=\"); exit !(m[2] <= 0.2 && p[2] <= 2) }'"
# What the shader does not draw goes to the texture mode, with a note
# naming it: the render is then the CPU splat
SF="$EX/surface.txt"
for f in "surface images:--quiet:$SF" "alpha-map road edges:--edges alphamap:$EX/junction.txt" \
         "Hermite line smoothing:--aa hermite:$EX/junction.txt"; do
    what=${f%%:*}; rest=${f#*:}; opt=${rest%%:*}; rt=${rest#*:}
    check "fallback: $what -> texture mode with a note" sh -c "'$BIN' render $J --quiet $opt --ortho --lighting off --stats '$T/fb.json' '$EX/junction-dem.pgm' '$rt' '$T/fb.png' 2>'$T/fb.err' && grep -q '\"roads\": \"texture\"' '$T/fb.json' && grep -q 'shader mode does not draw $what' '$T/fb.err' && test \$(wc -l <'$T/fb.err') -eq 1 && '$BIN' $J --quiet $opt '$EX/junction-dem.pgm' '$rt' '$T/fbc.png' && python3 '$T/png.py' mad '$T/fb.png' '$T/fbc.png' 0.5"
done
# Edge profile: a close-up (2 cm pixels) across a 7 m road with a fill and a
# 0.15 m white lane line; 0.5 m texels. Shader mode: the road edge and the
# line's edge are at most 2 pixels wide; the baked texture blurs both over
# 10 or more.
awk 'BEGIN { print "P2"; print 31, 31; print 100; for (i = 0; i < 31; i++) { l = ""; for (j = 0; j < 31; j++) l = l " 50"; print l } }' > "$T/flat.pgm"
printf 'style lane\n  fill #202020\n  line 1.75 0.15 #FFFFFF\nend\nroad r width 7 style=lane\n20 60\n20 0\nend\n' > "$T/lane.txt"
E="--cell-size 2 --z-scale 0.01 --texels 4 --size 640x480 --fov 45 --camera 20,40,4 --look-at 20,30,0 --lighting off"
check "edge: shader close-up renders" "$BIN" render $E --quiet "$T/flat.pgm" "$T/lane.txt" "$T/es.png"
check "edge: texture close-up renders" "$BIN" render $E --quiet --roads texture "$T/flat.pgm" "$T/lane.txt" "$T/et.png"
ramp_ok() { # file cmp limit: both widths cmp limit
    out=$(python3 "$T/png.py" ramp "$1" 32 255) || return 1
    echo "$1: edge and line transitions $out px"
    echo "$out" | awk -v c="$2" -v l="$3" '{ if (c == "le") exit !($1 <= l && $2 <= l); exit !($1 >= l && $2 >= l) }'
}
check "edge: shader transitions (road edge, 0.15 m line) <= 2 px" ramp_ok "$T/es.png" le 2
check "edge: texture transitions >= 10 px" ramp_ok "$T/et.png" ge 10

# Dashes at a distance (issue 25 target 4, docs/render.md): a driver's eye
# 1.2 m above a dashed centre line (3 m on, 6 m off, 0.15 m, white on
# #404040) over flat ground, 0.1 m texels; tests/tools/dash_range.py gives
# the distance to which the dash/gap contrast along the line stays >= 25 %
# of white against the road's grey (191 levels). Texture mode with
# anisotropic filtering (the GL's maximum by default) and the shader keep
# dashes to >= 40 m; isotropic mip levels lose them near 20 m.
awk 'BEGIN { print "P2"; print 101, 11; print 100; for (i = 0; i < 11; i++) { l = ""; for (j = 0; j < 101; j++) l = l " 50"; print l } }' > "$T/long.pgm"
printf 'style dashed\n  fill #404040\n  line 0 0.15 #FFFFFF dash 3 6\nend\nroad r width 7 style=dashed\n-5 10\n205 10\nend\n' > "$T/long.txt"
DV="--cell-size 2 --z-scale 0.01 --texels 20 --size 1281x721 --fov 40 --camera 0,10,1.7 --look-at 100,10,0.5 --lighting off --quiet"
dash_ge() { # file min_metres: dashes visible to at least min_metres
    out=$(python3 "$TESTS/tools/dash_range.py" "$1" 1.2 100 40 9 191) || return 1
    echo "$1: $out"
    echo "$out" | awk -v m="$2" '{ split($1, v, "="); exit !(v[2] >= m) }'
}
check "dashes: texture mode render" "$BIN" render $DV --roads texture --stats "$T/dt.json" "$T/long.pgm" "$T/long.txt" "$T/dt.png"
if grep -q '"anisotropy_max": 1,' "$T/dt.json"; then
    echo "cli_render: note: this GL offers no anisotropic filtering; the texture-mode distance check is skipped"
else
    check "dashes: texture mode uses the GL's anisotropic filtering" grep -q '"anisotropy": 16' "$T/dt.json"
    check "dashes: texture mode (anisotropic) keeps dashes visible to >= 40 m" dash_ge "$T/dt.png" 40
fi
check "dashes: shader mode render" "$BIN" render $DV --roads shader "$T/long.pgm" "$T/long.txt" "$T/ds2.png"
check "dashes: shader mode keeps dashes visible to >= 40 m" dash_ge "$T/ds2.png" 40
check "dashes: --anisotropy 1 (isotropic) loses them before 30 m" sh -c "'$BIN' render $DV --roads texture --anisotropy 1 '$T/long.pgm' '$T/long.txt' '$T/di.png' && ! python3 '$TESTS/tools/dash_range.py' '$T/di.png' 1.2 100 40 9 191 | awk '{ split(\$1, v, \"=\"); exit !(v[2] >= 30) }'"
check "bad --anisotropy rejected" sh -c "! '$BIN' render --anisotropy 0.5 '$T/dem.pgm' '$T/roads.txt' '$T/e.png' 2>'$T/an.err' && grep -q 'anisotropy' '$T/an.err' && test ! -e '$T/e.png'"

# perspective: sky at the top, terrain below
check "oblique render exits 0" "$BIN" render $S --quiet --size 320x240 --camera 64,94,30 --look-at 64,30,8 "$T/dem.pgm" "$T/roads.txt" "$T/obl.png"
check "output is 320x240" py size "$T/obl.png" 320 240
check "sky at the top rows, terrain at the bottom" py sky "$T/obl.png"
check "default camera shows sky and terrain" sh -c "'$BIN' render $S --quiet --size 320x240 '$T/dem.pgm' '$T/roads.txt' '$T/def.png' && python3 '$T/png.py' sky '$T/def.png' 0.6 >/dev/null"
# straight down over the road: 12 m at 100 m with a 60 deg fov on 240 rows -> ~25 rows
check "top-down render exits 0" "$BIN" render $S --quiet --size 320x240 --fov 60 --camera 64,48,115 --look-at 64,48,0 --lighting off "$T/dem.pgm" "$T/roads.txt" "$T/down.png"
check "the road is dark where it projects, terrain around it" py road "$T/down.png" 8
check "deterministic output (same bytes twice)" sh -c "'$BIN' render $S --quiet --size 320x240 --camera 64,94,30 --look-at 64,30,8 '$T/dem.pgm' '$T/roads.txt' '$T/obl2.png' && cmp -s '$T/obl.png' '$T/obl2.png'"
check "lighting changes the picture" sh -c "'$BIN' render $S --quiet --size 320x240 --camera 64,94,30 --look-at 64,30,8 --lighting off '$T/dem.pgm' '$T/roads.txt' '$T/unlit.png' && python3 '$T/png.py' differ '$T/obl.png' '$T/unlit.png'"
check "fog changes the picture" sh -c "'$BIN' render $S --quiet --size 320x240 --camera 64,94,30 --look-at 64,30,8 --fog '$T/dem.pgm' '$T/roads.txt' '$T/fog.png' && python3 '$T/png.py' differ '$T/obl.png' '$T/fog.png'"

# camera checks (issue 15): warnings that name the problem; --origin cameras
# are in the roads' frame
check "a camera below the terrain is a warning naming it" sh -c "'$BIN' render $S --quiet --size 64x48 --camera 64,48,-100 --look-at 64,30,-100 '$T/dem.pgm' '$T/roads.txt' '$T/below.png' 2>'$T/below.err' && grep -q 'below the terrain' '$T/below.err'"
check "a view away from the map is a warning naming it" sh -c "'$BIN' render $S --quiet --size 64x48 --camera 64,-50,20 --look-at 64,-100,20 '$T/dem.pgm' '$T/roads.txt' '$T/away.png' 2>'$T/away.err' && grep -q 'misses the map' '$T/away.err'"
check "a good view gives no warning" sh -c "'$BIN' render $S --quiet --size 64x48 --camera 64,94,30 --look-at 64,30,8 '$T/dem.pgm' '$T/roads.txt' '$T/good.png' 2>'$T/good.err' && test ! -s '$T/good.err'"
printf 'road main width 12\n990 2048\n1140 2048\nend\n' > "$T/roads_o.txt"
check "--origin: camera in the roads' frame gives the untranslated picture" sh -c "'$BIN' render $S --quiet --origin 1000,2000 --size 320x240 --camera 1064,2094,30 --look-at 1064,2030,8 --stats '$T/o.json' '$T/dem.pgm' '$T/roads_o.txt' '$T/orig.png' 2>'$T/orig.err' && test ! -s '$T/orig.err' && cmp -s '$T/orig.png' '$T/obl.png' && grep -q '\"frame\": \"origin\"' '$T/o.json' && grep -q '\"camera\": \[1064, 2094, 30\]' '$T/o.json'"

# stats and budgets
check "stats run exits 0" "$BIN" render $S --quiet --size 320x240 --frames 4 --triangles 400 --stats "$T/s.json" "$T/dem.pgm" "$T/roads.txt" "$T/b.png"
check "stats JSON has fps, triangles, timings" sh -c "grep -q '\"fps\"' '$T/s.json' && grep -q '\"triangles\"' '$T/s.json' && grep -q '\"timings_ms\"' '$T/s.json' && grep -q '\"frames\": 4' '$T/s.json'"
check "fps is positive" awk -F'[:,]' '/"fps"/ { f = $2 } END { exit !(f > 0) }' "$T/s.json"
check "stats JSON has the mesh time and triangles of each of the 4 frames" python3 -c "
import json, sys
d = json.load(open(sys.argv[1]))
p = d['per_frame']
assert len(p['mesh_ms']) == 4 and len(p['mesh_triangles']) == 4
assert all(t > 0 for t in p['mesh_triangles']) and all(m >= 0 for m in p['mesh_ms'])
assert p['mesh_triangles'][-1] == d['triangles']
" "$T/s.json"
check "triangle budget held (<= 105 %)" awk -F'[:,]' '/"triangles"/ { t = $2 } END { exit !(t > 0 && t <= 420) }' "$T/s.json"
check "finer pixel error gives more triangles" sh -c "'$BIN' render $S --quiet --size 320x240 --pixel-error 8 --stats '$T/p8.json' '$T/dem.pgm' '$T/roads.txt' '$T/p8.png' && '$BIN' render $S --quiet --size 320x240 --pixel-error 0.25 --stats '$T/p1.json' '$T/dem.pgm' '$T/roads.txt' '$T/p1.png' && test \$(sed -n 's/.*\"triangles\": \([0-9]*\).*/\1/p' '$T/p1.json') -gt \$(sed -n 's/.*\"triangles\": \([0-9]*\).*/\1/p' '$T/p8.json')"

# errors: exit 1, nothing written
check "bad --size rejected" sh -c "! '$BIN' render --size 0x10 '$T/dem.pgm' '$T/roads.txt' '$T/e.png' 2>/dev/null && test ! -e '$T/e.png'"
check "bad --camera rejected" sh -c "! '$BIN' render --camera 1,2 '$T/dem.pgm' '$T/roads.txt' '$T/e.png' 2>/dev/null && test ! -e '$T/e.png'"
check "--pixel-error with --triangles rejected" sh -c "! '$BIN' render --pixel-error 1 --triangles 100 '$T/dem.pgm' '$T/roads.txt' '$T/e.png' 2>/dev/null && test ! -e '$T/e.png'"
check "unknown option rejected" sh -c "! '$BIN' render --bogus 1 '$T/dem.pgm' '$T/roads.txt' '$T/e.png' 2>/dev/null && test ! -e '$T/e.png'"
check "missing DEM rejected" sh -c "! '$BIN' render '$T/nope.pgm' '$T/roads.txt' '$T/e.png' 2>/dev/null && test ! -e '$T/e.png'"
check "failed run leaves an existing output untouched" sh -c "cp '$T/obl.png' '$T/keep.png' && ! '$BIN' render --lighting maybe '$T/dem.pgm' '$T/roads.txt' '$T/keep.png' 2>/dev/null && cmp -s '$T/obl.png' '$T/keep.png'"
# write errors: a full disk (file-size limit; OpenImageIO itself reports
# success there) and a FIFO as OUT must fail and leave no trace
if command -v prlimit >/dev/null 2>&1; then
    check "full disk: exit 1, old output untouched, no temp file" sh -c "cp '$T/obl.png' '$T/full.png' && ! sh -c 'trap \"\" XFSZ; exec prlimit --fsize=1000 \"\$0\" \"\$@\"' '$BIN' render $S --quiet --size 320x240 --camera 64,94,30 --look-at 64,30,8 '$T/dem.pgm' '$T/roads.txt' '$T/full.png' 2>'$T/full.err' && cmp -s '$T/obl.png' '$T/full.png' && grep -q 'full.png' '$T/full.err' && test -z \"\$(ls -a '$T' | grep '^\.full\.png\.')\""
fi
if mkfifo "$T/fifo.png" 2>/dev/null; then
    check "a FIFO as OUT is refused and kept" sh -c "! '$BIN' render $S --quiet --size 64x48 '$T/dem.pgm' '$T/roads.txt' '$T/fifo.png' 2>'$T/fifo.err' && test -p '$T/fifo.png' && grep -q 'not a regular file' '$T/fifo.err'"
fi
check "render --help exits 0" sh -c "'$BIN' render --help | grep -q -- --ortho"

echo "cli_render: $pass passed, $fail failed"
[ "$fail" = 0 ]
