#!/usr/bin/env python3
"""Cairo reference for tests/bench/roadfield.c: stroke the scene's roads with
round caps and joins into an A8 image of the same pixels (cell/T metres) and
print the fastest (minimum) time of N fills (stroke alone), in ms: on a shared
machine the minimum is the least disturbed run (medians swing 2x with load).
Usage: roadfield_cairo.py ROADS.txt T [out.f32] [N]   (N: fills, default 15)
ROADS.txt: first line "W H cell", then one road per line "width n x0 y0 ...".
With out.f32, the A8 coverage is written as float32 row-major (0..1)."""
import sys
import time

import cairo


def read_roads(path, T):
    """The roads file: (image width, height at T texels, cell size, [(width, [x0, y0, ...])])."""
    with open(path) as f:
        w, h, cs = f.readline().split()
        roads = []
        for line in f:
            v = line.split()
            width, n = float(v[0]), int(v[1])
            roads.append((width, [float(x) for x in v[2:2 + 2 * n]]))
    return (int(w) - 1) * T, (int(h) - 1) * T, float(cs), roads


def timed_stroke(cr, pts, width):
    """Build the path (not timed: Python-side work), stroke it; the stroke's seconds."""
    cr.move_to(pts[0], pts[1])
    for k in range(1, len(pts) // 2):
        cr.line_to(pts[2 * k], pts[2 * k + 1])
    cr.set_line_width(width)
    t0 = time.perf_counter()
    cr.stroke()
    return time.perf_counter() - t0


def main():
    path, T = sys.argv[1], int(sys.argv[2])
    W, H, cs, roads = read_roads(path, T)
    scale = T / cs
    runs = int(sys.argv[4]) if len(sys.argv) > 4 else 15
    times = []
    for _ in range(runs):
        surf = cairo.ImageSurface(cairo.FORMAT_A8, W, H)
        cr = cairo.Context(surf)
        cr.set_line_cap(cairo.LINE_CAP_ROUND)
        cr.set_line_join(cairo.LINE_JOIN_ROUND)
        cr.scale(scale, scale)
        el = 0.0
        for width, pts in roads:
            el += timed_stroke(cr, pts, width)
        surf.flush()
        times.append(el * 1000.0)
    print("%.3f" % min(times))
    if len(sys.argv) > 3 and sys.argv[3] not in ("", "-"):
        import array
        data = surf.get_data()
        stride = surf.get_stride()
        out = array.array("f", [0.0] * (W * H))
        for y in range(H):
            row = y * stride
            for x in range(W):
                out[y * W + x] = data[row + x] / 255.0
        with open(sys.argv[3], "wb") as f:
            out.tofile(f)


if __name__ == "__main__":
    main()
