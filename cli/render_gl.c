/* Offscreen renderer for `roadsplat render`: OSMesa + fixed-function GL 1.x.
 * See render_gl.h for the interface and docs/render.md for the design.
 * Built only with -DRS_WITH_OSMESA; otherwise this file is empty of code. */
#include "render_gl.h"

#ifdef RS_WITH_OSMESA
#include <GL/osmesa.h>
#include <GL/gl.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define RG_PI 3.14159265358979323846
/* GL_EXT_texture_filter_anisotropic (= the GL 4.6 core names without _EXT) */
#define RG_TEXTURE_MAX_ANISOTROPY 0x84FE
#define RG_MAX_TEXTURE_MAX_ANISOTROPY 0x84FF

struct rg_renderer {
    OSMesaContext osm;
    GLubyte *buf;
    uint32_t w, h;
    GLint max_tex;
    GLfloat max_aniso; /* GL_MAX_TEXTURE_MAX_ANISOTROPY; 1: not offered */
    /* texture tiles: core texels [tx*core, ..) plus `border` texels each side */
    uint32_t tex_w, tex_h, core, border, ntx, nty;
    GLuint *tex;
    /* per-frame scratch: GL-frame vertex arrays and clipped tile geometry */
    float *pos, *nrm, *uv;
    size_t cap_v;
    float *clip;
    size_t clip_n, clip_cap;
    /* rg_draw_vt's tile slots: a texture each, made on the slot's first upload */
    GLuint *vt_tex;
    uint8_t *vt_made;
    uint32_t vt_slots, vt_side;
};

static void set_err(char *err, size_t n, const char *msg)
{
    if (err && n) snprintf(err, n, "%s", msg);
}

rg_renderer *rg_create(uint32_t width, uint32_t height, char *err, size_t err_size)
{
    rg_renderer *r = calloc(1, sizeof *r);
    if (!r) { set_err(err, err_size, "out of memory"); return NULL; }
    r->w = width;
    r->h = height;
    r->osm = OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, NULL);
    if (!r->osm) { set_err(err, err_size, "OSMesaCreateContextExt failed (RGBA, 24-bit depth)"); free(r); return NULL; }
    r->buf = malloc((size_t)width * height * 4);
    if (!r->buf) { set_err(err, err_size, "out of memory for the frame buffer"); rg_destroy(r); return NULL; }
    if (!OSMesaMakeCurrent(r->osm, r->buf, GL_UNSIGNED_BYTE, (GLsizei)width, (GLsizei)height)) {
        set_err(err, err_size, "OSMesaMakeCurrent failed (size too large for this Mesa?)");
        rg_destroy(r);
        return NULL;
    }
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &r->max_tex);
    if (r->max_tex < 64) r->max_tex = 64;
    /* anisotropic filtering: GL_EXT/ARB_texture_filter_anisotropic (core in
     * GL 4.6, same enums); llvmpipe offers it, up to 16 taps */
    r->max_aniso = 1;
    {
        const char *ext = (const char *)glGetString(GL_EXTENSIONS), *ver = (const char *)glGetString(GL_VERSION);
        int major = 0, minor = 0;
        if (ver) sscanf(ver, "%d.%d", &major, &minor);
        if ((ext && (strstr(ext, "GL_EXT_texture_filter_anisotropic") || strstr(ext, "GL_ARB_texture_filter_anisotropic"))) ||
            major > 4 || (major == 4 && minor >= 6)) {
            GLfloat m = 1;
            glGetFloatv(RG_MAX_TEXTURE_MAX_ANISOTROPY, &m);
            if (glGetError() == GL_NO_ERROR && m > 1) r->max_aniso = m;
        }
    }
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    return r;
}

void rg_destroy(rg_renderer *r)
{
    if (!r) return;
    if (r->tex) {
        glDeleteTextures((GLsizei)(r->ntx * r->nty), r->tex);
        free(r->tex);
    }
    if (r->vt_tex) {
        glDeleteTextures((GLsizei)r->vt_slots, r->vt_tex);
        free(r->vt_tex);
    }
    free(r->vt_made);
    if (r->osm) OSMesaDestroyContext(r->osm);
    free(r->buf);
    free(r->pos); free(r->nrm); free(r->uv); free(r->clip);
    free(r);
}

uint32_t rg_max_texture_size(const rg_renderer *r) { return (uint32_t)r->max_tex; }

void rg_describe(const rg_renderer *r, char *out, size_t out_size)
{
    const GLubyte *rn = glGetString(GL_RENDERER), *ver = glGetString(GL_VERSION);
    (void)r;
    snprintf(out, out_size, "%s, GL %s", rn ? (const char *)rn : "?", ver ? (const char *)ver : "?");
    for (char *c = out; *c; c++) /* keep it a plain JSON string */
        if (*c == '"' || *c == '\\' || (unsigned char)*c < 32) *c = ' ';
}

/* ---- mip levels --------------------------------------------------------- */

/* Area-weighted box filter from sw x sh to dw x dh (dw <= sw, dh <= sh), exact
 * in integer overlap units, so odd sizes keep their footprint (no dropped column). */
static int downsample(const uint8_t *src, uint32_t sw, uint32_t sh, uint8_t *dst, uint32_t dw, uint32_t dh)
{
    double *tmp = malloc((size_t)dw * sh * 4 * sizeof *tmp);
    if (!tmp) return 1;
    for (uint32_t y = 0; y < sh; y++)
        for (uint32_t x = 0; x < dw; x++) {
            uint64_t a = (uint64_t)x * sw, b = (uint64_t)(x + 1) * sw; /* in 1/dw texel units */
            double acc[4] = { 0, 0, 0, 0 };
            for (uint64_t k = a / dw; k * dw < b && k < sw; k++) {
                uint64_t lo = k * dw > a ? k * dw : a, hi = (k + 1) * dw < b ? (k + 1) * dw : b;
                double wgt = (double)(hi - lo) / (double)sw;
                const uint8_t *p = src + 4 * ((size_t)y * sw + k);
                for (int c = 0; c < 4; c++) acc[c] += wgt * p[c];
            }
            memcpy(tmp + 4 * ((size_t)y * dw + x), acc, sizeof acc);
        }
    for (uint32_t y = 0; y < dh; y++) {
        uint64_t a = (uint64_t)y * sh, b = (uint64_t)(y + 1) * sh;
        for (uint32_t x = 0; x < dw; x++) {
            double acc[4] = { 0, 0, 0, 0 };
            for (uint64_t k = a / dh; k * dh < b && k < sh; k++) {
                uint64_t lo = k * dh > a ? k * dh : a, hi = (k + 1) * dh < b ? (k + 1) * dh : b;
                double wgt = (double)(hi - lo) / (double)sh;
                const double *p = tmp + 4 * ((size_t)k * dw + x);
                for (int c = 0; c < 4; c++) acc[c] += wgt * p[c];
            }
            for (int c = 0; c < 4; c++) {
                long v = lround(acc[c]);
                dst[4 * ((size_t)y * dw + x) + (size_t)c] = (uint8_t)(v < 0 ? 0 : v > 255 ? 255 : v);
            }
        }
    }
    free(tmp);
    return 0;
}

/* Base mip level a tile needs (seed 002): the projected size in pixels of one
 * texel at the tile's nearest point, s = texel * focal / d; levels finer than
 * floor(log2(1/s)) are never sampled. Perspective doubles s as a margin for
 * off-axis stretching, so the choice never comes out coarser than GL's own. */
static uint32_t tile_base_level(const rg_renderer *r, const rg_view *v, double x0, double x1, double y0, double y1,
                                double texel_m, uint32_t nlevels)
{
    double s;
    if (v->ortho) {
        double ppm = fmin((double)r->w / v->map_w, (double)r->h / v->map_h);
        s = texel_m * ppm * (1.0 + 1e-9);
    } else {
        double dx = v->eye[0] < x0 ? x0 - v->eye[0] : v->eye[0] > x1 ? v->eye[0] - x1 : 0;
        double dy = v->eye[1] < y0 ? y0 - v->eye[1] : v->eye[1] > y1 ? v->eye[1] - y1 : 0;
        double dz = v->eye[2] < v->zmin ? v->zmin - v->eye[2] : v->eye[2] > v->zmax ? v->eye[2] - v->zmax : 0;
        double d = sqrt(dx * dx + dy * dy + dz * dz);
        double focal = r->h / (2.0 * tan(v->fov_y * RG_PI / 360.0));
        if (d < 1e-9) return 0;
        s = 2.0 * texel_m * focal / d;
    }
    if (!(s < 1.0)) return 0;
    if (!(s > 0.0)) return nlevels - 1; /* eye (far) away: the coarsest level; no division by 0 */
    double l = floor(log2(1.0 / s));
    if (l > nlevels - 1) l = nlevels - 1;
    return l > 0 ? (uint32_t)l : 0;
}

int rg_upload_texture(rg_renderer *r, const uint8_t *rgba, uint32_t tex_w, uint32_t tex_h, uint32_t tile_limit,
                      const rg_view *view, rg_tex_stats *st, char *err, size_t err_size)
{
    uint32_t lim = tile_limit && tile_limit < (uint32_t)r->max_tex ? tile_limit : (uint32_t)r->max_tex;
    memset(st, 0, sizeof *st);
    st->max_texture_size = (uint32_t)r->max_tex;
    r->tex_w = tex_w;
    r->tex_h = tex_h;
    if (tex_w <= lim && tex_h <= lim) {
        r->border = 0;
        r->core = tex_w > tex_h ? tex_w : tex_h;
    } else {
        /* a border of real neighbour texels keeps bilinear and the first mip
         * levels seamless across tile edges */
        r->border = lim >= 64 ? 4 : 1;
        if (lim <= 2 * r->border) { set_err(err, err_size, "tile size too small"); return 1; }
        r->core = lim - 2 * r->border;
    }
    r->ntx = (tex_w + r->core - 1) / r->core;
    r->nty = (tex_h + r->core - 1) / r->core;
    r->tex = calloc((size_t)r->ntx * r->nty, sizeof *r->tex);
    if (!r->tex) { set_err(err, err_size, "out of memory"); return 1; }
    glGenTextures((GLsizei)(r->ntx * r->nty), r->tex);
    st->tiles_x = r->ntx;
    st->tiles_y = r->nty;
    st->tile_core = r->core;
    st->finest_level = UINT32_MAX;
    /* the ortho view looks straight down: its footprints are isotropic,
     * and llvmpipe's anisotropic path would not give the exact texels */
    double aniso = view->ortho ? 1
                   : view->anisotropy > 0 && view->anisotropy < r->max_aniso ? view->anisotropy : r->max_aniso;
    st->anisotropy = aniso;
    st->anisotropy_max = r->max_aniso;
    /* No finer levels are needed for it: with N taps GL samples the level
     * of the footprint's minor axis at the finest, and a texel's size seen
     * face-on at the tile's nearest point (tile_base_level) bounds that. */
    double texel_m = fmax(view->map_w / tex_w, view->map_h / tex_h);
    uint32_t B = r->border;
    for (uint32_t ty = 0; ty < r->nty; ty++)
        for (uint32_t tx = 0; tx < r->ntx; tx++) {
            uint32_t x0 = tx * r->core, y0 = ty * r->core;
            uint32_t cw = tex_w - x0 < r->core ? tex_w - x0 : r->core, ch = tex_h - y0 < r->core ? tex_h - y0 : r->core;
            uint32_t tw = cw + 2 * B, th = ch + 2 * B;
            uint8_t *lv = malloc((size_t)tw * th * 4);
            if (!lv) { set_err(err, err_size, "out of memory for a texture tile"); return 1; }
            for (uint32_t y = 0; y < th; y++) {
                long sy = (long)y0 + (long)y - (long)B;
                sy = sy < 0 ? 0 : sy >= (long)tex_h ? (long)tex_h - 1 : sy;
                for (uint32_t x = 0; x < tw; x++) {
                    long sx = (long)x0 + (long)x - (long)B;
                    sx = sx < 0 ? 0 : sx >= (long)tex_w ? (long)tex_w - 1 : sx;
                    memcpy(lv + 4 * ((size_t)y * tw + x), rgba + 4 * ((size_t)sy * tex_w + (size_t)sx), 4);
                }
            }
            uint32_t nlevels = 1;
            for (uint32_t m = tw > th ? tw : th; m > 1; m >>= 1) nlevels++;
            uint32_t base = tile_base_level(r, view, x0 * (view->map_w / tex_w), (x0 + cw) * (view->map_w / tex_w),
                                            y0 * (view->map_h / tex_h), (y0 + ch) * (view->map_h / tex_h), texel_m,
                                            nlevels);
            glBindTexture(GL_TEXTURE_2D, r->tex[ty * r->ntx + tx]);
            uint32_t lw = tw, lh = th;
            for (uint32_t l = 0; l < nlevels; l++) {
                if (l >= base) {
                    glTexImage2D(GL_TEXTURE_2D, (GLint)l, GL_RGBA8, (GLsizei)lw, (GLsizei)lh, 0, GL_RGBA,
                                 GL_UNSIGNED_BYTE, lv);
                    st->texels_uploaded += (uint64_t)lw * lh;
                }
                st->texels_full += (uint64_t)lw * lh;
                if (l + 1 == nlevels) break;
                uint32_t nw = lw > 1 ? lw / 2 : 1, nh = lh > 1 ? lh / 2 : 1;
                uint8_t *nx = malloc((size_t)nw * nh * 4);
                if (!nx || downsample(lv, lw, lh, nx, nw, nh)) {
                    free(nx); free(lv);
                    set_err(err, err_size, "out of memory for mip levels");
                    return 1;
                }
                free(lv);
                lv = nx; lw = nw; lh = nh;
            }
            free(lv);
            glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_BASE_LEVEL, (GLint)base);
            glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, (GLint)(nlevels - 1));
            glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
            glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
            glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
            glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
            if (aniso > 1) glTexParameterf(GL_TEXTURE_2D, RG_TEXTURE_MAX_ANISOTROPY, aniso);
            if (base < st->finest_level) st->finest_level = base;
            if (base > st->coarsest_base) st->coarsest_base = base;
        }
    if (glGetError() != GL_NO_ERROR) { set_err(err, err_size, "texture upload failed (GL error)"); return 1; }
    return 0;
}

/* ---- camera and sky ------------------------------------------------------ */

static void norm3(double *v)
{
    double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (l > 0) { v[0] /= l; v[1] /= l; v[2] /= l; }
}

static void cross3(const double *a, const double *b, double *o)
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}

void rg_camera_basis(const double *eye_m, const double *look_m, double *E, double *s, double *u, double *f)
{
    E[0] = eye_m[0]; E[1] = eye_m[2]; E[2] = eye_m[1];
    f[0] = look_m[0] - eye_m[0]; f[1] = look_m[2] - eye_m[2]; f[2] = look_m[1] - eye_m[1];
    norm3(f);
    double up[3] = { 0, 1, 0 };
    cross3(f, up, s);
    if (sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]) < 1e-6) {
        double north[3] = { 0, 0, -1 };
        cross3(f, north, s);
    }
    norm3(s);
    cross3(s, f, u);
}

static void load_view(const double *E, const double *s, const double *u, const double *f)
{
    GLdouble m[16] = { s[0], u[0], -f[0], 0, s[1], u[1], -f[1], 0, s[2], u[2], -f[2], 0,
                       -(s[0] * E[0] + s[1] * E[1] + s[2] * E[2]), -(u[0] * E[0] + u[1] * E[1] + u[2] * E[2]),
                       f[0] * E[0] + f[1] * E[1] + f[2] * E[2], 1 };
    glMatrixMode(GL_MODELVIEW);
    glLoadMatrixd(m);
}

static const float sky_zenith[3] = { 0.22f, 0.42f, 0.78f };
static const float sky_horizon[3] = { 0.78f, 0.85f, 0.93f };
static const float ground_haze[3] = { 0.62f, 0.66f, 0.70f };

static void sky_colour(double sin_elev, float *c)
{
    if (sin_elev <= 0) {
        double t = fmin(1.0, -sin_elev / 0.15);
        for (int k = 0; k < 3; k++) c[k] = (float)(sky_horizon[k] + t * (ground_haze[k] - sky_horizon[k]));
        return;
    }
    double t = sqrt(fmin(1.0, sin_elev / 0.7));
    for (int k = 0; k < 3; k++) c[k] = (float)(sky_horizon[k] + t * (sky_zenith[k] - sky_horizon[k]));
}

/* Gradient by the elevation of the ray through each band corner. */
static void draw_sky(const rg_renderer *r, const rg_view *v, const double *s, const double *u, const double *f)
{
    double ty = tan(v->fov_y * RG_PI / 360.0), tx = ty * r->w / r->h;
    glMatrixMode(GL_PROJECTION);
    glLoadIdentity();
    glMatrixMode(GL_MODELVIEW);
    glLoadIdentity();
    enum { BANDS = 64 };
    glBegin(GL_QUAD_STRIP);
    for (int b = 0; b <= BANDS; b++) {
        double ny = -1.0 + 2.0 * b / BANDS;
        for (int side = 0; side < 2; side++) {
            double nx = side ? 1.0 : -1.0, d[3];
            for (int k = 0; k < 3; k++) d[k] = f[k] + s[k] * nx * tx + u[k] * ny * ty;
            norm3(d);
            float c[3];
            sky_colour(d[1], c);
            glColor3f(c[0], c[1], c[2]);
            glVertex2d(nx, ny);
        }
    }
    glEnd();
}

/* ---- geometry ----------------------------------------------------------- */

static int grow(float **p, size_t *cap, size_t need)
{
    if (need <= *cap) return 0;
    size_t n = *cap ? *cap : 1024;
    while (n < need) n *= 2;
    float *q = realloc(*p, n * sizeof *q);
    if (!q) return 1;
    *p = q;
    *cap = n;
    return 0;
}

/* A clip vertex: GL position (3), GL normal (3), texel coordinates (2). */
enum { CV = 8 };

/* Intersection of edge a-b with tu (axis 6) or tv (axis 7) = c; endpoints are
 * ordered first so both tiles sharing the edge compute identical bits. */
static void clip_point(const float *a, const float *b, int axis, double c, float *o)
{
    if (a[axis] > b[axis] || (a[axis] == b[axis] && memcmp(a, b, CV * sizeof *a) > 0)) {
        const float *t = a; a = b; b = t;
    }
    double t = (c - a[axis]) / ((double)b[axis] - a[axis]);
    for (int k = 0; k < CV; k++) o[k] = (float)(a[k] + t * ((double)b[k] - a[k]));
    o[axis] = (float)c;
}

/* Sutherland-Hodgman against one half plane: keep = sign * (p[axis] - c) >= 0. */
static int clip_poly(const float *in, int n, float *out, int axis, double c, double sign)
{
    int m = 0;
    for (int k = 0; k < n; k++) {
        const float *a = in + CV * k, *b = in + CV * ((k + 1) % n);
        double da = sign * (a[axis] - c), db = sign * (b[axis] - c);
        if (da >= 0) { memcpy(out + CV * m, a, CV * sizeof *a); m++; }
        if ((da >= 0) != (db >= 0)) { clip_point(a, b, axis, c, out + CV * m); m++; }
    }
    return m;
}

/* Triangles of the mesh clipped to tile core [x0,x1] x [y0,y1] (texels),
 * appended to r->clip as GL triangles. */
static int clip_tile(rg_renderer *r, const uint32_t *idx, size_t ntri, double x0, double x1, double y0, double y1)
{
    r->clip_n = 0;
    float pa[CV * 8], pb[CV * 8];
    for (size_t t = 0; t < ntri; t++) {
        float tri[3 * CV];
        float mnx = 1e30f, mxx = -1e30f, mny = 1e30f, mxy = -1e30f;
        for (int c = 0; c < 3; c++) {
            uint32_t i = idx[3 * t + (size_t)c];
            float *o = tri + CV * c;
            memcpy(o, r->pos + 3 * (size_t)i, 3 * sizeof *o);
            memcpy(o + 3, r->nrm + 3 * (size_t)i, 3 * sizeof *o);
            o[6] = r->uv[2 * (size_t)i] * (float)r->tex_w;
            o[7] = r->uv[2 * (size_t)i + 1] * (float)r->tex_h;
            mnx = fminf(mnx, o[6]); mxx = fmaxf(mxx, o[6]);
            mny = fminf(mny, o[7]); mxy = fmaxf(mxy, o[7]);
        }
        if (mxx <= x0 || mnx >= x1 || mxy <= y0 || mny >= y1) continue;
        int n = 3;
        const float *poly = tri;
        if (mnx < x0 || mxx > x1 || mny < y0 || mxy > y1) {
            n = clip_poly(tri, 3, pa, 6, x0, 1.0);
            n = clip_poly(pa, n, pb, 6, x1, -1.0);
            n = clip_poly(pb, n, pa, 7, y0, 1.0);
            n = clip_poly(pa, n, pb, 7, y1, -1.0);
            poly = pb;
            if (n < 3) continue;
        }
        if (grow(&r->clip, &r->clip_cap, (r->clip_n + 3 * (size_t)(n - 2)) * CV)) return 1;
        for (int k = 1; k + 1 < n; k++) {
            memcpy(r->clip + CV * r->clip_n++, poly, CV * sizeof *poly);
            memcpy(r->clip + CV * r->clip_n++, poly + CV * k, CV * sizeof *poly);
            memcpy(r->clip + CV * r->clip_n++, poly + CV * (k + 1), CV * sizeof *poly);
        }
    }
    return 0;
}

/* A frame up to the mesh: vertex arrays in the GL frame, sky, camera,
 * lighting, fog, client arrays on (rg_draw and rg_draw_vt). */
static int draw_begin(rg_renderer *r, const rg_view *v, const float *vertices, const float *normals, size_t nv,
                      char *err, size_t err_size)
{
    size_t c3 = r->cap_v, c3n = r->cap_v, c2 = r->cap_v;
    if (grow(&r->pos, &c3, 3 * nv + 3) || grow(&r->nrm, &c3n, 3 * nv + 3) || grow(&r->uv, &c2, 3 * nv + 3)) {
        set_err(err, err_size, "out of memory for the vertex arrays");
        return 1;
    }
    r->cap_v = c3 < c3n ? (c3 < c2 ? c3 : c2) : (c3n < c2 ? c3n : c2);
    for (size_t k = 0; k < nv; k++) {
        const float *p = vertices + 5 * k, *n = normals + 3 * k;
        r->pos[3 * k] = p[0]; r->pos[3 * k + 1] = p[2]; r->pos[3 * k + 2] = p[1];
        r->nrm[3 * k] = n[0]; r->nrm[3 * k + 1] = n[2]; r->nrm[3 * k + 2] = n[1];
        r->uv[2 * k] = p[3]; r->uv[2 * k + 1] = p[4];
    }

    glViewport(0, 0, (GLsizei)r->w, (GLsizei)r->h);
    glClearColor(ground_haze[0], ground_haze[1], ground_haze[2], 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_LIGHTING);
    glDisable(GL_TEXTURE_2D);
    glDisable(GL_FOG);
    glDisable(GL_CULL_FACE);
    glShadeModel(GL_SMOOTH);

    double E[3], s[3], u[3], f[3];
    if (v->ortho) {
        double eye[3] = { v->map_w / 2, v->map_h / 2, v->zmax + 1.0 }, look[3] = { v->map_w / 2, v->map_h / 2, v->zmin };
        rg_camera_basis(eye, look, E, s, u, f);
        double ppm = fmin((double)r->w / v->map_w, (double)r->h / v->map_h);
        double hw = r->w / (2 * ppm), hh = r->h / (2 * ppm);
        glMatrixMode(GL_PROJECTION);
        glLoadIdentity();
        glOrtho(-hw, hw, -hh, hh, 0.5, v->zmax - v->zmin + 2.0);
    } else {
        rg_camera_basis(v->eye, v->look, E, s, u, f);
        draw_sky(r, v, s, u, f);
        double ty = tan(v->fov_y * RG_PI / 360.0) * v->znear, tx = ty * r->w / r->h;
        glMatrixMode(GL_PROJECTION);
        glLoadIdentity();
        glFrustum(-tx, tx, -ty, ty, v->znear, v->zfar);
    }
    load_view(E, s, u, f);

    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glEnable(GL_TEXTURE_2D);
    glColor4f(1, 1, 1, 1);
    if (v->lighting) {
        GLfloat zero[4] = { 0, 0, 0, 1 }, amb[4] = { 0.42f, 0.42f, 0.45f, 1 }, dif[4] = { 0.70f, 0.68f, 0.64f, 1 };
        GLfloat pos[4] = { (GLfloat)v->sun[0], (GLfloat)v->sun[2], (GLfloat)v->sun[1], 0 };
        glEnable(GL_LIGHTING);
        glEnable(GL_LIGHT0);
        glLightModelfv(GL_LIGHT_MODEL_AMBIENT, zero);
        glLightfv(GL_LIGHT0, GL_AMBIENT, amb);
        glLightfv(GL_LIGHT0, GL_DIFFUSE, dif);
        glLightfv(GL_LIGHT0, GL_SPECULAR, zero);
        glLightfv(GL_LIGHT0, GL_POSITION, pos); /* direction, through the view matrix */
        glEnable(GL_COLOR_MATERIAL);
        glColorMaterial(GL_FRONT_AND_BACK, GL_AMBIENT_AND_DIFFUSE);
        glTexEnvi(GL_TEXTURE_ENV, GL_TEXTURE_ENV_MODE, GL_MODULATE);
    } else {
        glTexEnvi(GL_TEXTURE_ENV, GL_TEXTURE_ENV_MODE, GL_REPLACE);
    }
    if (v->fog && !v->ortho) {
        GLfloat fc[4] = { sky_horizon[0], sky_horizon[1], sky_horizon[2], 1 };
        glEnable(GL_FOG);
        glFogi(GL_FOG_MODE, GL_LINEAR);
        glFogf(GL_FOG_START, (GLfloat)v->fog_start);
        glFogf(GL_FOG_END, (GLfloat)v->fog_end);
        glFogfv(GL_FOG_COLOR, fc);
    }

    glEnableClientState(GL_VERTEX_ARRAY);
    glEnableClientState(GL_NORMAL_ARRAY);
    glEnableClientState(GL_TEXTURE_COORD_ARRAY);
    return 0;
}

/* The frame's end: state back, glFinish, GL errors. */
static int draw_end(char *err, size_t err_size)
{
    glMatrixMode(GL_TEXTURE);
    glLoadIdentity();
    glDisableClientState(GL_VERTEX_ARRAY);
    glDisableClientState(GL_NORMAL_ARRAY);
    glDisableClientState(GL_TEXTURE_COORD_ARRAY);
    glDisable(GL_LIGHTING);
    glDisable(GL_FOG);
    glDisable(GL_TEXTURE_2D);
    glFinish();
    if (glGetError() != GL_NO_ERROR) { set_err(err, err_size, "drawing failed (GL error)"); return 1; }
    return 0;
}

int rg_draw(rg_renderer *r, const rg_view *v, const float *vertices, const float *normals, size_t nv,
            const uint32_t *indices, size_t ni, char *err, size_t err_size)
{
    if (draw_begin(r, v, vertices, normals, nv, err, err_size)) return 1;
    size_t ntri = ni / 3;
    if (r->ntx * r->nty == 1) {
        glBindTexture(GL_TEXTURE_2D, r->tex[0]);
        glMatrixMode(GL_TEXTURE);
        glLoadIdentity();
        glVertexPointer(3, GL_FLOAT, 0, r->pos);
        glNormalPointer(GL_FLOAT, 0, r->nrm);
        glTexCoordPointer(2, GL_FLOAT, 0, r->uv);
        glDrawElements(GL_TRIANGLES, (GLsizei)ni, GL_UNSIGNED_INT, indices);
    } else {
        for (uint32_t ty = 0; ty < r->nty; ty++)
            for (uint32_t tx = 0; tx < r->ntx; tx++) {
                double x0 = (double)tx * r->core, y0 = (double)ty * r->core;
                double x1 = fmin(x0 + r->core, r->tex_w), y1 = fmin(y0 + r->core, r->tex_h);
                if (clip_tile(r, indices, ntri, x0, x1, y0, y1)) {
                    set_err(err, err_size, "out of memory clipping the mesh to texture tiles");
                    return 1;
                }
                if (!r->clip_n) continue;
                /* texels -> this tile's texture [0,1], border included */
                double tw = (x1 - x0) + 2.0 * r->border, th = (y1 - y0) + 2.0 * r->border;
                glBindTexture(GL_TEXTURE_2D, r->tex[ty * r->ntx + tx]);
                glMatrixMode(GL_TEXTURE);
                glLoadIdentity();
                glScaled(1.0 / tw, 1.0 / th, 1.0);
                glTranslated(r->border - x0, r->border - y0, 0.0);
                glVertexPointer(3, GL_FLOAT, CV * sizeof(float), r->clip);
                glNormalPointer(GL_FLOAT, CV * sizeof(float), r->clip + 3);
                glTexCoordPointer(2, GL_FLOAT, CV * sizeof(float), r->clip + 6);
                glDrawArrays(GL_TRIANGLES, 0, (GLsizei)r->clip_n);
            }
    }
    return draw_end(err, err_size);
}

int rg_vt_slots(rg_renderer *r, uint32_t slots, uint32_t side, char *err, size_t err_size)
{
    r->vt_tex = calloc(slots, sizeof *r->vt_tex);
    r->vt_made = calloc(slots, 1);
    if (!r->vt_tex || !r->vt_made) { set_err(err, err_size, "out of memory for the tile slots"); return 1; }
    glGenTextures((GLsizei)slots, r->vt_tex);
    r->vt_slots = slots;
    r->vt_side = side;
    return 0;
}

int rg_vt_upload(rg_renderer *r, uint32_t slot, const uint8_t *rgba, char *err, size_t err_size)
{
    if (slot >= r->vt_slots) { set_err(err, err_size, "tile slot out of range"); return 1; }
    glBindTexture(GL_TEXTURE_2D, r->vt_tex[slot]);
    if (!r->vt_made[slot]) { /* the slot's storage, on its first tile */
        /* mip levels of the tile made by GL on every upload (GL 1.4): the vt's level is
         * at least as fine as a screen pixel, the mips take what is finer */
        glTexParameteri(GL_TEXTURE_2D, GL_GENERATE_MIPMAP, GL_TRUE);
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, (GLsizei)r->vt_side, (GLsizei)r->vt_side, 0, GL_RGBA,
                     GL_UNSIGNED_BYTE, rgba);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
        r->vt_made[slot] = 1;
    } else
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, (GLsizei)r->vt_side, (GLsizei)r->vt_side, GL_RGBA, GL_UNSIGNED_BYTE,
                        rgba);
    if (glGetError() != GL_NO_ERROR) { set_err(err, err_size, "tile upload failed (GL error)"); return 1; }
    return 0;
}

int rg_draw_vt(rg_renderer *r, const rg_view *v, const float *vertices, const float *normals, size_t nv,
               const uint32_t *indices, size_t ni, uint32_t tex_w, uint32_t tex_h, const rg_vt_draw_tile *tiles,
               size_t ntiles, char *err, size_t err_size)
{
    if (draw_begin(r, v, vertices, normals, nv, err, err_size)) return 1;
    r->tex_w = tex_w;
    r->tex_h = tex_h;
    for (size_t k = 0; k < ntiles; k++) {
        const rg_vt_draw_tile *t = &tiles[k];
        if (t->slot >= r->vt_slots || !r->vt_made[t->slot]) continue;
        if (clip_tile(r, indices, ni / 3, t->x0, t->x1, t->y0, t->y1)) {
            set_err(err, err_size, "out of memory clipping the mesh to texture tiles");
            return 1;
        }
        if (!r->clip_n) continue;
        /* finest texels -> the tile's [0,1]: (texel / scale - origin) / side */
        glBindTexture(GL_TEXTURE_2D, r->vt_tex[t->slot]);
        glMatrixMode(GL_TEXTURE);
        glLoadIdentity();
        glScaled(1.0 / r->vt_side, 1.0 / r->vt_side, 1.0);
        glTranslated(-t->ox, -t->oy, 0.0);
        glScaled(1.0 / t->scale, 1.0 / t->scale, 1.0);
        glVertexPointer(3, GL_FLOAT, CV * sizeof(float), r->clip);
        glNormalPointer(GL_FLOAT, CV * sizeof(float), r->clip + 3);
        glTexCoordPointer(2, GL_FLOAT, CV * sizeof(float), r->clip + 6);
        glDrawArrays(GL_TRIANGLES, 0, (GLsizei)r->clip_n);
    }
    return draw_end(err, err_size);
}

void rg_read_current(uint32_t w, uint32_t h, uint8_t *out)
{
    glReadPixels(0, 0, (GLsizei)w, (GLsizei)h, GL_RGBA, GL_UNSIGNED_BYTE, out);
    size_t row = (size_t)w * 4;
    for (uint32_t y = 0; y < h / 2; y++) { /* GL rows run bottom-up */
        uint8_t *a = out + row * y, *b = out + row * (h - 1 - y);
        for (size_t k = 0; k < row; k++) {
            uint8_t t = a[k];
            a[k] = b[k];
            b[k] = t;
        }
    }
}

void rg_read_rgba(rg_renderer *r, uint8_t *out) { rg_read_current(r->w, r->h, out); }

#else
/* Without OSMesa nothing here is compiled (cli/render.c prints why). */
typedef int rg_no_osmesa_in_this_build;
#endif
