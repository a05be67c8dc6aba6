"""PNG decoding for the CLI tests (cli_png_test.sh, cli_render_test.sh):
8-bit, non-interlaced grey, RGB or RGBA, all five row filters, every chunk
CRC checked. Independent of the writer under test (cli/png.c)."""
import struct
import zlib


def read(path):
    """(width, height, channels, bytes of the decoded rows)."""
    d = open(path, 'rb').read()
    assert d[:8] == b'\x89PNG\r\n\x1a\n', 'not a PNG'
    pos, idat, t = 8, b'', b''
    while pos < len(d):
        n, t = struct.unpack('>I4s', d[pos:pos + 8])
        body = d[pos + 8:pos + 8 + n]
        assert zlib.crc32(t + body) == struct.unpack('>I', d[pos + 8 + n:pos + 12 + n])[0], 'CRC'
        pos += 12 + n
        if t == b'IHDR':
            w, h, bits, ct, _, _, il = struct.unpack('>IIBBBBB', body)
        elif t == b'IDAT':
            idat += body
    assert t == b'IEND' and bits == 8 and il == 0 and ct in (0, 2, 6), 'unsupported PNG'
    ch = {0: 1, 2: 3, 6: 4}[ct]
    stride, raw = w * ch, zlib.decompress(idat)
    out, prev = bytearray(), bytearray(stride)
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - ch] if i >= ch else 0
            b = prev[i]
            c = prev[i - ch] if i >= ch else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        out += line
        prev = line
    return w, h, ch, bytes(out)
