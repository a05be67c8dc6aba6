"""How far dashes stay visible in a driver's view (docs/render.md
"Dashes at a distance"). The view: a camera H metres above flat ground,
straight above a dashed centre line, looking along it at a ground point
LOOK metres ahead, vertical field of view FOV degrees; the line then runs
up the image's centre column (the image width must be odd).

For a distance d the ground point d metres ahead lies on row
    rows/2 + f tan(atan(H/d) - atan(H/LOOK)),  f = (rows/2) / tan(FOV/2).
Contrast at d = the luminance range (max - min) along the centre column
over the rows of one dash period centred on d, as a share of REF, the
contrast between the dash and the road colours (levels of luminance;
0: the range over d = 6..15 m in this image). The dashes are visible to
distance D when that share is >= THRESHOLD at every d from 6 m to D in
steps of 0.5 m. A period spanning fewer
than 2 rows cannot show a dash at all: the scan stops there ('geometric
limit', printed as well).

Usage: dash_range.py IMAGE H LOOK FOV PERIOD [REF [THRESHOLD]]
(REF default 0, THRESHOLD default 0.25)
Prints 'visible=D limit=G near_contrast=C' (metres, levels)."""
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
from png_read import read  # noqa: E402


def main():
    path = sys.argv[1]
    h, look, fov, period = (float(v) for v in sys.argv[2:6])
    ref = float(sys.argv[6]) if len(sys.argv) > 6 else 0.0
    thr = float(sys.argv[7]) if len(sys.argv) > 7 else 0.25
    w, rows, ch, px = read(path)
    assert w % 2 == 1, 'the image width must be odd (the line on the centre column)'
    col = w // 2
    f = (rows / 2.0) / math.tan(math.radians(fov) / 2)
    theta = math.atan(h / look)

    def row(d):
        return rows / 2.0 + f * math.tan(math.atan(h / d) - theta)

    def lum(y):
        i = (y * w + col) * ch
        c = px[i:i + 3] if ch >= 3 else (px[i],) * 3
        return 0.299 * c[0] + 0.587 * c[1] + 0.114 * c[2]

    def contrast(d0, d1):
        y0, y1 = int(math.floor(row(d1))), int(math.ceil(row(d0)))
        y0, y1 = max(y0, 0), min(y1, rows - 1)
        v = [lum(y) for y in range(y0, y1 + 1)]
        return max(v) - min(v), y1 - y0

    near, _ = contrast(6.0, 15.0)
    if ref <= 0:
        ref = near
    visible, limit, d = 6.0, None, 6.0
    while d < 5000:
        c, nrow = contrast(d - period / 2, d + period / 2)
        if nrow < 2:
            limit = d
            break
        if ref <= 0 or c / ref < thr:
            break
        visible = d
        d += 0.5
    if limit is None:  # the geometric limit beyond the first invisible distance
        g = d
        while g < 5000 and contrast(g - period / 2, g + period / 2)[1] >= 2:
            g += 0.5
        limit = g
    print('visible=%.1f limit=%.1f near_contrast=%.1f' % (visible, limit, near))


if __name__ == '__main__':
    main()
