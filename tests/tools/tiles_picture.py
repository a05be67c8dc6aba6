"""The picture of docs/tiles.md: every level of a `roadsplat tiles` folder
side by side, coarsest first, each tile shrunk to CELL pixels with a gap
between tiles; tiles that were not written (sparse) drawn as hatching.
Usage: tiles_picture.py OUTDIR PICTURE.png [CELL]"""
import json, os, struct, sys, zlib
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
from png_read import read

d, out = sys.argv[1], sys.argv[2]
C = int(sys.argv[3]) if len(sys.argv) > 3 else 96
m = json.load(open(os.path.join(d, 'tiles.json')))
S, gap, pad = m['tile_size'], 3, 16
levels = m['level_tiles']
W = sum(nx * (C + gap) for nx, _ in levels) + pad * (len(levels) + 1)
H = max(ny for _, ny in levels) * (C + gap) + 2 * pad
img = bytearray(b'\xff' * (W * H * 3))
x0 = pad
for z, (nx, ny) in enumerate(levels):
    for ty in range(ny):
        for tx in range(nx):
            p = os.path.join(d, str(z), str(tx), '%d.png' % ty)
            px = read(p) if os.path.exists(p) else None
            for j in range(C):
                for i in range(C):
                    X, Y = x0 + tx * (C + gap) + i, pad + ty * (C + gap) + j
                    if px:
                        w, h, ch, data = px
                        sx, sy = i * S // C, j * S // C
                        o = (sy * w + sx) * ch
                        a = data[o + 3] if ch == 4 else 255
                        rgb = [(data[o + k] * a + 255 * (255 - a)) // 255 for k in range(3)]
                    else:
                        rgb = [200, 200, 200] if (i + j) // 6 % 2 else [235, 235, 235]
                    img[3 * (Y * W + X):3 * (Y * W + X) + 3] = bytes(rgb)
    x0 += nx * (C + gap) + pad
raw = b''.join(b'\0' + bytes(img[3 * W * y:3 * W * (y + 1)]) for y in range(H))
def chunk(t, b):
    return struct.pack('>I', len(b)) + t + b + struct.pack('>I', zlib.crc32(t + b))
open(out, 'wb').write(b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', W, H, 8, 2, 0, 0, 0)) +
                      chunk(b'IDAT', zlib.compress(raw, 9)) + chunk(b'IEND', b''))
