/* The marking atlas (issue 14, docs/markings.md): the index parser, the
 * per-type premultiplied mip chains, trilinear sampling and the built-in
 * atlas. */
#include "atlas.h"

#include <math.h>
#include <string.h>

static void free_types(rs_ctx *ctx, rs__atlas_type *t, size_t n)
{
    if (!t) return;
    for (size_t i = 0; i < n; i++)
        for (uint32_t l = 0; l < t[i].nlev && !t[i].shared; l++) rs__free(ctx, t[i].lev[l].px);
    rs__free(ctx, t);
}

void rs_atlas_free(rs_ctx *ctx, rs_atlas *a)
{
    if (!ctx || !a) return;
    free_types(ctx, a->t, a->n);
    rs__free(ctx, a);
}

size_t rs_atlas_count(const rs_atlas *a) { return a ? a->n : 0; }

rs_result rs_atlas_get(const rs_atlas *a, size_t i, const char **name, double *length, double *width, uint32_t *w,
                       uint32_t *h)
{
    if (!a || i >= a->n) return RS_ERR_INVALID_ARG;
    const rs__atlas_type *t = &a->t[i];
    if (name) *name = t->name;
    if (length) *length = t->length;
    if (width) *width = t->width;
    if (w) *w = t->lev[0].w;
    if (h) *h = t->lev[0].h;
    return RS_OK;
}

long rs_atlas_find(const rs_atlas *a, const char *name)
{
    if (!a || !name) return -1;
    for (size_t i = 0; i < a->n; i++)
        if (strcmp(a->t[i].name, name) == 0) return (long)i;
    return -1;
}

/* Bytes of the mip chain of a w x h rectangle (as build_levels makes it). */
static uint64_t chain_bytes(uint32_t w, uint32_t h)
{
    uint64_t b = 0;
    for (uint32_t l = 0; l < RS__ATLAS_MAX_LEVELS; l++) {
        b += (uint64_t)w * h * 4 * sizeof(float);
        if (w == 1 && h == 1) break;
        w = (w + 1) / 2;
        h = (h + 1) / 2;
    }
    return b;
}

/* Level 0 from the image, premultiplied; then halving (odd sizes padded
 * with transparent texels, so every level spans the same metres per
 * level-0 texel and keeps the sprite's integral). */
static rs_result build_levels(rs_ctx *ctx, rs__atlas_type *t, const rs_image *img, uint32_t x0, uint32_t y0,
                              uint32_t w, uint32_t h, size_t *bytes)
{
    for (uint32_t l = 0; l < RS__ATLAS_MAX_LEVELS; l++) {
        rs__atlas_level *L = &t->lev[l];
        L->w = l ? (t->lev[l - 1].w + 1) / 2 : w;
        L->h = l ? (t->lev[l - 1].h + 1) / 2 : h;
        L->px = rs__alloc_array(ctx, (size_t)L->w * L->h, 4 * sizeof(float));
        if (!L->px) return RS_ERR_NOMEM;
        t->nlev = l + 1;
        *bytes += (size_t)L->w * L->h * 4 * sizeof(float);
        if (l == 0) {
            for (uint32_t j = 0; j < h; j++) {
                /* (a callback every 64 rows: 256 rows of a 4096-wide sprite took 15 ms) */
                if ((j & 63) == 63 && rs__poll(ctx)) return RS_ERR_CANCELLED;
                for (uint32_t i = 0; i < w; i++) {
                    const uint8_t *p = img->rgba + ((size_t)(y0 + j) * img->width + (x0 + i)) * 4;
                    float *o = L->px + ((size_t)j * w + i) * 4;
                    float a = p[3] / 255.0f;
                    o[0] = p[0] * a;
                    o[1] = p[1] * a;
                    o[2] = p[2] * a;
                    o[3] = a;
                }
            }
        } else {
            const rs__atlas_level *U = &t->lev[l - 1];
            for (uint32_t j = 0; j < L->h; j++) {
                if ((j & 63) == 63 && rs__poll(ctx)) return RS_ERR_CANCELLED;
                for (uint32_t i = 0; i < L->w; i++) {
                    float s[4] = { 0, 0, 0, 0 };
                    for (uint32_t b = 0; b < 2; b++)
                        for (uint32_t a = 0; a < 2; a++) {
                            uint32_t x = 2 * i + a, y = 2 * j + b;
                            if (x >= U->w || y >= U->h) continue;
                            const float *q = U->px + ((size_t)y * U->w + x) * 4;
                            for (int c = 0; c < 4; c++) s[c] += q[c];
                        }
                    float *o = L->px + ((size_t)j * L->w + i) * 4;
                    for (int c = 0; c < 4; c++) o[c] = s[c] * 0.25f;
                }
            }
        }
        if (L->w == 1 && L->h == 1) break;
    }
    return RS_OK;
}

/* Next whitespace-separated token of [*p, end) on this line, or 0. */
static int token(const char **p, const char *end, const char **s, size_t *n)
{
    const char *q = *p;
    while (q < end && (*q == ' ' || *q == '\t' || *q == '\r')) q++;
    if (q == end || *q == '#') {
        *p = end;
        return 0;
    }
    *s = q;
    while (q < end && *q != ' ' && *q != '\t' && *q != '\r' && *q != '#') q++;
    *n = (size_t)(q - *s);
    *p = q;
    return 1;
}

static const char *show(char *buf, size_t cap, const char *s, size_t n)
{
    size_t k = 0;
    for (size_t i = 0; i < n && k + 4 < cap; i++) buf[k++] = (s[i] >= 0x20 && s[i] < 0x7F) ? s[i] : '?';
    if (k + 4 >= cap && n > k) {
        buf[k++] = '.';
        buf[k++] = '.';
    }
    buf[k] = '\0';
    return buf;
}

static rs_result create(rs_ctx *ctx, const rs_image *img, const char *index, size_t size, int builtin, rs_atlas **out)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!out) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_atlas_create: out is NULL");
    *out = NULL;
    if (!img || !img->rgba || !img->width || !img->height)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_atlas_create: the atlas image is NULL or empty");
    if (!builtin && (uint64_t)img->width * img->height > ctx->limits.max_texture_pixels)
        return rs__fail(ctx, RS_ERR_LIMIT, "atlas image of %u x %u pixels exceeds the texture limit", img->width,
                        img->height);
    if (!index && size) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_atlas_create: index is NULL");
    rs_atlas *a = rs__calloc(ctx, 1, sizeof *a);
    if (!a) return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for the atlas");
    size_t cap = 0;
    rs_result r = RS_OK;
    unsigned long long line = 0;
    char b1[48];
    for (size_t pos = 0; pos < size && !r;) {
        line++;
        const char *ls = index + pos, *nl = memchr(ls, '\n', size - pos);
        const char *le = nl ? nl : index + size;
        pos = (size_t)(le - index) + (nl ? 1 : 0);
        const char *p = ls, *tok[8];
        size_t tn[8], nt = 0;
        for (size_t i = 0; i < (size_t)(le - ls); i++)
            if (ls[i] == '\0' || ((unsigned char)ls[i] < 0x20 && ls[i] != '\t' && ls[i] != '\r')) {
                r = rs__fail(ctx, RS_ERR_PARSE, "atlas index line %llu: control character at column %zu", line, i + 1);
                break;
            }
        if (r) break;
        while (nt < 8 && token(&p, le, &tok[nt], &tn[nt])) nt++;
        if (nt == 0) continue;
        if (nt != 7) {
            r = rs__fail(ctx, RS_ERR_PARSE, "atlas index line %llu: expected NAME X Y W H LENGTH WIDTH (7 fields), got %s%zu",
                         line, nt == 8 ? "more than " : "", nt == 8 ? (size_t)7 : nt);
            break;
        }
        if (tn[0] > RS_MARK_TYPE_MAX) {
            r = rs__fail(ctx, RS_ERR_PARSE, "atlas index line %llu: name '%s' is longer than %d bytes", line,
                         show(b1, sizeof b1, tok[0], tn[0]), RS_MARK_TYPE_MAX);
            break;
        }
        for (size_t i = 0; i < tn[0]; i++) {
            char c = tok[0][i];
            if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-')) {
                r = rs__fail(ctx, RS_ERR_PARSE, "atlas index line %llu: name '%s': only A-Z a-z 0-9 _ - allowed", line,
                             show(b1, sizeof b1, tok[0], tn[0]));
                break;
            }
        }
        if (r) break;
        double v[6];
        static const char *const what[6] = { "X", "Y", "W", "H", "LENGTH", "WIDTH" };
        for (int k = 0; k < 6 && !r; k++) {
            const char *stop;
            if (!rs__parse_double(tok[k + 1], tok[k + 1] + tn[k + 1], &v[k], &stop) || stop != tok[k + 1] + tn[k + 1])
                r = rs__fail(ctx, RS_ERR_PARSE, "atlas index line %llu: %s '%s' is not a number", line, what[k],
                             show(b1, sizeof b1, tok[k + 1], tn[k + 1]));
            else if (k < 4 && !(v[k] >= 0 && v[k] <= 1e9 && v[k] == floor(v[k])))
                r = rs__fail(ctx, RS_ERR_PARSE, "atlas index line %llu: %s '%s' must be a whole number >= 0", line,
                             what[k], show(b1, sizeof b1, tok[k + 1], tn[k + 1]));
            else if (k >= 4 && !(v[k] > 0 && v[k] <= 1e6))
                r = rs__fail(ctx, RS_ERR_PARSE, "atlas index line %llu: %s '%s' must be > 0 and <= 1e6 metres", line,
                             what[k], show(b1, sizeof b1, tok[k + 1], tn[k + 1]));
        }
        if (r) break;
        if (v[2] < 1 || v[3] < 1 || v[0] + v[2] > img->width || v[1] + v[3] > img->height) {
            r = rs__fail(ctx, RS_ERR_PARSE, "atlas index line %llu: rectangle %.0f,%.0f %.0fx%.0f is empty or outside the %ux%u image",
                         line, v[0], v[1], v[2], v[3], img->width, img->height);
            break;
        }
        for (size_t i = 0; i < a->n; i++)
            if (strlen(a->t[i].name) == tn[0] && memcmp(a->t[i].name, tok[0], tn[0]) == 0) {
                r = rs__fail(ctx, RS_ERR_PARSE, "atlas index line %llu: type '%s' given twice", line,
                             show(b1, sizeof b1, tok[0], tn[0]));
                break;
            }
        if (r) break;
        if (a->n >= RS_ATLAS_MAX_TYPES) {
            r = rs__fail(ctx, RS_ERR_LIMIT, "atlas index line %llu: more than %d types", line, RS_ATLAS_MAX_TYPES);
            break;
        }
        if (a->n == cap) {
            size_t nc = cap ? 2 * cap : 16;
            rs__atlas_type *t = rs__realloc(ctx, a->t, nc * sizeof *t);
            if (!t) {
                r = rs__fail(ctx, RS_ERR_NOMEM, "out of memory for the atlas index");
                break;
            }
            a->t = t;
            cap = nc;
        }
        /* A rectangle given before shares its mip chain; a new one must
         * fit the budget for all types together before it is made. */
        uint32_t rx = (uint32_t)v[0], ry = (uint32_t)v[1], rw = (uint32_t)v[2], rh = (uint32_t)v[3];
        size_t same = a->n;
        for (size_t i = 0; i < a->n && same == a->n; i++)
            if (a->t[i].x == rx && a->t[i].y == ry && a->t[i].lev[0].w == rw && a->t[i].lev[0].h == rh) same = i;
        uint64_t need = same < a->n ? 0 : chain_bytes(rw, rh);
        if (!builtin && need > ctx->limits.max_atlas_bytes - a->bytes) {
            r = rs__fail(ctx, RS_ERR_LIMIT,
                         "atlas index line %llu: type '%s' (%ux%u pixels) brings the mip levels of all types to "
                         "%llu bytes, over the atlas budget of %llu bytes (rs_limits.max_atlas_bytes)",
                         line, show(b1, sizeof b1, tok[0], tn[0]), rw, rh, (unsigned long long)(a->bytes + need),
                         (unsigned long long)ctx->limits.max_atlas_bytes);
            break;
        }
        rs__atlas_type *t = &a->t[a->n++];
        memset(t, 0, sizeof *t);
        memcpy(t->name, tok[0], tn[0]);
        t->length = v[4];
        t->width = v[5];
        t->x = rx;
        t->y = ry;
        if (same < a->n - 1) {
            memcpy(t->lev, a->t[same].lev, sizeof t->lev);
            t->nlev = a->t[same].nlev;
            t->shared = 1;
        } else if ((r = build_levels(ctx, t, img, rx, ry, rw, rh, &a->bytes)) == RS_ERR_NOMEM) {
            r = rs__fail(ctx, RS_ERR_NOMEM, "out of memory for the atlas mip levels");
        }
    }
    if (!r && a->n == 0) r = rs__fail(ctx, RS_ERR_PARSE, "atlas index line %llu: the index names no marking type", line);
    if (r) {
        rs_atlas_free(ctx, a);
        return r;
    }
    *out = a;
    rs__ok(ctx);
    return RS_OK;
}

/* Progress: the context's callback (rs_ctx_set_progress), polls in the
 * mip levels' rows; a cancel makes nothing. */
rs_result rs_atlas_create(rs_ctx *ctx, const rs_image *img, const char *index, size_t size, rs_atlas **out)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    rs__progress pg;
    rs__progress_begin(ctx, &pg, NULL, NULL, 1, 1);
    return rs__progress_end(ctx, &pg, create(ctx, img, index, size, 0, out));
}

/* The built-in atlas is not the caller's texture: no texture limit. */
rs_result rs_atlas_default(rs_ctx *ctx, rs_atlas **out)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!out) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_atlas_default: out is NULL");
    *out = NULL;
    size_t n = (size_t)rs__atlas_default_w * rs__atlas_default_h;
    uint8_t *px = rs__alloc_array(ctx, n, 4);
    if (!px) return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for the built-in atlas");
    size_t at = 0;
    for (size_t i = 0; i + 1 < rs__atlas_default_rle_size && at < n; i += 2)
        for (unsigned k = 0; k < rs__atlas_default_rle[i] && at < n; k++, at++) {
            px[4 * at] = px[4 * at + 1] = px[4 * at + 2] = 255;
            px[4 * at + 3] = rs__atlas_default_rle[i + 1];
        }
    for (; at < n; at++) px[4 * at] = px[4 * at + 1] = px[4 * at + 2] = px[4 * at + 3] = 0;
    rs_image img = { rs__atlas_default_w, rs__atlas_default_h, px };
    rs_result r = create(ctx, &img, rs__atlas_default_index, strlen(rs__atlas_default_index), 1, out);
    rs__free(ctx, px);
    return r;
}

/* The up to 4 texels (and weights) of a bilinear tap at level texel
 * coordinates (x, y) (texel centres at integers); texels outside the level
 * are transparent and left out. */
static int taps(const rs__atlas_level *L, double x, double y, const float **q, float *w)
{
    double fx = floor(x), fy = floor(y);
    float wx = (float)(x - fx), wy = (float)(y - fy);
    int n = 0;
    for (int b = 0; b < 2; b++) {
        double yy = fy + b;
        if (yy < 0 || yy >= L->h) continue;
        float wb = b ? wy : 1 - wy;
        for (int a = 0; a < 2; a++) {
            double xx = fx + a;
            if (xx < 0 || xx >= L->w) continue;
            q[n] = L->px + ((size_t)yy * L->w + (size_t)xx) * 4;
            w[n] = wb * (a ? wx : 1 - wx);
            n++;
        }
    }
    return n;
}

/* Alpha first: most samples of a sprite's box are transparent. */
void rs__atlas_sample(const rs__atlas_type *t, double x, double y, double lod, float out[4])
{
    const float *q[8];
    float w[8];
    if (!(lod > 0)) lod = 0;
    double top = (double)(t->nlev - 1);
    int l = lod >= top ? (int)top : (int)lod;
    float f = lod >= top ? 0 : (float)(lod - l);
    double s0 = ldexp(1.0, -l);
    int n0 = taps(&t->lev[l], x * s0 - 0.5, y * s0 - 0.5, q, w), n = n0;
    if (f > 0) {
        n += taps(&t->lev[l + 1], x * s0 * 0.5 - 0.5, y * s0 * 0.5 - 0.5, q + n0, w + n0);
        for (int i = 0; i < n; i++) w[i] *= i < n0 ? 1 - f : f;
    }
    float a = 0;
    for (int i = 0; i < n; i++) a += w[i] * q[i][3];
    out[3] = a;
    if (!(a > 0)) {
        out[0] = out[1] = out[2] = 0;
        return;
    }
    float r = 0, g = 0, b = 0;
    for (int i = 0; i < n; i++) {
        r += w[i] * q[i][0];
        g += w[i] * q[i][1];
        b += w[i] * q[i][2];
    }
    out[0] = r;
    out[1] = g;
    out[2] = b;
}
