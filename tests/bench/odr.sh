#!/bin/sh
# `make bench`: OpenDRIVE road sources (docs/opendrive.md, issue 32 target
# 3): a network of 12 four-arm junctions (31 arm roads with sidewalks and
# marks, 72 connecting roads; 103 roads) rendered at 0.1 m per pixel
# (4200 x 3200) from the .xodr and from its converted road text
# (`roadsplat convert`), --threads 1, fastest of 3 each. Target: the .xodr
# in at most 2x the time of the road text. Writes OUT/odr.md.
set -e
OUT=${1:-build/bench}
B=${BUILD:-build}
BIN=$B/roadsplat
mkdir -p "$OUT"
if [ ! -f "$B/roadsplat-odr.so" ]; then
    printf '## OpenDRIVE network\n\nSKIP: %s/roadsplat-odr.so not built (libexpat1-dev)\n' "$B" >"$OUT/odr.md"
    exit 0
fi
W=$(mktemp -d); trap 'rm -rf "$W"' EXIT
python3 - "$W" <<'PY'
import math, sys
w = sys.argv[1]
def lanes(side, centre, edge, sidewalk):
    def mk(t): return f'<roadMark sOffset="0" type="{t}" width="0.12"/>' if t else ''
    sw = lambda i: f'<lane id="{i}" type="sidewalk"><width sOffset="0" a="2" b="0" c="0" d="0"/></lane>' if sidewalk else ''
    c = f'<roadMark sOffset="0" type="{centre}" color="yellow" width="0.12"/>' if centre else ''
    return (f'<lanes><laneSection s="0"><left>{sw(2)}<lane id="1" type="driving"><width sOffset="0" a="3.5" b="0" c="0" d="0"/>{mk(edge)}</lane></left>'
            f'<center><lane id="0" type="none">{c}</lane></center>'
            f'<right><lane id="-1" type="driving"><width sOffset="0" a="3.5" b="0" c="0" d="0"/>{mk(edge)}</lane>{sw(-2)}</right></laneSection></lanes>')
roads, n = [], [0]
def road(x, y, hdg, length, geom='<line/>', junction=-1, **kw):
    n[0] += 1
    roads.append(f'<road id="{n[0]}" length="{length!r}" junction="{junction}"><planView><geometry s="0" x="{x!r}" y="{y!r}" hdg="{hdg!r}" '
                 f'length="{length!r}">{geom}</geometry></planView>{lanes(**kw)}</road>')
arm = dict(side=1, centre="broken", edge="solid", sidewalk=True)
cx = [60 + 100 * i for i in range(4)]
cy = [60 + 100 * j for j in range(3)]
for y in cy:
    xs = [10] + [c for x in cx for c in (x - 10, x + 10)] + [410]
    for a, b in zip(xs[0::2], xs[1::2]):
        road(a, y, 0.0, b - a, **arm)
for x in cx:
    ys = [10] + [c for y in cy for c in (y - 10, y + 10)] + [310]
    for a, b in zip(ys[0::2], ys[1::2]):
        road(x, a, math.pi / 2, b - a, **arm)
q = math.pi / 2 * 10
con = dict(side=1, centre=None, edge=None, sidewalk=False)
jid = 0
for x in cx:
    for y in cy:
        jid += 1
        J = 1000 + jid
        road(x - 10, y, 0.0, 20.0, junction=J, **con)
        road(x, y - 10, math.pi / 2, 20.0, junction=J, **con)
        road(x - 10, y, 0.0, q, geom='<arc curvature="-0.1"/>', junction=J, **con)
        road(x - 10, y, 0.0, q, geom='<arc curvature="0.1"/>', junction=J, **con)
        road(x, y - 10, math.pi / 2, q, geom='<arc curvature="-0.1"/>', junction=J, **con)
        road(x + 10, y, math.pi, q, geom='<arc curvature="-0.1"/>', junction=J, **con)
junctions = "".join(f'<junction id="{1000 + k}" name="j{k}"/>' for k in range(1, jid + 1))
open(f"{w}/net.xodr", "w").write('<?xml version="1.0"?>\n<OpenDRIVE><header revMajor="1" revMinor="6"/>\n' + "\n".join(roads) + junctions + "</OpenDRIVE>\n")
W, H = 211, 161
open(f"{w}/dem.pgm", "wb").write(b"P5 %d %d 255\n" % (W, H) + bytes(100 + ((i % W) + (i // W)) % 50 for i in range(W * H)))
print(f"bench odr: {n[0]} roads, {jid} junctions")
PY
now() { date +%s.%N; }
calc() { echo "$*" | bc -l; }
best() { # command...: the fastest of 3 runs, seconds
    b=
    for k in 1 2 3; do
        t0=$(now); "$@"; t=$(calc "$(now) - $t0")
        if [ -z "$b" ] || [ "$(calc "$t < $b")" = 1 ]; then b=$t; fi
    done
    echo "$b"
}
R="--quiet --threads 1 --cell-size 2 --origin 0,320 --texels 20 --z-scale 0.01"
t_conv=$(best "$BIN" convert "$W/net.xodr" "$W/net.txt")
t_text=$(best "$BIN" $R "$W/dem.pgm" "$W/net.txt" "$W/t.png")
t_xodr=$(best "$BIN" $R "$W/dem.pgm" "$W/net.xodr" "$W/x.png")
cmp -s "$W/t.png" "$W/x.png" || { echo "bench odr: the .xodr and its road text render differently"; exit 1; }
roads=$(grep -c '<road ' "$W/net.xodr")
recs=$(grep -c '^road ' "$W/net.txt")
ratio=$(calc "$t_xodr / $t_text")
{
    echo "## OpenDRIVE network (tests/bench/odr.sh)"
    echo
    echo "$roads roads (31 arms with sidewalks and marks, 72 connecting roads) in 12 junctions, 4200 x 3200 pixels at 0.1 m, --threads 1, fastest of 3. The converted road text has $recs records."
    echo
    echo "| input | seconds |"
    echo "| --- | --- |"
    printf '| road text (converted) | %.3f |\n' "$t_text"
    printf '| .xodr (read, converted, drawn) | %.3f |\n' "$t_xodr"
    printf '| roadsplat convert alone | %.3f |\n' "$t_conv"
    echo
    printf 'Ratio .xodr / road text: **%.2fx** (target <= 2x); both give the same bytes.\n' "$ratio"
} >"$OUT/odr.md"
cat "$OUT/odr.md"
