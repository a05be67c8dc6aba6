/* The .glb writer of `roadsplat mesh` (cli/gltf.h; module roadsplat-gltf.so).
 * One node, one mesh, one triangle primitive; one binary buffer holding,
 * 4-byte aligned: positions (float32 VEC3), texture coordinates (unsigned
 * short VEC2, normalised), normals (byte VEC3 + 1 pad byte, normalised),
 * indices (unsigned short or int), and the texture image. */
#include "gltf.h"
#include "cli.h"

#include <errno.h>
#include <math.h>
#include <meshoptimizer.h>
#include <stdlib.h>
#include <string.h>

/* A growing JSON text. */
typedef struct jbuf {
    char *s;
    size_t n, cap;
    int oom;
} jbuf;

static void jprintf(jbuf *j, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

#include <stdarg.h>
static void jprintf(jbuf *j, const char *fmt, ...)
{
    if (j->oom) return;
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        int k = vsnprintf(j->s ? j->s + j->n : NULL, j->s ? j->cap - j->n : 0, fmt, ap);
        va_end(ap);
        if (k < 0) { j->oom = 1; return; }
        if (j->s && j->n + (size_t)k < j->cap) { j->n += (size_t)k; return; }
        size_t cap = j->cap ? j->cap * 2 : 4096;
        while (cap < j->n + (size_t)k + 1) cap *= 2;
        char *t = realloc(j->s, cap);
        if (!t) { j->oom = 1; return; }
        j->s = t;
        j->cap = cap;
    }
}

static void put_u32(unsigned char *b, uint32_t u)
{
    b[0] = (unsigned char)u; b[1] = (unsigned char)(u >> 8); b[2] = (unsigned char)(u >> 16); b[3] = (unsigned char)(u >> 24);
}

static size_t pad4(size_t n) { return (n + 3) & ~(size_t)3; }

/* Little-endian float32 and the quantised forms (KHR_mesh_quantization:
 * normalised integers, round to nearest). */
static void put_f32(unsigned char *b, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    put_u32(b, u);
}

static uint16_t unorm16(float v)
{
    double x = v < 0 ? 0 : v > 1 ? 1 : (double)v;
    return (uint16_t)floor(x * 65535.0 + 0.5);
}

static int8_t snorm8(float v)
{
    double x = v < -1 ? -1 : v > 1 ? 1 : (double)v;
    return (int8_t)(x >= 0 ? floor(x * 127.0 + 0.5) : -floor(-x * 127.0 + 0.5));
}

int cli_gltf_write(FILE *f, const char *shown, const cli_gltf_mesh *m, cli_gltf_stats *st)
{
    memset(st, 0, sizeof *st);
    const size_t nv = m->nv, ni = m->ni;
    if (nv == 0 || ni == 0 || ni % 3 || nv > UINT32_MAX) {
        cli_error("%s: no mesh to write (%zu vertices, %zu indices)", shown, nv, ni);
        return 1;
    }
    int rc = 1;
    unsigned int *idx = malloc(ni * sizeof *idx), *remap = malloc(nv * sizeof *remap);
    unsigned char *bin = NULL;
    jbuf j = { NULL, 0, 0, 0 };
    if (!idx || !remap) goto oom;
    /* post-transform cache first, then the fetch order it implies; the
     * remap keeps every referenced vertex, so the count stays the mesh's */
    memcpy(idx, m->idx, ni * sizeof *idx);
    st->acmr_before = meshopt_analyzeVertexCache(idx, ni, nv, 16, 0, 0).acmr;
    meshopt_optimizeVertexCache(idx, idx, ni, nv);
    size_t used = meshopt_optimizeVertexFetchRemap(remap, idx, ni, nv);
    meshopt_remapIndexBuffer(idx, idx, ni, remap);
    st->acmr_after = meshopt_analyzeVertexCache(idx, ni, used, 16, 0, 0).acmr;
    st->vertices = used;
    st->triangles = ni / 3;

    const int wide = used > 65535;
    const size_t o_pos = 0, l_pos = used * 12;
    const size_t o_uv = pad4(o_pos + l_pos), l_uv = used * 4;
    const size_t o_nrm = pad4(o_uv + l_uv), l_nrm = m->nrm ? used * 4 : 0;
    const size_t o_idx = pad4(o_nrm + l_nrm), l_idx = ni * (wide ? 4 : 2);
    const size_t o_img = pad4(o_idx + l_idx), l_img = m->image ? m->image_len : 0;
    const size_t bin_len = pad4(o_img + l_img);
    if (!(bin = calloc(bin_len, 1))) goto oom;
    float lo[3] = { INFINITY, INFINITY, INFINITY }, hi[3] = { -INFINITY, -INFINITY, -INFINITY };
    for (size_t k = 0; k < nv; k++) {
        uint32_t d = remap[k];
        if (d == ~0u) continue; /* unreferenced */
        const float *p = m->pos + 3 * k;
        for (int c = 0; c < 3; c++) {
            put_f32(bin + o_pos + 12 * (size_t)d + 4 * (size_t)c, p[c]);
            if (p[c] < lo[c]) lo[c] = p[c];
            if (p[c] > hi[c]) hi[c] = p[c];
        }
        uint16_t u = unorm16(m->uv[2 * k]), v = unorm16(m->uv[2 * k + 1]);
        unsigned char *q = bin + o_uv + 4 * (size_t)d;
        q[0] = (unsigned char)u; q[1] = (unsigned char)(u >> 8); q[2] = (unsigned char)v; q[3] = (unsigned char)(v >> 8);
        if (m->nrm)
            for (int c = 0; c < 3; c++) bin[o_nrm + 4 * (size_t)d + (size_t)c] = (unsigned char)snorm8(m->nrm[3 * k + (size_t)c]);
    }
    for (size_t k = 0; k < ni; k++) {
        if (wide) put_u32(bin + o_idx + 4 * k, idx[k]);
        else {
            bin[o_idx + 2 * k] = (unsigned char)idx[k];
            bin[o_idx + 2 * k + 1] = (unsigned char)(idx[k] >> 8);
        }
    }
    if (l_img) memcpy(bin + o_img, m->image, l_img);

    jprintf(&j, "{\"asset\":{\"version\":\"2.0\",\"generator\":\"roadsplat %s\"},", rs_version_string());
    if (m->nrm) jprintf(&j, "\"extensionsUsed\":[\"KHR_mesh_quantization\"],\"extensionsRequired\":[\"KHR_mesh_quantization\"],");
    jprintf(&j, "\"scene\":0,\"scenes\":[{\"nodes\":[0]%s%s}],", m->extras ? ",\"extras\":" : "", m->extras ? m->extras : "");
    jprintf(&j, "\"nodes\":[{\"mesh\":0,\"name\":\"terrain\"}],");
    jprintf(&j, "\"meshes\":[{\"name\":\"terrain\",\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":1%s},"
                "\"indices\":%d,\"material\":0,\"mode\":4}]}],",
            m->nrm ? ",\"NORMAL\":2" : "", m->nrm ? 3 : 2);
    if (m->image)
        jprintf(&j, "\"materials\":[{\"name\":\"roadsplat\",\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0},"
                    "\"metallicFactor\":0,\"roughnessFactor\":1}}],"
                    "\"textures\":[{\"sampler\":0,\"source\":0}],"
                    "\"samplers\":[{\"magFilter\":9729,\"minFilter\":9987,\"wrapS\":33071,\"wrapT\":33071}],"
                    "\"images\":[{\"bufferView\":%d,\"mimeType\":\"%s\"}],",
                m->nrm ? 4 : 3, m->image_mime);
    else
        jprintf(&j, "\"materials\":[{\"name\":\"roadsplat\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[1,1,1,1],"
                    "\"metallicFactor\":0,\"roughnessFactor\":1}}],");
    jprintf(&j, "\"buffers\":[{\"byteLength\":%zu}],\"bufferViews\":[", bin_len);
    jprintf(&j, "{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu,\"byteStride\":12,\"target\":34962},", o_pos, l_pos);
    jprintf(&j, "{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu,\"byteStride\":4,\"target\":34962}", o_uv, l_uv);
    if (m->nrm) jprintf(&j, ",{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu,\"byteStride\":4,\"target\":34962}", o_nrm, l_nrm);
    jprintf(&j, ",{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu,\"target\":34963}", o_idx, l_idx);
    if (m->image) jprintf(&j, ",{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu}", o_img, l_img);
    jprintf(&j, "],\"accessors\":[");
    jprintf(&j, "{\"bufferView\":0,\"componentType\":5126,\"count\":%zu,\"type\":\"VEC3\",\"min\":[%.9g,%.9g,%.9g],"
                "\"max\":[%.9g,%.9g,%.9g]},",
            used, (double)lo[0], (double)lo[1], (double)lo[2], (double)hi[0], (double)hi[1], (double)hi[2]);
    jprintf(&j, "{\"bufferView\":1,\"componentType\":5123,\"normalized\":true,\"count\":%zu,\"type\":\"VEC2\"}", used);
    if (m->nrm) jprintf(&j, ",{\"bufferView\":2,\"componentType\":5120,\"normalized\":true,\"count\":%zu,\"type\":\"VEC3\"}", used);
    jprintf(&j, ",{\"bufferView\":%d,\"componentType\":%d,\"count\":%zu,\"type\":\"SCALAR\"}]}", m->nrm ? 3 : 2,
            wide ? 5125 : 5123, ni);
    if (j.oom) goto oom;
    {
        size_t jlen = pad4(j.n), total = 12 + 8 + jlen + 8 + bin_len;
        if (total > UINT32_MAX) {
            cli_error("%s: the mesh needs %zu bytes, beyond the 4 GiB a .glb can hold", shown, total);
            goto done;
        }
        unsigned char h[20];
        put_u32(h, 0x46546C67u); /* "glTF" */
        put_u32(h + 4, 2);
        put_u32(h + 8, (uint32_t)total);
        put_u32(h + 12, (uint32_t)jlen);
        put_u32(h + 16, 0x4E4F534Au); /* "JSON" */
        static const char spaces[4] = { ' ', ' ', ' ', ' ' };
        unsigned char bh[8];
        put_u32(bh, (uint32_t)bin_len);
        put_u32(bh + 4, 0x004E4942u); /* "BIN\0" */
        if (fwrite(h, 1, 20, f) != 20 || fwrite(j.s, 1, j.n, f) != j.n ||
            fwrite(spaces, 1, jlen - j.n, f) != jlen - j.n || fwrite(bh, 1, 8, f) != 8 ||
            fwrite(bin, 1, bin_len, f) != bin_len) {
            cli_error("%s: write failed: %s", shown, strerror(errno ? errno : EIO));
            goto done;
        }
        st->bytes = total;
    }
    rc = 0;
    goto done;
oom:
    cli_error("%s: out of memory for the glTF buffers (%zu vertices)", shown, nv);
done:
    free(idx);
    free(remap);
    free(bin);
    free(j.s);
    return rc;
}
