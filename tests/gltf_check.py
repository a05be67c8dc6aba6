"""Structural check of a .glb against the glTF 2.0 rules the writer uses
(cli/gltf.c), independent of it, and against the OBJ of the same mesh.

usage: gltf_check.py OUT.glb OUT.obj [TEXTURE]
Prints one line per problem; exit 1 on any. Checks: GLB header and chunk
framing, JSON references in range, bufferViews inside the buffer and
4-byte aligned, accessor strides, POSITION min/max equal to the data,
every index below the vertex count, normals unit length (within the
int8 quantisation), texture coordinates in [0, 1], the embedded image
equal to TEXTURE, and the vertex set and triangle count equal to the
OBJ's (positions exactly: both hold the same float32 values)."""
import json
import math
import struct
import sys

problems = []


def bad(msg):
    problems.append(msg)


glb = open(sys.argv[1], 'rb').read()
magic, version, length = struct.unpack_from('<III', glb, 0)
if magic != 0x46546C67 or version != 2 or length != len(glb):
    bad('GLB header: magic %x version %d length %d of %d' % (magic, version, length, len(glb)))
jlen, jtype = struct.unpack_from('<II', glb, 12)
if jtype != 0x4E4F534A or jlen % 4:
    bad('first chunk is not JSON or not padded')
doc = json.loads(glb[20:20 + jlen].decode('utf-8'))
blen, btype = struct.unpack_from('<II', glb, 20 + jlen)
if btype != 0x004E4942 or blen % 4 or 28 + jlen + blen != len(glb):
    bad('second chunk is not BIN or its length is off')
binary = glb[28 + jlen:28 + jlen + blen]
if doc['asset']['version'] != '2.0':
    bad('asset.version')
if doc['buffers'][0]['byteLength'] > blen:
    bad('buffer longer than the BIN chunk')

CT = {5120: ('b', 1), 5121: ('B', 1), 5122: ('h', 2), 5123: ('H', 2), 5125: ('I', 4), 5126: ('f', 4)}
NC = {'SCALAR': 1, 'VEC2': 2, 'VEC3': 3, 'VEC4': 4}

for i, bv in enumerate(doc['bufferViews']):
    off, ln = bv.get('byteOffset', 0), bv['byteLength']
    if off % 4 or off + ln > doc['buffers'][bv['buffer']]['byteLength']:
        bad('bufferView %d misaligned or outside the buffer' % i)
    if 'byteStride' in bv and bv['byteStride'] % 4:
        bad('bufferView %d stride %d not a multiple of 4' % (i, bv['byteStride']))


def read(acc_index):
    a = doc['accessors'][acc_index]
    bv = doc['bufferViews'][a['bufferView']]
    fmt, size = CT[a['componentType']]
    n = NC[a['type']]
    stride = bv.get('byteStride', size * n)
    if stride < size * n:
        bad('accessor %d: stride below its element' % acc_index)
    base = bv.get('byteOffset', 0) + a.get('byteOffset', 0)
    if (a['count'] - 1) * stride + size * n > bv['byteLength']:
        bad('accessor %d runs past its bufferView' % acc_index)
        return []
    out = []
    for k in range(a['count']):
        v = struct.unpack_from('<' + fmt * n, binary, base + k * stride)
        if a.get('normalized'):
            if fmt == 'H':
                v = tuple(x / 65535.0 for x in v)
            elif fmt == 'b':
                v = tuple(max(x / 127.0, -1.0) for x in v)
        out.append(v)
    return out


prim = doc['meshes'][doc['nodes'][doc['scenes'][doc['scene']]['nodes'][0]]['mesh']]['primitives'][0]
if prim.get('mode', 4) != 4:
    bad('not triangles')
attrs = prim['attributes']
pos = read(attrs['POSITION'])
pa = doc['accessors'][attrs['POSITION']]
for c in range(3):
    lo, hi = min(p[c] for p in pos), max(p[c] for p in pos)
    if struct.pack('<f', lo) != struct.pack('<f', pa['min'][c]) or struct.pack('<f', hi) != struct.pack('<f', pa['max'][c]):
        bad('POSITION min/max %d: %r %r vs data %r %r' % (c, pa['min'][c], pa['max'][c], lo, hi))
uv = read(attrs['TEXCOORD_0'])
if len(uv) != len(pos) or any(not (0 <= x <= 1) for t in uv for x in t):
    bad('TEXCOORD_0 count or range')
if 'NORMAL' in attrs:
    if 'KHR_mesh_quantization' not in doc.get('extensionsRequired', []):
        bad('byte normals without KHR_mesh_quantization required')
    for nrm in read(attrs['NORMAL']):
        if abs(math.sqrt(sum(x * x for x in nrm)) - 1) > 0.02:
            bad('normal %r not unit' % (nrm,))
            break
        if nrm[1] < 0:
            bad('normal %r points down' % (nrm,))
            break
idx = [t[0] for t in read(prim['indices'])]
if len(idx) % 3 or any(i >= len(pos) for i in idx):
    bad('indices: %d, max %d for %d vertices' % (len(idx), max(idx), len(pos)))
# counter-clockwise seen from above (y up): the normal's y > 0
for t in range(0, len(idx), 3):
    a, b, c = pos[idx[t]], pos[idx[t + 1]], pos[idx[t + 2]]
    ny = (c[0] - a[0]) * (b[2] - a[2]) - (b[0] - a[0]) * (c[2] - a[2])
    if ny < 0:  # skirt triangles are vertical (ny == 0); none may face down
        bad('triangle %d faces down' % (t // 3))
        break
if len(sys.argv) > 3:
    img = doc['images'][doc['textures'][doc['materials'][prim['material']]['pbrMetallicRoughness']['baseColorTexture']['index']]['source']]
    bv = doc['bufferViews'][img['bufferView']]
    data = binary[bv.get('byteOffset', 0):bv.get('byteOffset', 0) + bv['byteLength']]
    if data != open(sys.argv[3], 'rb').read():
        bad('embedded image differs from the texture file')

# the OBJ of the same mesh: the same vertex set and triangle count
objv, objf = [], 0
for line in open(sys.argv[2]):
    if line.startswith('v '):
        objv.append(tuple(struct.unpack('<f', struct.pack('<f', float(x)))[0] for x in line.split()[1:4]))
    elif line.startswith('f '):
        objf += 1
if sorted(objv) != sorted(pos):
    bad('vertex set differs from the OBJ (%d vs %d vertices)' % (len(pos), len(objv)))
if objf * 3 != len(idx):
    bad('triangles %d vs OBJ %d' % (len(idx) // 3, objf))

for p in problems:
    print(p)
print('gltf_check: %d vertices, %d triangles, %d problems' % (len(pos), len(idx) // 3, len(problems)))
sys.exit(1 if problems else 0)
