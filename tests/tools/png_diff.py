"""Compare two RGB(A) PNGs of the same size on RGB: prints
'mean=M p99=P max=X n=N' in 1/255 units (mean and 99th percentile of the
per-channel absolute difference). Optional third argument: write the
per-pixel max difference x8 as a grey PGM; or, as X0,X1,Y0,Y1, compare only
the pixels of columns [X0, X1) and rows [Y0, Y1). Used by tests/cli_render_test.sh."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
from png_read import read  # noqa: E402


def main():
    wa, ha, ca, a = read(sys.argv[1])
    wb, hb, cb, b = read(sys.argv[2])
    assert (wa, ha) == (wb, hb), 'sizes differ: %dx%d vs %dx%d' % (wa, ha, wb, hb)
    hist = [0] * 256
    tot = 0
    worst = bytearray(wa * ha)
    region = None
    if len(sys.argv) > 3 and sys.argv[3].count(',') == 3:
        region = [int(v) for v in sys.argv[3].split(',')]
    for i in range(wa * ha):
        if region and not (region[0] <= i % wa < region[1] and region[2] <= i // wa < region[3]):
            continue
        pa, pb = i * ca, i * cb
        m = 0
        for c in range(3):
            d = abs(a[pa + c] - b[pb + c])
            hist[d] += 1
            tot += d
            if d > m:
                m = d
        worst[i] = min(255, 8 * m)
    n = 3 * (wa * ha if not region else
             max(0, min(region[1], wa) - region[0]) * max(0, min(region[3], ha) - region[2]))
    acc, p99 = 0, 0
    for d in range(256):
        acc += hist[d]
        if acc >= 0.99 * n:
            p99 = d
            break
    mx = max(d for d in range(256) if hist[d])
    print('mean=%.4f p99=%d max=%d n=%d' % (tot / n, p99, mx, n))
    if len(sys.argv) > 3 and not region:
        with open(sys.argv[3], 'wb') as f:
            f.write(b'P5 %d %d 255\n' % (wa, ha) + bytes(worst))


main()
