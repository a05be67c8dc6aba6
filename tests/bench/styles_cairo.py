#!/usr/bin/env python3
"""Cairo reference for issue 29 target 1 (tests/bench/styles.c): the city's
roads styled as tests/bench/styles.c styles them for the target (a casing,
two solid edge lines and a dashed centre line on every road), drawn with
Cairo into an ARGB32 image of the same pixels (cell/T metres). Prints the
fastest (minimum) time of N drawings in ms, strokes only: the paths are
built in Python outside the timed calls.

Cairo cannot offset a path, so the edge lines are the usual double stroke:
a white stroke as wide as the road between the edge lines' outer edges,
then an asphalt stroke between their inner edges. The layers go over all
roads in turn (casings, surfaces, edge-line strokes, asphalt, centre
dashes), the way a renderer such as Mapnik orders them, so a junction's
surface covers the edge lines of the roads meeting there.

Usage: styles_cairo.py ROADS.txt T [N [out.png]]
ROADS.txt: first line "W H cell", then one road per line "width n x0 y0 ...".
Constants (metres) must match styles.c: CASING, EDGE_IN, EDGE_W, CENTRE_W, DASH."""
import sys

import cairo

from roadfield_cairo import read_roads, timed_stroke  # (this folder: the script's own)

CASING = 0.5      # casing band outside each road edge
EDGE_IN = 0.25    # edge line centre this far inside the road edge
EDGE_W = 0.12     # edge line width
CENTRE_W = 0.15   # centre line width
DASH = (6.0, 12.0)


def main():
    path, T = sys.argv[1], int(sys.argv[2])
    runs = int(sys.argv[3]) if len(sys.argv) > 3 else 10
    out = sys.argv[4] if len(sys.argv) > 4 else None
    W, H, cs, roads = read_roads(path, T)
    scale = T / cs
    # (layer colour, width of a road of width wd, dashed)
    layers = [((0.63, 0.63, 0.63), lambda wd: wd + 2 * CASING, False),
              ((0.22, 0.22, 0.22), lambda wd: wd, False),
              ((1.0, 1.0, 1.0), lambda wd: wd - 2 * EDGE_IN + EDGE_W, False),
              ((0.22, 0.22, 0.22), lambda wd: wd - 2 * EDGE_IN - EDGE_W, False),
              ((1.0, 1.0, 1.0), lambda wd: CENTRE_W, True)]
    times = []
    for _ in range(runs):
        surf = cairo.ImageSurface(cairo.FORMAT_ARGB32, W, H)
        cr = cairo.Context(surf)
        cr.set_source_rgb(0.45, 0.55, 0.35)
        cr.paint()
        cr.set_line_cap(cairo.LINE_CAP_ROUND)
        cr.set_line_join(cairo.LINE_JOIN_ROUND)
        cr.scale(scale, scale)
        el = 0.0
        for colour, lw, dashed in layers:
            cr.set_source_rgb(*colour)
            cr.set_dash(DASH if dashed else [])
            cr.set_line_cap(cairo.LINE_CAP_BUTT if dashed else cairo.LINE_CAP_ROUND)
            for width, pts in roads:
                el += timed_stroke(cr, pts, max(lw(width), 0.01))
        surf.flush()
        times.append(el * 1000.0)
    print("%.3f" % min(times))
    if out:
        surf.write_to_png(out)


if __name__ == "__main__":
    main()
