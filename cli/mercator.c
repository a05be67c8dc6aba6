/* `roadsplat tiles --tiling mercator` (docs/tiles.md "Tiling"): the finest
 * tiles of a Web Mercator (EPSG:3857) XYZ pyramid resampled from the splat
 * in the DEM's CRS.
 *
 * - The finest level zmax: the zoom whose pixel on the ground, at the
 *   DEM's centre, is just finer than the pixel the options ask for (as
 *   gdal2tiles picks it), or --zoom.
 * - The splat the tiles are sampled from has texels such that its pixel is
 *   no larger than a finest tile pixel anywhere on the map (the ground
 *   size of a mercator pixel shrinks with cos(latitude)), so the bilinear
 *   filter never skips a source pixel.
 * - A tile: the centres of its pixels taken back to the DEM's CRS through
 *   GDAL/PROJ (the transformer is in the GDAL module), the window of the
 *   splat around them rendered (rs_splat_window: a byte-identical crop of
 *   the whole image), each pixel the alpha-weighted bilinear sample there;
 *   pixels whose centre falls outside the texture are transparent. */
/* realpath() is XSI */
#ifndef _XOPEN_SOURCE
#define _XOPEN_SOURCE 700
#endif
#include "mercator.h"
#include "gis.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

typedef void *(*proj_open_fn)(const char *, const char *);
typedef void (*proj_transform_fn)(void *, int, size_t, double *, double *);
typedef void (*proj_close_fn)(void *);

struct cli_merc {
    cli_merc_grid g;
    const cli_splat_input *in;
    void *proj;
    proj_transform_fn transform;
    proj_close_fn close;
    uint32_t S;
    uint32_t rw, rh;  /* the splat's image at g.texels */
    double gx0, gy0, px; /* its top-left corner (world, y north) and pixel size */
    double *u, *v;    /* per tile pixel: its centre in source pixel coordinates */
    uint8_t *win;     /* the rendered window, RGBA */
    uint16_t *wt;     /* its road weights */
    size_t win_cap;
};

static double res_at(uint32_t S, uint32_t z) { return 2 * CLI_MERC_HALF / ((double)S * (double)((uint64_t)1 << z)); }

static double lat_of(double my) { return atan(sinh(my / 6378137.0)) * (180.0 / PI); }

static void *gdal_sym(const char *name)
{
    return cli_module_symbol("gdal", name, "--tiling mercator");
}

int cli_merc_open(const cli_splat_input *in, const char *dem_path, uint32_t tile, uint32_t user_texels,
                  int zoom_min, int zoom_max, cli_merc **out, cli_merc_grid *grid)
{
    *out = NULL;
    if (!in->geo.georef || !in->geo.crs) {
        cli_error("%s: --tiling mercator needs a DEM with a CRS (a GeoTIFF or another georeferenced raster GDAL "
                  "reads); this one has %s: use --tiling raster, or give it one: gdal_translate -a_srs EPSG:XXXX "
                  "-a_ullr ...",
                  dem_path, in->geo.georef ? "no CRS" : "no georeference");
        return 1;
    }
#ifndef RS_WITH_GDAL
    cli_error("--tiling mercator: this build has no GDAL support (install libgdal-dev, or run 'make deps', and rebuild)");
    return 1;
#else
    void *so = gdal_sym("cli_merc_proj_open"), *st = so ? gdal_sym("cli_merc_proj_transform") : NULL,
         *sc = st ? gdal_sym("cli_merc_proj_close") : NULL;
    if (!sc) return 1;
    cli_merc *m = calloc(1, sizeof *m);
    if (!m) {
        cli_error("out of memory");
        return 1;
    }
    proj_open_fn popen_;
    memcpy(&popen_, &so, sizeof popen_);
    memcpy(&m->transform, &st, sizeof m->transform);
    memcpy(&m->close, &sc, sizeof m->close);
    m->in = in;
    m->S = tile;
    if (!(m->proj = popen_(in->geo.crs, dem_path))) {
        free(m);
        return 1;
    }
    cli_merc_grid *g = &m->g;
    rs_dem_frame fr;
    rs_dem_get_frame(in->dem, &fr);
    double cs = fr.cell_size > 0 ? fr.cell_size : 1;
    /* the texture covers the cells between the DEM's sample centres */
    double X0 = in->wx0, Y1 = in->wy0;
    double X1 = X0 + (rs_dem_width(in->dem) - 1) * cs, Y0 = Y1 - (rs_dem_height(in->dem) - 1) * cs;
    enum { N = 64 }; /* the border, densified: a UTM square is curved in mercator */
    double bx[4 * N + 1], by[4 * N + 1];
    for (int i = 0; i < N; i++) {
        double t = (double)i / N;
        bx[i] = X0 + t * (X1 - X0), by[i] = Y0;
        bx[N + i] = X1, by[N + i] = Y0 + t * (Y1 - Y0);
        bx[2 * N + i] = X1 - t * (X1 - X0), by[2 * N + i] = Y1;
        bx[3 * N + i] = X0, by[3 * N + i] = Y1 - t * (Y1 - Y0);
    }
    bx[4 * N] = (X0 + X1) / 2, by[4 * N] = (Y0 + Y1) / 2;
    m->transform(m->proj, 0, 4 * N + 1, bx, by);
    g->m[0] = g->m[1] = INFINITY, g->m[2] = g->m[3] = -INFINITY;
    for (int i = 0; i < 4 * N + 1; i++) {
        if (isnan(bx[i])) {
            cli_error("%s: --tiling mercator: a point of the DEM's border has no place in EPSG:3857 (beyond 85 "
                      "degrees of latitude, or a CRS PROJ cannot transform)", dem_path);
            cli_merc_close(m);
            return 1;
        }
        g->m[0] = fmin(g->m[0], bx[i]), g->m[2] = fmax(g->m[2], bx[i]);
        g->m[1] = fmin(g->m[1], by[i]), g->m[3] = fmax(g->m[3], by[i]);
    }
    if (g->m[1] < -CLI_MERC_HALF || g->m[3] > CLI_MERC_HALF) {
        cli_error("%s: --tiling mercator: the DEM reaches beyond the Web Mercator square (85.05 degrees of latitude)",
                  dem_path);
        cli_merc_close(m);
        return 1;
    }
    for (int k = 0; k < 4; k += 2) g->ll[k] = g->m[k] / CLI_MERC_HALF * 180.0, g->ll[k + 1] = lat_of(g->m[k + 1]);
    g->centre[0] = bx[4 * N] / CLI_MERC_HALF * 180.0, g->centre[1] = lat_of(by[4 * N]);
    double cosc = cos(g->centre[1] * PI / 180);
    double want = cs / (user_texels ? user_texels : 8); /* the pixel the options ask for */
    uint32_t z = 0;
    if (zoom_max >= 0) z = (uint32_t)zoom_max;
    else
        while (z < 24 && res_at(tile, z) * cosc > want * (1 + 1e-9)) z++;
    g->zmax = z;
    g->zd = 0;
    while (g->zd < z && res_at(tile, g->zd) * cosc > cs * (1 + 1e-9)) g->zd++;
    double res = res_at(tile, z);
    g->pixel_m = res * cosc;
    /* the splat's texels: its pixel no larger than a tile pixel at the
     * footprint's latitude farthest from the equator */
    double latmax = fmax(fabs(g->ll[1]), fabs(g->ll[3])) * PI / 180;
    double t = ceil(cs / (res * cos(latmax)) - 1e-9);
    if (t > 1024) {
        cli_error("%s: --tiling mercator: zoom %u needs the splat at %.0f texels per %.10g m DEM cell (the limit is "
                  "1024): choose a smaller --zoom", dem_path, z, t, cs);
        cli_merc_close(m);
        return 1;
    }
    g->texels = t < 1 ? 1 : (uint32_t)t;
    /* the finest tiles that meet the footprint */
    double span = (double)tile * res, ntiles = (double)((uint64_t)1 << z);
    double tx0 = floor((g->m[0] + CLI_MERC_HALF) / span), tx1 = floor((g->m[2] + CLI_MERC_HALF) / span);
    double ty0 = floor((CLI_MERC_HALF - g->m[3]) / span), ty1 = floor((CLI_MERC_HALF - g->m[1]) / span);
    tx0 = fmax(0, tx0), ty0 = fmax(0, ty0), tx1 = fmin(ntiles - 1, tx1), ty1 = fmin(ntiles - 1, ty1);
    g->fx0 = (uint64_t)tx0, g->fy0 = (uint64_t)ty0;
    g->nx = (uint64_t)(tx1 - tx0) + 1, g->ny = (uint64_t)(ty1 - ty0) + 1;
    /* the first level written: where the footprint is about one tile wide (gdal2tiles' choice) */
    double wide = fmax(g->m[2] - g->m[0], g->m[3] - g->m[1]) / res / tile;
    uint32_t up = 0;
    while (up < z && (double)((uint64_t)1 << up) < wide) up++;
    g->zmin = zoom_min >= 0 ? (uint32_t)zoom_min : z - up;
    if (g->zmin > z) {
        cli_error("--zoom: the first level %u is finer than the last %u", g->zmin, z);
        cli_merc_close(m);
        return 1;
    }
    if (g->zd > z) g->zd = z;
    if (g->zd < g->zmin) g->zd = g->zmin;
    /* the source splat's frame */
    m->px = cs / g->texels;
    m->gx0 = X0, m->gy0 = Y1;
    m->rw = (uint32_t)((rs_dem_width(in->dem) - 1) * (uint64_t)g->texels);
    m->rh = (uint32_t)((rs_dem_height(in->dem) - 1) * (uint64_t)g->texels);
    size_t n = (size_t)tile * tile;
    if (!(m->u = malloc(n * sizeof *m->u)) || !(m->v = malloc(n * sizeof *m->v))) {
        cli_error("out of memory");
        cli_merc_close(m);
        return 1;
    }
    *grid = *g;
    *out = m;
    return 0;
#endif
}

void cli_merc_close(cli_merc *m)
{
    if (!m) return;
    if (m->proj) m->close(m->proj);
    free(m->u);
    free(m->v);
    free(m->win);
    free(m->wt);
    free(m);
}

/* The tile's pixel centres in the DEM's CRS (m->u, m->v) interpolated
 * bilinearly between exact transforms every G pixels, as GDAL's approximate
 * transformer does: the projection is smooth at that scale. Checked at the
 * middle of every grid cell (where the interpolation is worst) against the
 * exact transform: 0 when all are within 0.01 of a source pixel, else 1
 * (the caller transforms every pixel). */
enum { G = 16, GN = 1024 / G + 1 };
static int approx_centres(cli_merc *m, double ox, double oy, double res)
{
    uint32_t S = m->S, n = S / G + 1;
    double gx[GN * GN], gy[GN * GN], cx[GN * GN], cy[GN * GN];
    for (uint32_t j = 0; j < n; j++)
        for (uint32_t i = 0; i < n; i++) {
            gx[j * n + i] = ox + (i * G + 0.5) * res, gy[j * n + i] = oy - (j * G + 0.5) * res;
            if (i + 1 < n && j + 1 < n)
                cx[j * (n - 1) + i] = ox + (i * G + G / 2 + 0.5) * res, cy[j * (n - 1) + i] = oy - (j * G + G / 2 + 0.5) * res;
        }
    m->transform(m->proj, 1, (size_t)n * n, gx, gy);
    m->transform(m->proj, 1, (size_t)(n - 1) * (n - 1), cx, cy);
    double tol = 0.01 * m->px;
    for (uint32_t j = 0; j + 1 < n; j++)
        for (uint32_t i = 0; i + 1 < n; i++) {
            const double *a = gx + j * n + i, *b = gy + j * n + i;
            double ix = (a[0] + a[1] + a[n] + a[n + 1]) / 4, iy = (b[0] + b[1] + b[n] + b[n + 1]) / 4;
            double ex = cx[j * (n - 1) + i], ey = cy[j * (n - 1) + i];
            if (!(fabs(ix - ex) <= tol && fabs(iy - ey) <= tol)) return 1; /* NaN too */
        }
    for (uint32_t y = 0; y < S; y++) {
        uint32_t j = y / G;
        double fy = (double)(y - j * G) / G;
        for (uint32_t x = 0; x < S; x++) {
            uint32_t i = x / G;
            double fx = (double)(x - i * G) / G;
            size_t k = (size_t)j * n + i;
            m->u[(size_t)y * S + x] = (1 - fy) * ((1 - fx) * gx[k] + fx * gx[k + 1]) + fy * ((1 - fx) * gx[k + n] + fx * gx[k + n + 1]);
            m->v[(size_t)y * S + x] = (1 - fy) * ((1 - fx) * gy[k] + fx * gy[k + 1]) + fy * ((1 - fx) * gy[k + n] + fx * gy[k + n + 1]);
        }
    }
    return 0;
}

int cli_merc_tile(cli_merc *m, const rs_splatter *sp, const cli_splat_args *s, uint64_t x, uint64_t y,
                  uint8_t *rgba, int *has_road)
{
    uint32_t S = m->S;
    size_t n = (size_t)S * S;
    double res = res_at(S, m->g.zmax);
    double ox = -CLI_MERC_HALF + (double)x * S * res, oy = CLI_MERC_HALF - (double)y * S * res;
    if (approx_centres(m, ox, oy, res)) { /* exact, pixel by pixel */
        for (uint32_t j = 0; j < S; j++)
            for (uint32_t i = 0; i < S; i++) {
                m->u[(size_t)j * S + i] = ox + (i + 0.5) * res;
                m->v[(size_t)j * S + i] = oy - (j + 0.5) * res;
            }
        m->transform(m->proj, 1, n, m->u, m->v);
    }
    /* to the splat's pixel coordinates, pixel centres at whole numbers */
    double umin = INFINITY, umax = -INFINITY, vmin = INFINITY, vmax = -INFINITY;
    for (size_t k = 0; k < n; k++) {
        double u = (m->u[k] - m->gx0) / m->px - 0.5, v = (m->gy0 - m->v[k]) / m->px - 0.5;
        if (!(u >= -0.5 && u < m->rw - 0.5 && v >= -0.5 && v < m->rh - 0.5)) u = v = NAN; /* outside: transparent */
        m->u[k] = u, m->v[k] = v;
        if (u == u) umin = fmin(umin, u), umax = fmax(umax, u), vmin = fmin(vmin, v), vmax = fmax(vmax, v);
    }
    memset(rgba, 0, n * 4);
    *has_road = 0;
    if (!(umin <= umax)) return 0;
    int64_t wx0 = (int64_t)floor(umin), wy0 = (int64_t)floor(vmin);
    int64_t wx1 = (int64_t)floor(umax) + 1, wy1 = (int64_t)floor(vmax) + 1;
    if (wx0 < 0) wx0 = 0;
    if (wy0 < 0) wy0 = 0;
    if (wx1 > (int64_t)m->rw - 1) wx1 = m->rw - 1;
    if (wy1 > (int64_t)m->rh - 1) wy1 = m->rh - 1;
    uint32_t ww = (uint32_t)(wx1 - wx0 + 1), wh = (uint32_t)(wy1 - wy0 + 1);
    size_t wn = (size_t)ww * wh;
    if (wn > m->win_cap) {
        free(m->win);
        free(m->wt);
        m->win_cap = 0;
        if (!(m->win = malloc(wn * 4)) || !(m->wt = malloc(wn * sizeof *m->wt))) {
            cli_error("out of memory for a tile's window (%u x %u pixels)", ww, wh);
            return 1;
        }
        m->win_cap = wn;
    }
    cli_splat_job job;
    cli_splat_job_init(&job, sp, s, 1);
    job.texels = m->g.texels;
    job.x0 = (uint32_t)wx0, job.y0 = (uint32_t)wy0, job.w = ww, job.h = wh;
    job.rgba = m->win;
    job.weight = m->wt;
    job.nodata = m->in->nodata;
    job.dem_w = rs_dem_width(m->in->dem), job.dem_h = rs_dem_height(m->in->dem);
    if (cli_splat_run(&job)) return 1;
    int road = 0;
    for (size_t k = 0; k < n; k++) {
        double u = m->u[k], v = m->v[k];
        if (u != u) continue;
        double fx0 = floor(u), fy0 = floor(v), fx = u - fx0, fy = v - fy0;
        int64_t ix[2] = { (int64_t)fx0, (int64_t)fx0 + 1 }, iy[2] = { (int64_t)fy0, (int64_t)fy0 + 1 };
        for (int q = 0; q < 2; q++) { /* clamp to the window (the image's edge pixels extend half a pixel) */
            ix[q] = ix[q] < wx0 ? wx0 : ix[q] > wx1 ? wx1 : ix[q];
            iy[q] = iy[q] < wy0 ? wy0 : iy[q] > wy1 ? wy1 : iy[q];
        }
        double wts[4] = { (1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy };
        double A = 0, C[3] = { 0, 0, 0 };
        for (int q = 0; q < 4; q++) {
            if (wts[q] <= 0) continue;
            size_t p = (size_t)(iy[q >> 1] - wy0) * ww + (size_t)(ix[q & 1] - wx0);
            const uint8_t *src = m->win + 4 * p;
            double wa = wts[q] * src[3];
            A += wa;
            for (int c = 0; c < 3; c++) C[c] += wa * src[c];
            if (m->wt[p]) road = 1;
        }
        uint8_t *o = rgba + 4 * k;
        int a = (int)floor(A + 0.5);
        if (a <= 0) continue;
        for (int c = 0; c < 3; c++) {
            double val = floor(C[c] / A + 0.5);
            o[c] = (uint8_t)(val < 0 ? 0 : val > 255 ? 255 : val);
        }
        o[3] = (uint8_t)(a > 255 ? 255 : a);
    }
    *has_road = road;
    return 0;
}

void cli_merc_bounds_text(const cli_merc_grid *g, char *buf, size_t cap)
{
    snprintf(buf, cap, "%.9f,%.9f,%.9f,%.9f", g->ll[0], g->ll[1], g->ll[2], g->ll[3]);
}

void cli_merc_center_text(const cli_merc_grid *g, char *buf, size_t cap)
{
    uint32_t z = g->zmin + (g->zmax - g->zmin + 1) / 2;
    snprintf(buf, cap, "%.9f,%.9f,%u", g->centre[0], g->centre[1], z);
}

int cli_tiles_gdal_xml(const char *outdir, const double ul[2], double px, uint32_t zmax,
                       uint32_t tile, int tms, const char *crs)
{
    char *abs = realpath(outdir, NULL);
    size_t n = strlen(outdir) + 16;
    char *path = malloc(n);
    if (!abs || !path) {
        cli_error("%s: %s", outdir, abs ? "out of memory" : strerror(errno));
        free(abs);
        free(path);
        return 1;
    }
    snprintf(path, n, "%s/tiles.xml", outdir);
    cli_out o;
    memset(&o, 0, sizeof o);
    if (cli_out_open(&o, path)) {
        free(abs);
        free(path);
        return 1;
    }
    FILE *f = o.f;
    double side = (double)tile * (double)((uint64_t)1 << zmax) * px; /* the level-0 tile's square */
    fprintf(f, "<GDAL_WMS>\n  <!-- written by roadsplat tiles: open with gdalinfo or QGIS (docs/tiles.md) -->\n");
    fprintf(f, "  <Service name=\"TMS\">\n    <ServerUrl>file://");
    for (const char *p = abs; *p; p++) { /* an XML text and a URL path */
        unsigned char c = (unsigned char)*p;
        if (c == '&') fputs("&amp;", f);
        else if (c == '<') fputs("&lt;", f);
        else if (c == '>') fputs("&gt;", f);
        else if (c <= ' ' || c >= 0x7f || c == '%' || c == '#' || c == '?' || c == '$') fprintf(f, "%%%02X", c);
        else fputc(c, f);
    }
    fprintf(f, "/${z}/${x}/${y}.png</ServerUrl>\n  </Service>\n");
    fprintf(f, "  <DataWindow>\n    <UpperLeftX>%.17g</UpperLeftX>\n    <UpperLeftY>%.17g</UpperLeftY>\n", ul[0], ul[1]);
    fprintf(f, "    <LowerRightX>%.17g</LowerRightX>\n    <LowerRightY>%.17g</LowerRightY>\n", ul[0] + side, ul[1] - side);
    fprintf(f, "    <TileLevel>%u</TileLevel>\n    <TileCountX>1</TileCountX>\n    <TileCountY>1</TileCountY>\n", zmax);
    fprintf(f, "    <YOrigin>%s</YOrigin>\n  </DataWindow>\n", tms ? "bottom" : "top");
    fprintf(f, "  <Projection>");
    for (const char *p = crs; *p; p++) {
        if (*p == '&') fputs("&amp;", f);
        else if (*p == '<') fputs("&lt;", f);
        else if (*p == '>') fputs("&gt;", f);
        else fputc(*p, f);
    }
    fprintf(f, "</Projection>\n  <BlockSizeX>%u</BlockSizeX>\n  <BlockSizeY>%u</BlockSizeY>\n  <BandsCount>4</BandsCount>\n",
            tile, tile);
    fprintf(f, "  <ZeroBlockHttpCodes>204,404</ZeroBlockHttpCodes>\n  <ZeroBlockOnServerException>true</ZeroBlockOnServerException>\n"
               "</GDAL_WMS>\n");
    free(abs);
    free(path);
    if (fflush(f) != 0 || ferror(f)) {
        cli_error("%s: write failed: %s", o.path, strerror(errno ? errno : EIO));
        cli_out_abort(&o);
        return 1;
    }
    return cli_out_commit(&o);
}
