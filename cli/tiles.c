/* `roadsplat tiles [options] DEM ROADS OUTDIR`: the texture as a tile
 * pyramid, OUTDIR/{z}/{x}/{y}.png (or one MBTiles file), streamed through
 * a quadtree so that memory does not grow with the map (docs/tiles.md).
 *
 * - The finest level zmax is the splat at its texel size; its tile (x, y)
 *   is the window [xS, (x+1)S) x [yS, (y+1)S) of the whole image (S = tile
 *   size), rendered by rs_splat_window, whose windows are byte-identical
 *   to the whole image. Pixels beyond the image are transparent (0,0,0,0).
 * - Every coarser tile is the 2x2 box filter of its four children (alpha-
 *   weighted colour, so transparent padding does not darken edges); no
 *   level re-renders the scene. z = 0 is the level where the image fits in
 *   one tile.
 * - Tiles are visited depth first in Morton (Z) order: a parent is built
 *   as soon as its four children are, so at most one tile buffer per level
 *   is alive (levels x S^2 x 4 bytes).
 * - Sparse: on levels finer than zd (the coarsest level whose pixel is no
 *   larger than a DEM cell) a tile is written only when it holds a road;
 *   road-free ones are computed in memory for their parent. A level-zd
 *   tile that no road's reach meets is terrain only: rendered directly at
 *   its own pixel size (the splat at T / 2^(zmax - zd) texels), nothing
 *   under it rendered (route_setup).
 * - Layers: the colour, and with --normals the normal map ({y}_n.png; the
 *   coarser tiles the renormalised mean of the children's vectors). With
 *   --halo P each file carries P pixels of the same level's image around
 *   the tile (level_rect), the parent is built from the children's cores.
 * - Runs: --shard I/N takes a contiguous run of the finest tiles in Morton
 *   order, of equal count or, with terrain-only tiles, equal work (and
 *   every coarser tile whose subtree lies inside it); each run
 *   appends a line per finished tile to OUTDIR/.tiles-log/NAME.log, after
 *   the tile's atomic rename. --resume and --from-children read every log
 *   there, skip tiles whose file still has the logged SHA-256, and build
 *   what is missing; --from-children renders no finest tile that holds a
 *   road (they must come from the shards). A whole run and --from-children
 *   end by writing tiles.json, the manifest. */
#include "png.h"
#include "gis.h"
#include "sha256.h"
#include "tiles.h"

#include <dirent.h>
#include <pthread.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>
#include <zlib.h>

#include "mercator.h"
#include "viewer.h"

static const char tiles_usage[] =
    "Usage: roadsplat tiles [options] DEM ROADS OUTDIR\n"
    "       roadsplat tiles --format mbtiles [options] DEM ROADS OUT.mbtiles\n"
    "\n"
    "Writes the texture of `roadsplat DEM ROADS OUT.png` as a tile pyramid:\n"
    "OUTDIR/{z}/{x}/{y}.png, the finest level at the splat's texel size, z = 0\n"
    "the level where the whole image fits one tile, each coarser tile the 2x2\n"
    "box filter of its four children; OUTDIR/tiles.json lists the levels, the\n"
    "frame, the inputs' and every tile's SHA-256 (docs/tiles.md).\n"
    "\n"
    "Options (and every splat option of roadsplat --help but --window*,\n"
    "--weight-out, --stats, --world-file, --cog, --rgba):\n"
    "  --tiling raster|mercator  raster (default): the splat's own pixel grid,\n"
    "                     z = 0 the whole image; mercator: XYZ tiles in EPSG:3857\n"
    "                     (the web-map grid), resampled from the DEM's CRS; needs a\n"
    "                     DEM with a CRS (docs/tiles.md \"Tiling\")\n"
    "  --zoom MAX | MIN-MAX  mercator: the finest level (default: the zoom whose\n"
    "                     pixel is just finer than --pixel-size/--texels at the\n"
    "                     map's centre) and the first level written (default: where\n"
    "                     the map is about one tile wide)\n"
    "  --tile-size N      256 (default), 512 or 1024 pixels\n"
    "  --scheme xyz|tms   y down (default) or up (TMS) in the file names\n"
    "  --format png|mbtiles  a folder of PNG files (default) or one MBTiles 1.3\n"
    "                     file (SQLite; needs the module roadsplat-mbtiles.so)\n"
    "  --normals          also the tangent-space normal map, {z}/{x}/{y}_n.png\n"
    "                     (finest tiles = roadsplat --normal-out; coarser: the\n"
    "                     mean of the four children's vectors, renormalised)\n"
    "  --normal-convention gl|dx, --normal-strength S  as for roadsplat --normal-out\n"
    "  --lighting, --sun AZ,ALT, --specular K  lit tiles, as for roadsplat (the\n"
    "                     finest tiles = windows of the lit image)\n"
    "  --halo PX          each tile with a PX-pixel border of its neighbours'\n"
    "                     pixels (S + 2 PX square; 0..128, default 0)\n"
    "  --dense            write every tile (default: on levels finer than a DEM\n"
    "                     cell, only tiles that hold a road)\n"
    "  --render-all       render every finest tile (default: a tile of the finest\n"
    "                     complete level that no road reaches is rendered at its\n"
    "                     own pixel size, and nothing under it)\n"
    "  --shard I/N        render only shard I (0..N-1) of N: a compact run of the\n"
    "                     finest tiles in Morton order; then --from-children\n"
    "  --from-children    build the coarser levels from the shards' tiles on disk\n"
    "                     and write tiles.json\n"
    "  --resume           keep tiles whose file matches its logged SHA-256\n"
    "  --threads N        splat threads and tile workers (box filter, PNG, SHA-256,\n"
    "                     writes; default: all cores; the same bytes for any N)\n"
    "  --png-level N      PNG compression 0..12 (default 1)\n"
    "  --viewer           also OUTDIR/index.html: the pyramid on a Leaflet map\n"
    "                     (Leaflet copied from libjs-leaflet into OUTDIR/leaflet/)\n"
    "  --attribution TEXT the viewer's attribution line (default: rendered with\n"
    "                     roadsplat; name your data's source, e.g. OpenStreetMap)\n"
    "  --quiet, --help\n";

#define LOG_DIR ".tiles-log"
#define OLD_RUNS 8 /* earlier runs of a log whose temporaries are looked for */
#define MAX_ZOOM 24

typedef struct targs {
    cli_splat_args s;
    const char *dem, *roads, *out;
    uint32_t tile;
    int tms, mbtiles, dense, resume, from_children, quiet, sharded;
    int normals, normal_given, conv_given, render_all;
    int viewer;               /* --viewer: OUTDIR/index.html (cli/viewer.c) */
    const char *attribution;  /* --attribution TEXT for the viewer */
    rs_normal_options normal;
    uint32_t halo;
    int mercator;             /* --tiling mercator (cli/mercator.c) */
    int zoom_min, zoom_max;   /* --zoom, -1 when not given */
    uint32_t shard_i, shard_n;
    const char **opt; /* the splat options as given (for the manifest), --threads, --gdal-trust, --max-image-pixels left out */
    int nopt;
} targs;

/* ---- tile table: what the logs say about each tile ---------------------------- */

typedef struct entry {
    uint64_t key;     /* z << 58 | x << 29 | y, +1 (0: empty slot) */
    uint8_t flag;     /* 'r': written, holds a road; 'w': written, road-free; 'e': road-free, not written;
                         'd': written, a terrain-only level-zd tile rendered directly (no subtree) */
    uint8_t checked;  /* 1: the file (and its normal tile) was found to match this run */
    uint8_t has_n;    /* nhash is known (a run with --normals) */
    uint8_t hash[32];
    uint8_t nhash[32]; /* the normal tile's, with --normals */
} entry;

typedef struct table {
    entry *e;
    size_t cap, n;
} table;

static uint64_t tkey(uint32_t z, uint64_t x, uint64_t y) { return ((uint64_t)z << 58 | x << 29 | y) + 1; }

static size_t tslot(const table *t, uint64_t key)
{
    uint64_t h = key * 0x9E3779B97F4A7C15ull;
    size_t i = (size_t)(h >> 17) & (t->cap - 1);
    while (t->e[i].key && t->e[i].key != key) i = (i + 1) & (t->cap - 1);
    return i;
}

static entry *tfind(table *t, uint64_t key)
{
    if (!t->cap) return NULL;
    entry *e = &t->e[tslot(t, key)];
    return e->key ? e : NULL;
}

static entry *tput(table *t, uint64_t key, int flag, const uint8_t *hash, const uint8_t *nhash)
{
    if ((t->n + 1) * 2 > t->cap) {
        size_t nc = t->cap ? t->cap * 2 : 1024;
        entry *ne = calloc(nc, sizeof *ne), *old = t->e;
        if (!ne) return NULL;
        size_t oc = t->cap;
        t->e = ne, t->cap = nc;
        for (size_t i = 0; i < oc; i++)
            if (old[i].key) t->e[tslot(t, old[i].key)] = old[i];
        free(old);
    }
    entry *e = &t->e[tslot(t, key)];
    if (!e->key) t->n++;
    e->key = key;
    e->flag = (uint8_t)flag;
    e->checked = 0;
    if (hash) memcpy(e->hash, hash, 32);
    else memset(e->hash, 0, 32);
    e->has_n = nhash != NULL;
    if (nhash) memcpy(e->nhash, nhash, 32);
    else memset(e->nhash, 0, 32);
    return e;
}

/* ---- the run -------------------------------------------------------------------- */

typedef struct run {
    targs *a;
    const cli_splat_input *in;
    const rs_splatter *sp;
    uint32_t fw, fh, S, T, zmax, zd;
    /* --tiling mercator: the finest tiles are [fx0, fx0 + nx) x [fy0, fy0 + ny)
     * of the global grid, rendered by cli_merc_tile; levels below zmin are
     * only walked through (build), never made nor written */
    cli_merc *merc;
    cli_merc_grid mg;
    uint64_t fx0, fy0;
    uint32_t zmin;
    uint32_t P, side;   /* halo, and a written tile's side S + 2P */
    int layers;         /* 1, or 2 with --normals (layer 1: the normal map) */
    unsigned threads;   /* the splat's thread count (the normal map's too) */
    /* workers run: a tile's colour is rendered on the main thread alone (in
     * bands the render took 2-3x as long on a busy 2-core machine: its threads wait
     * for cores the workers hold, and the workers wait for the render) */
    int one_band;
    /* Terrain-only subtrees (docs/tiles.md, "Sparse levels"): a level-zd tile
     * whose area holds no road's reach is rendered directly by dsp, the same
     * splat at T >> (zmax - zd) texels, and its subtree is never rendered. */
    int route;
    const rs_splatter *dsp;
    uint32_t dw, dh;    /* dsp's image: level zd's image size */
    uint8_t *zfree;     /* per level-zd tile (row-major), 1: no road reaches it */
    uint64_t zx, zy;    /* level-zd tiles per row, column */
    uint64_t direct;    /* tiles rendered directly */
    uint64_t nx, ny;    /* finest tiles per row, column */
    uint64_t lo, hi;    /* this run's finest tiles: Morton ranks [lo, hi) */
    table tab;
    FILE *log;
    char *log_path;
    char fingerprint[65];
    /* temporaries: "DIR/.NAME.<runid>.part", unique to the run; the ids of
     * earlier runs of this log, whose leftovers (a kill) are removed when
     * their tile is made again */
    char runid[17];
    char old_ids[OLD_RUNS][17];
    int n_old;
    const cli_mbtiles_api *mb;
    void *db;
    struct pool *pl;                /* the workers (below; none with --threads 1) */
    uint8_t *lbuf[2][MAX_ZOOM + 2]; /* --halo: per layer, one S x S block per level (level_rect) */
    uint8_t *full;               /* a written tile, side x side RGBA (halo) or a decoded one */
    uint8_t *scratch;            /* a finest render, side x side RGBA */
    uint8_t *nrgb;               /* a finest normal render, side x side RGB */
    char *path;                  /* tile path scratch */
    size_t path_cap;
    uint64_t rendered, written, road_free, kept, done_finest, total_finest;
    cli_progress prog;
} run;

/* Side of a level-z tile in finest tiles, and whether (z, x, y) exists. */
static uint64_t span(const run *r, uint32_t z) { return (uint64_t)1 << (r->zmax - z); }

/* Finest tiles of the image under (z, x, y). */
static uint64_t finest_count(const run *r, uint32_t z, uint64_t x, uint64_t y)
{
    uint64_t k = span(r, z), x0 = x * k, y0 = y * k, ex = r->fx0 + r->nx, ey = r->fy0 + r->ny;
    if (x0 < r->fx0) x0 = r->fx0;
    if (y0 < r->fy0) y0 = r->fy0;
    uint64_t x1 = x * k + k < ex ? x * k + k : ex, y1 = y * k + k < ey ? y * k + k : ey;
    if (x0 >= x1 || y0 >= y1) return 0;
    return (x1 - x0) * (y1 - y0);
}

static int exists(const run *r, uint32_t z, uint64_t x, uint64_t y) { return finest_count(r, z, x, y) > 0; }

static uint64_t file_y(const run *r, uint32_t z, uint64_t y)
{
    return r->a->tms ? (((uint64_t)1 << z) - 1 - y) : y;
}

/* A folder inside OUTDIR, made when missing: a real folder, never a
 * symbolic link someone planted to send tiles elsewhere (lstat). 0, or 1
 * after a message. */
static int own_folder(const char *path)
{
    struct stat st;
    memset(&st, 0, sizeof st);
    if (mkdir(path, 0777) != 0 && errno != EEXIST) {
        cli_error("%s: cannot create the folder: %s", path, strerror(errno));
        return 1;
    }
    if (lstat(path, &st) != 0 || !S_ISDIR(st.st_mode)) {
        cli_error("%s: %s; the tile folders must be real folders (remove it)", path,
                  S_ISLNK(st.st_mode) ? "is a symbolic link" : "is not a folder");
        return 1;
    }
    return 0;
}

/* "OUTDIR/z/x/y.png" (layer 1: "y_n.png") in r->path; with mk, its
 * folders are made. */
static int tile_path_in(const run *r, char **path, size_t *cap, uint32_t z, uint64_t x, uint64_t y, int mk, int layer)
{
    size_t need = strlen(r->a->out) + 80;
    if (need > *cap) {
        free(*path);
        if (!(*path = malloc(need))) {
            *cap = 0;
            cli_error("out of memory");
            return 1;
        }
        *cap = need;
    }
    char *p = *path;
    int n = snprintf(p, need, "%s/%u", r->a->out, z);
    if (mk && own_folder(p)) return 1;
    n += snprintf(p + n, need - n, "/%llu", (unsigned long long)x);
    if (mk && own_folder(p)) return 1;
    snprintf(p + n, need - n, "/%llu%s.png", (unsigned long long)file_y(r, z, y), layer ? "_n" : "");
    return 0;
}

/* The same in r->path (the main thread's). */
static int tile_path(run *r, uint32_t z, uint64_t x, uint64_t y, int mk, int layer)
{
    return tile_path_in(r, &r->path, &r->path_cap, z, x, y, mk, layer);
}

/* ---- PNG bytes: encode into memory, decode our own tiles ------------------------ */

/* The side x side tile as a PNG in memory (*png malloc'd): RGB when every
 * pixel is opaque, else RGBA. */
static int encode_tile(const run *r, uint8_t *rgb, const uint8_t *rgba, uint32_t side, const char *shown, char **png,
                       size_t *size)
{
    size_t n = (size_t)side * side;
    int opaque = 1;
    for (size_t i = 0; i < n && opaque; i++) opaque = rgba[4 * i + 3] == 255;
    if (opaque)
        for (size_t i = 0; i < n; i++) memcpy(rgb + 3 * i, rgba + 4 * i, 3);
    cli_png_image img = { side, side, opaque ? 3 : 4, 8, opaque ? (const void *)rgb : (const void *)rgba };
    cli_png_options po = { r->a->s.png_level_given ? r->a->s.png_level : -1, NULL, NULL, 1 };
    *png = NULL;
    *size = 0;
    FILE *f = open_memstream(png, size);
    if (!f) {
        cli_error("%s: out of memory", shown);
        return 1;
    }
    int bad = cli_png_encode(f, shown, &img, &po);
    if (fclose(f) != 0 && !bad) {
        cli_error("%s: out of memory", shown);
        bad = 1;
    }
    if (bad) {
        free(*png);
        *png = NULL;
    }
    return bad;
}

static uint32_t be32(const uint8_t *p) { return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3]; }

static int paeth(int a, int b, int c)
{
    int p = a + b - c, pa = abs(p - a), pb = abs(p - b), pc = abs(p - c);
    return pa <= pb && pa <= pc ? a : (pb <= pc ? b : c);
}

/* An S x S 8-bit RGB or RGBA PNG (what encode_tile writes) into rgba. */
static int decode_tile(const uint8_t *p, size_t n, uint32_t S, uint8_t *rgba)
{
    static const uint8_t sig[8] = { 0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n' };
    if (n < 8 + 25 || memcmp(p, sig, 8) || memcmp(p + 12, "IHDR", 4)) return 1;
    uint32_t w = be32(p + 16), h = be32(p + 20);
    int bits = p[24], ct = p[25], ch = ct == 2 ? 3 : ct == 6 ? 4 : 0;
    if (w != S || h != S || bits != 8 || !ch || p[28] != 0) return 1;
    size_t rowb = (size_t)S * ch, raw_n = (rowb + 1) * S;
    uint8_t *z = NULL, *raw = malloc(raw_n);
    size_t zn = 0, zcap = 0;
    int bad = !raw;
    for (size_t off = 8; !bad && off + 12 <= n;) {
        uint32_t len = be32(p + off);
        if (len > n - off - 12) { bad = 1; break; }
        const uint8_t *type = p + off + 4;
        if (!memcmp(type, "IDAT", 4)) {
            if (zn + len > zcap) {
                size_t nc = (zn + len) * 2;
                uint8_t *nz = realloc(z, nc);
                if (!nz) { bad = 1; break; }
                z = nz, zcap = nc;
            }
            memcpy(z + zn, p + off + 8, len);
            zn += len;
        }
        off += 12 + (size_t)len;
        if (!memcmp(type, "IEND", 4)) break;
    }
    uLongf got = (uLongf)raw_n;
    if (!bad && (uncompress(raw, &got, z, (uLong)zn) != Z_OK || got != raw_n)) bad = 1;
    for (uint32_t y = 0; !bad && y < S; y++) {
        uint8_t *row = raw + y * (rowb + 1) + 1, *prev = y ? row - (rowb + 1) : NULL;
        int ft = row[-1];
        for (size_t i = 0; i < rowb; i++) {
            int a = i >= (size_t)ch ? row[i - ch] : 0, b = prev ? prev[i] : 0, c = prev && i >= (size_t)ch ? prev[i - ch] : 0;
            int v = ft == 0 ? 0 : ft == 1 ? a : ft == 2 ? b : ft == 3 ? (a + b) / 2 : ft == 4 ? paeth(a, b, c) : -1;
            if (v < 0) { bad = 1; break; }
            row[i] = (uint8_t)(row[i] + v);
        }
        for (uint32_t x = 0; !bad && x < S; x++) {
            uint8_t *o = rgba + ((size_t)y * S + x) * 4;
            memcpy(o, row + (size_t)x * ch, (size_t)ch);
            if (ch == 3) o[3] = 255;
        }
    }
    free(z);
    free(raw);
    return bad;
}

/* ---- pixels ---------------------------------------------------------------------- */

/* The 2x2 box filter of a cw x ch block c (rows cstride pixels apart; cw,
 * ch even) into the (cw/2) x (ch/2) block o (rows ostride pixels apart).
 * Colour (layer 0): alpha the rounded mean, colour the alpha-weighted mean
 * (rounded; all four opaque: (c0 + c1 + c2 + c3 + 2) / 4). Normal map
 * (layer 1): the four decoded vectors (2b - 255 per component), weighted
 * by alpha, summed (s), renormalised and encoded again as
 * floor(s_k * (127.5 / |s|) + 128) = round((n / 2 + 1/2) * 255) in double
 * arithmetic, in this order; alpha as for the colour. */
static void box_rect(int layer, const uint8_t *c, uint32_t cw, uint32_t ch, size_t cstride, uint8_t *o,
                     size_t ostride)
{
    for (uint32_t y = 0; y < ch / 2; y++) {
        const uint8_t *r0 = c + (size_t)(2 * y) * cstride * 4, *r1 = r0 + cstride * 4;
        uint8_t *op = o + (size_t)y * ostride * 4;
        for (uint32_t x = 0; x < cw / 2; x++, r0 += 8, r1 += 8, op += 4) {
            uint32_t a0 = r0[3], a1 = r0[7], a2 = r1[3], a3 = r1[7], A = a0 + a1 + a2 + a3;
            if (A == 0) {
                memset(op, 0, 4);
            } else if (layer) {
                double v[3];
                for (int k = 0; k < 3; k++)
                    v[k] = (double)((long)a0 * (2 * r0[k] - 255) + (long)a1 * (2 * r0[4 + k] - 255) +
                                    (long)a2 * (2 * r1[k] - 255) + (long)a3 * (2 * r1[4 + k] - 255));
                double len = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
                double f = len > 0 ? 127.5 / len : 0; /* byte = n * 127.5 + 128, floored */
                for (int k = 0; k < 3; k++) {
                    double b = v[k] * f + 128.0;
                    op[k] = (uint8_t)(b < 0 ? 0 : b >= 255 ? 255 : (int)b);
                }
                if (len == 0) op[2] = 255;
                op[3] = (uint8_t)((A + 2) >> 2);
            } else if (A == 4 * 255) {
                for (int k = 0; k < 3; k++) op[k] = (uint8_t)((r0[k] + r0[4 + k] + r1[k] + r1[4 + k] + 2) >> 2);
                op[3] = 255;
            } else {
                for (int k = 0; k < 3; k++)
                    op[k] = (uint8_t)((r0[k] * a0 + r0[4 + k] * a1 + r1[k] * a2 + r1[4 + k] * a3 + A / 2) / A);
                op[3] = (uint8_t)((A + 2) >> 2);
            }
        }
    }
}

/* rs_normal_window of a window by bands of rows on the splat's thread
 * count (cli_normal_rgb: the same bytes for any count). */
static int normal_window(const run *r, const rs_splatter *sp, uint32_t x0, uint32_t y0, uint32_t w, uint32_t h,
                         uint8_t *rgb)
{
    unsigned n = r->threads < 1 ? 1 : r->threads > 64 ? 64 : r->threads;
    uint32_t band = (h + n - 1) / n;
    if (band < 16) band = 16;
    char msg[256];
    if (!cli_normal_rgb(sp, &r->a->normal, x0, y0, w, h, n, band, rgb, msg, sizeof msg)) return 0;
    cli_error("normal map: %s", msg);
    return 1;
}

/* Pixels [X0, X0+w) x [Y0, Y0+h) of the finest level's image (w, h <=
 * side; X0, Y0 may lie outside it) into out (rows ostride pixels apart),
 * transparent (0,0,0,0) beyond the image. Layer 0: the splat (with
 * *road_pixels, when not NULL, its road pixel count); layer 1: the normal
 * map, alpha 255. */
static int splat_rect(run *r, int direct, int layer, int64_t X0, int64_t Y0, uint32_t w, uint32_t h, uint8_t *out,
                      size_t ostride, uint64_t *road_pixels)
{
    const rs_splatter *sp = direct ? r->dsp : r->sp;
    int64_t W = direct ? r->dw : r->fw, Hh = direct ? r->dh : r->fh;
    int64_t x0 = X0 < 0 ? 0 : X0, y0 = Y0 < 0 ? 0 : Y0;
    int64_t x1 = X0 + w < W ? X0 + w : W, y1 = Y0 + h < Hh ? Y0 + h : Hh;
    if (road_pixels) *road_pixels = 0;
    for (uint32_t j = 0; j < h; j++) memset(out + (size_t)j * ostride * 4, 0, (size_t)w * 4);
    if (x0 >= x1 || y0 >= y1) return 0;
    uint32_t cw = (uint32_t)(x1 - x0), chh = (uint32_t)(y1 - y0);
    if (layer == 0) {
        cli_splat_job job;
        cli_splat_job_init(&job, sp, &r->a->s, 1);
        if (r->one_band) job.threads = 1;
        if (direct) job.texels = r->T >> (r->zmax - r->zd);
        job.x0 = (uint32_t)x0, job.y0 = (uint32_t)y0, job.w = cw, job.h = chh;
        job.rgba = r->scratch;
        job.nodata = r->in->nodata;
        job.dem_w = rs_dem_width(r->in->dem), job.dem_h = rs_dem_height(r->in->dem);
        if (cli_splat_run(&job)) return 1;
        if (road_pixels) *road_pixels = job.profile.road_pixels;
    } else {
        if (normal_window(r, sp, (uint32_t)x0, (uint32_t)y0, cw, chh, r->nrgb)) return 1;
        for (size_t i = 0, n = (size_t)cw * chh; i < n; i++) {
            memcpy(r->scratch + 4 * i, r->nrgb + 3 * i, 3);
            r->scratch[4 * i + 3] = 255;
        }
    }
    for (uint32_t j = 0; j < chh; j++)
        memcpy(out + ((size_t)(y0 - Y0 + j) * ostride + (size_t)(x0 - X0)) * 4, r->scratch + (size_t)j * cw * 4,
               (size_t)cw * 4);
    return 0;
}

static int finest_rect(run *r, int layer, int64_t X0, int64_t Y0, uint32_t w, uint32_t h, uint8_t *out, size_t ostride,
                       uint64_t *road_pixels)
{
    return splat_rect(r, 0, layer, X0, Y0, w, h, out, ostride, road_pixels);
}

/* Level-zd tile (x, y) is terrain only, rendered directly. */
static int zone_free(const run *r, uint64_t x, uint64_t y)
{
    return r->route && x < r->zx && y < r->zy && r->zfree[y * r->zx + x];
}

static int level_blocks(run *r, int layer, uint32_t z, int64_t X0, int64_t Y0, uint32_t w, uint32_t h, uint8_t *out,
                        size_t ostride);

/* Pixels [X0, X0+w) x [Y0, Y0+h) of level z's image (the finest image
 * box-filtered zmax - z times, transparent beyond it) into out (rows
 * ostride pixels apart): what the tiles of level z hold there. For --halo:
 * blocks of at most S/2 x S/2, each from a 2x block of level z + 1. */
static int level_rect(run *r, int layer, uint32_t z, int64_t X0, int64_t Y0, uint32_t w, uint32_t h, uint8_t *out,
                      size_t ostride)
{
    if (z == r->zmax) return finest_rect(r, layer, X0, Y0, w, h, out, ostride, NULL);
    uint32_t k = r->zmax - z;
    int64_t lw = (int64_t)((r->fw + ((uint64_t)1 << k) - 1) >> k), lh = (int64_t)((r->fh + ((uint64_t)1 << k) - 1) >> k);
    if (X0 >= lw || Y0 >= lh || X0 + w <= 0 || Y0 + h <= 0) {
        for (uint32_t j = 0; j < h; j++) memset(out + (size_t)j * ostride * 4, 0, (size_t)w * 4);
        return 0;
    }
    if (r->route && z == r->zd) { /* piece by piece: a terrain-only tile's pixels are its direct render */
        int64_t S = r->S;
        for (int64_t ty = (Y0 < 0 ? 0 : Y0) / S; ty * S < Y0 + h && ty * S < lh; ty++)
            for (int64_t tx = (X0 < 0 ? 0 : X0) / S; tx * S < X0 + w && tx * S < lw; tx++) {
                int64_t px0 = tx * S > X0 ? tx * S : X0, py0 = ty * S > Y0 ? ty * S : Y0;
                int64_t px1 = (tx + 1) * S < X0 + w ? (tx + 1) * S : X0 + w;
                int64_t py1 = (ty + 1) * S < Y0 + h ? (ty + 1) * S : Y0 + h;
                uint8_t *o = out + ((size_t)(py0 - Y0) * ostride + (size_t)(px0 - X0)) * 4;
                int bad = zone_free(r, (uint64_t)tx, (uint64_t)ty)
                              ? splat_rect(r, 1, layer, px0, py0, (uint32_t)(px1 - px0), (uint32_t)(py1 - py0), o, ostride, NULL)
                              : level_blocks(r, layer, z, px0, py0, (uint32_t)(px1 - px0), (uint32_t)(py1 - py0), o, ostride);
                if (bad) return 1;
            }
        /* the parts beyond the image: transparent */
        for (uint32_t j = 0; j < h; j++)
            for (uint32_t i = 0; i < w; i++)
                if (X0 + i < 0 || Y0 + j < 0 || X0 + i >= lw || Y0 + j >= lh) memset(out + ((size_t)j * ostride + i) * 4, 0, 4);
        return 0;
    }
    return level_blocks(r, layer, z, X0, Y0, w, h, out, ostride);
}

/* level_rect by blocks of at most S/2 x S/2, each the box filter of the
 * 2x block of level z + 1. */
static int level_blocks(run *r, int layer, uint32_t z, int64_t X0, int64_t Y0, uint32_t w, uint32_t h, uint8_t *out,
                        size_t ostride)
{
    uint32_t H = r->S / 2;
    uint8_t *cb = r->lbuf[layer][z + 1];
    for (uint32_t by = 0; by < h; by += H)
        for (uint32_t bx = 0; bx < w; bx += H) {
            uint32_t bw = w - bx < H ? w - bx : H, bh = h - by < H ? h - by : H;
            if (level_rect(r, layer, z + 1, 2 * (X0 + bx), 2 * (Y0 + by), 2 * bw, 2 * bh, cb, 2 * bw)) return 1;
            box_rect(layer, cb, 2 * bw, 2 * bh, 2 * bw, out + ((size_t)by * ostride + bx) * 4, ostride);
        }
    return 0;
}

/* Child (S x S) into quadrant (qx, qy) of parent. */
static void box_down(int layer, const uint8_t *c, uint8_t *parent, uint32_t S, int qx, int qy)
{
    uint32_t h = S / 2;
    box_rect(layer, c, S, S, S, parent + ((size_t)qy * h * S + (size_t)qx * h) * 4, S);
}

/* The finest tile (x, y) of each layer into out[layer]: its window of the
 * image, transparent beyond it. */
static int render_tile(run *r, uint64_t x, uint64_t y, uint8_t *const *out, int *has_road)
{
    uint64_t roads = 0;
    if (r->merc) { /* Web Mercator: resampled from the splat in the DEM's CRS */
        if (cli_merc_tile(r->merc, r->sp, &r->a->s, x, y, out[0], has_road)) return 1;
        r->rendered++;
        return 0;
    }
    for (int l = 0; l < r->layers; l++)
        if (finest_rect(r, l, (int64_t)(x * r->S), (int64_t)(y * r->S), r->S, r->S, out[l], r->S, l ? NULL : &roads))
            return 1;
    *has_road = roads > 0;
    r->rendered++;
    return 0;
}

/* The written form of a level-z tile of one layer whose S x S pixels are
 * core: with --halo, r->full with the P-pixel ring of level z's image
 * around it; else core itself. */
static const uint8_t *with_halo(run *r, int layer, uint32_t z, uint64_t x, uint64_t y, const uint8_t *core)
{
    uint32_t S = r->S, P = r->P, side = r->side;
    if (!P) return core;
    int64_t X = (int64_t)(x * S), Y = (int64_t)(y * S);
    uint8_t *f = r->full;
    for (uint32_t j = 0; j < S; j++) memcpy(f + ((size_t)(P + j) * side + P) * 4, core + (size_t)j * S * 4, (size_t)S * 4);
    if (level_rect(r, layer, z, X - P, Y - P, side, P, f, side) ||
        level_rect(r, layer, z, X - P, Y + S, side, P, f + (size_t)(P + S) * side * 4, side) ||
        level_rect(r, layer, z, X - P, Y, P, S, f + (size_t)P * side * 4, side) ||
        level_rect(r, layer, z, X + S, Y, P, S, f + ((size_t)P * side + P + S) * 4, side))
        return NULL;
    return f;
}

/* ---- writing a tile ------------------------------------------------------------ */

static int write_all(int fd, const char *p, size_t n)
{
    while (n) {
        ssize_t k = write(fd, p, n);
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) return 1;
        p += k, n -= (size_t)k;
    }
    return 0;
}

static int log_line(run *r, uint32_t z, uint64_t x, uint64_t y, int flag, const uint8_t *hash, const uint8_t *nhash)
{
    char hex[65] = "-", nhex[66] = "";
    if (hash) cli_sha256_hex(hash, hex);
    if (nhash) {
        nhex[0] = ' ';
        cli_sha256_hex(nhash, nhex + 1);
    }
    if (fprintf(r->log, "%u %llu %llu %c %s%s\n", z, (unsigned long long)x, (unsigned long long)y, flag, hex, nhex) < 0 ||
        fflush(r->log) != 0) {
        cli_error("%s: write failed: %s", r->log_path, strerror(errno ? errno : EIO));
        return 1;
    }
    return tput(&r->tab, tkey(z, x, y), flag, hash, nhash) ? 0 : (cli_error("out of memory"), 1);
}

/* Every pixel transparent: a mercator tile off the DEM is not written. */
static int all_clear(const uint8_t *rgba, uint32_t S)
{
    for (size_t i = 0, n = (size_t)S * S; i < n; i++)
        if (rgba[4 * i + 3]) return 0;
    return 1;
}

/* ---- the workers ------------------------------------------------------------------
 *
 * With --threads N > 1, N worker threads take the work after a tile's
 * pixels exist: the 2x2 box filter into its parent, PNG compression, the
 * SHA-256 and the file write (docs/tiles.md, "Threads"). The main thread
 * walks the quadtree as before and renders the finest tiles; each tile it
 * finishes becomes a job with a sequence number, and the jobs' results (log
 * lines, MBTiles rows, counters, an error) are committed by the main thread
 * in that order, so every byte of the output is that of one thread. With
 * --threads 1 the main thread runs each job itself when it is queued. */

/* A tile's pixels, S x S RGBA per layer. A parent's are the box filter of
 * its children: each child's job boxes it into its quadrant, and the
 * parent is ready when `pending` (children not yet boxed, +1 while build()
 * adds them) is 0. refs and pending change under the pool's mutex. */
typedef struct pix {
    uint8_t *px[2];
    int refs, pending;
    struct pix *parent;
    int q;
} pix;

typedef struct job {
    pix *p;
    uint32_t z;
    uint64_t x, y;
    /* 0: box into the parent only; 'r', 'w', 'd': store with that flag;
     * 'c': store as 'w' unless every pixel is clear (mercator: then 'e');
     * 'e': log road-free, not written */
    int mode;
    uint8_t *written[2]; /* --halo: the side x side pixels to write (owned); else p's */
    int taken; /* by a worker (they take ready jobs out of order) */
    /* results, read by the commit once done */
    int done, bad, flag;
    uint8_t hash[2][32];
    char *png[2]; /* MBTiles: the tile's PNG, put in order by the commit */
    size_t size[2];
    char err[CLI_ERROR_CAP];
} job;

typedef struct wscratch { /* a thread's own scratch for storing tiles */
    uint8_t *rgb;
    char *path;
    size_t cap;
} wscratch;

typedef struct pool {
    run *r;
    pthread_mutex_t mu, tmu; /* tmu: the CLI's temporary-file registry */
    pthread_cond_t cv;       /* any change: a job queued or done, a pix ready */
    job *ring;               /* jobs by sequence number modulo cap */
    uint64_t cap, head, next, tail; /* [head, tail) queued; head: next to commit; every job before next taken */
    uint64_t fail_seq;       /* the first job that failed (UINT64_MAX: none) */
    int nth, stop, abort;
    pthread_t th[64];
    wscratch ws[65];         /* one per worker; ws[nth] the main thread's */
    struct warg { struct pool *pl; int i; } wa[64];
} pool;

static pix *pix_new(const run *r, int pending)
{
    pix *p = calloc(1, sizeof *p);
    size_t n = (size_t)r->S * r->S * 4;
    if (!p) return NULL;
    p->refs = 1;
    p->pending = pending;
    for (int l = 0; l < r->layers; l++)
        if (!(p->px[l] = pending ? calloc(n, 1) : malloc(n))) {
            free(p->px[0]);
            free(p);
            return NULL;
        }
    return p;
}

static void pix_release(pool *pl, pix *p)
{
    if (!p) return;
    pthread_mutex_lock(&pl->mu);
    int last = --p->refs == 0;
    pthread_mutex_unlock(&pl->mu);
    if (last) {
        free(p->px[0]);
        free(p->px[1]);
        free(p);
    }
}

/* Wait until p's children are all boxed into it. */
static void pix_wait(pool *pl, pix *p)
{
    pthread_mutex_lock(&pl->mu);
    while (p->pending > 0) pthread_cond_wait(&pl->cv, &pl->mu);
    pthread_mutex_unlock(&pl->mu);
}

/* One fewer child to wait for (or build() done adding them). */
static void pix_unhold(pool *pl, pix *p)
{
    pthread_mutex_lock(&pl->mu);
    if (--p->pending == 0) pthread_cond_broadcast(&pl->cv);
    pthread_mutex_unlock(&pl->mu);
}

/* Encode, hash and store one layer of a finished tile: a file renamed into
 * place, or (MBTiles) the PNG kept in *keep for the commit to put. */
static int store_layer(const run *r, pool *pl, wscratch *w, uint32_t z, uint64_t x, uint64_t y, int layer,
                       const uint8_t *px, uint8_t hash[32], char **keep, size_t *keep_size)
{
    char shown[96], *png = NULL;
    size_t size = 0;
    snprintf(shown, sizeof shown, "tile %u/%llu/%llu%s", z, (unsigned long long)x, (unsigned long long)file_y(r, z, y),
             layer ? "_n" : "");
    if (encode_tile(r, w->rgb, px, r->side, shown, &png, &size)) return 1;
    cli_sha256(png, size, hash);
    if (r->db) {
        *keep = png;
        *keep_size = size;
        return 0;
    }
    char *tmp = NULL;
    int fd = -1, bad = tile_path_in(r, &w->path, &w->cap, z, x, y, 1, layer);
    const char *path = w->path;
    if (!bad) { /* "DIR/.NAME.RUNID.part": this run's own, made with O_EXCL | O_NOFOLLOW */
        const char *base = strrchr(path, '/') + 1;
        size_t dl = (size_t)(base - path), cap = strlen(path) + 32;
        if (!(tmp = malloc(cap))) {
            cli_error("out of memory");
            bad = 1;
        } else {
            /* a temporary an earlier, killed run of this log left for this tile */
            for (int k = 0; k < r->n_old; k++) {
                struct stat ls;
                snprintf(tmp, cap, "%.*s.%s.%s.part", (int)dl, path, base, r->old_ids[k]);
                if (lstat(tmp, &ls) == 0 && S_ISREG(ls.st_mode)) unlink(tmp);
            }
            snprintf(tmp, cap, "%.*s.%s.%s.part", (int)dl, path, base, r->runid);
            pthread_mutex_lock(&pl->tmu);
            fd = cli_temp_create_named(tmp);
            int e = errno;
            pthread_mutex_unlock(&pl->tmu);
            if (fd < 0) {
                cli_error("%s: cannot create a temporary file next to it: %s", path, strerror(e));
                bad = 1;
            }
        }
    }
    if (!bad) {
        int e = 0;
        if (write_all(fd, png, size)) e = errno ? errno : EIO;
        if (close(fd) != 0 && !e) e = errno;
        int clash = !e && cli_inputs_check_output(path, "a tile");
        if (!e && !clash && rename(tmp, path) != 0) e = errno;
        pthread_mutex_lock(&pl->tmu);
        if (e || clash)
            cli_temp_remove(tmp);
        else
            cli_temp_forget(tmp);
        pthread_mutex_unlock(&pl->tmu);
        if (e) cli_error("%s: write failed: %s", path, strerror(e));
        bad = e || clash;
    }
    free(tmp);
    free(png);
    return bad;
}

/* A job's work on the thread that took it: wait for its pixels, box them
 * into the parent, store the tile. Errors are captured into j->err. */
static void job_run(pool *pl, wscratch *w, job *j, int skip)
{
    const run *r = pl->r;
    pix *p = j->p;
    if (!skip) pix_wait(pl, p);
    if (p->parent) {
        if (!skip)
            for (int l = 0; l < r->layers; l++) box_down(l, p->px[l], p->parent->px[l], r->S, p->q & 1, p->q >> 1);
        pix_unhold(pl, p->parent);
        pix_release(pl, p->parent);
    }
    j->flag = j->mode;
    if (skip) {
        j->bad = 1;
    } else if (j->mode && j->mode != 'e') {
        if (j->mode == 'c') j->flag = all_clear(p->px[0], r->S) ? 'e' : 'w';
        if (j->flag != 'e') {
            cli_error_capture(j->err);
            for (int l = 0; l < r->layers && !j->bad; l++)
                j->bad = store_layer(r, pl, w, j->z, j->x, j->y, l, j->written[l] ? j->written[l] : p->px[l], j->hash[l],
                                     &j->png[l], &j->size[l]);
            cli_error_capture(NULL);
            if (j->bad && !j->err[0]) snprintf(j->err, sizeof j->err, "roadsplat: tile %u/%llu/%llu: cannot store it",
                                               j->z, (unsigned long long)j->x, (unsigned long long)file_y(r, j->z, j->y));
        }
    }
    free(j->written[0]);
    free(j->written[1]);
    j->written[0] = j->written[1] = NULL;
    j->p = NULL;
    pix_release(pl, p);
}

/* The first job a worker may take (under pl->mu): not taken, and either
 * its pixels are complete or it is to be skipped. A parent's job waits for
 * its children's, which come before it; a worker that took it in order sat
 * idle while the other boxed the last child (on two cores about a tenth of
 * the run), so workers take any ready job and the commit keeps the order.
 * Skipped: after an abort, and the jobs after a failed one (those before it
 * run in full, so the first failure in order is the one reported, as with
 * one thread). Returns pl->tail when none. */
static uint64_t pool_pick(pool *pl, int *skip)
{
    while (pl->next < pl->tail && pl->ring[pl->next % pl->cap].taken) pl->next++;
    for (uint64_t s = pl->next; s < pl->tail; s++) {
        const job *j = &pl->ring[s % pl->cap];
        if (j->taken) continue;
        int k = pl->abort || s > pl->fail_seq;
        if (k || j->p->pending == 0) {
            *skip = k;
            return s;
        }
    }
    return pl->tail;
}

static void *worker_main(void *arg)
{
    struct warg *wa = arg;
    pool *pl = wa->pl;
    pthread_mutex_lock(&pl->mu);
    for (;;) {
        int skip = 0;
        uint64_t s;
        while ((s = pool_pick(pl, &skip)) == pl->tail && !(pl->stop && pl->next == pl->tail))
            pthread_cond_wait(&pl->cv, &pl->mu);
        if (s == pl->tail) break;
        job *j = &pl->ring[s % pl->cap];
        j->taken = 1;
        pthread_mutex_unlock(&pl->mu);
        job_run(pl, &pl->ws[wa->i], j, skip);
        pthread_mutex_lock(&pl->mu);
        j->done = 1;
        if (j->bad && s < pl->fail_seq) pl->fail_seq = s;
        pthread_cond_broadcast(&pl->cv);
    }
    pthread_mutex_unlock(&pl->mu);
    return NULL;
}

/* The pool: n workers (0: the main thread runs each job as it is queued). */
static int pool_start(run *r, unsigned n)
{
    pool *pl = calloc(1, sizeof *pl);
    if (!pl) return cli_error("out of memory"), 1;
    r->pl = pl;
    pl->r = r;
    if (n > 64) n = 64;
    pl->cap = n ? 4 * (uint64_t)n : 1;
    pl->fail_seq = UINT64_MAX;
    size_t side2 = (size_t)r->side * r->side;
    pthread_mutex_init(&pl->mu, NULL);
    pthread_mutex_init(&pl->tmu, NULL);
    pthread_cond_init(&pl->cv, NULL);
    cli_error_capture(NULL); /* the capture key made before any worker runs */
    if (!(pl->ring = calloc(pl->cap, sizeof *pl->ring))) return cli_error("out of memory"), 1;
    for (unsigned i = 0; i <= n; i++)
        if (!(pl->ws[i].rgb = malloc(side2 * 3))) return cli_error("out of memory for the tile buffers"), 1;
    for (unsigned i = 0; i < n; i++) {
        pl->wa[i].pl = pl;
        pl->wa[i].i = (int)i;
        int e = pthread_create(&pl->th[i], NULL, worker_main, &pl->wa[i]);
        if (e) {
            cli_error("cannot start a worker thread: %s", strerror(e));
            return 1;
        }
        pl->nth++;
    }
    return 0;
}

/* Stop the workers after the jobs they hold (with abort, the jobs not yet
 * taken are skipped) and free the pool. */
static void pool_stop(run *r, int abort)
{
    pool *pl = r->pl;
    if (!pl) return;
    pthread_mutex_lock(&pl->mu);
    pl->stop = 1;
    if (abort) pl->abort = 1;
    pthread_cond_broadcast(&pl->cv);
    pthread_mutex_unlock(&pl->mu);
    for (int i = 0; i < pl->nth; i++) pthread_join(pl->th[i], NULL);
    if (pl->ring) /* jobs never run (an error on the main thread with --threads 1 cannot leave any) */
        for (uint64_t s = pl->head; s < pl->tail; s++) {
            job *j = &pl->ring[s % pl->cap];
            if (!j->done && j->p) job_run(pl, &pl->ws[pl->nth], j, 1);
            free(j->png[0]);
            free(j->png[1]);
        }
    for (int i = 0; i < 65; i++) free(pl->ws[i].rgb), free(pl->ws[i].path);
    pthread_mutex_destroy(&pl->mu);
    pthread_mutex_destroy(&pl->tmu);
    pthread_cond_destroy(&pl->cv);
    free(pl->ring);
    free(pl);
    r->pl = NULL;
}

/* Commit a done job on the main thread: its MBTiles rows and log line, the
 * counters; a failed job's captured line is printed here. */
static int commit(run *r, job *j)
{
    int bad = j->bad;
    if (bad) {
        if (j->err[0]) fprintf(stderr, "%s\n", j->err);
    } else if (j->flag == 'e') {
        r->road_free++;
        bad = log_line(r, j->z, j->x, j->y, 'e', NULL, NULL);
    } else if (j->flag) {
        for (int l = 0; l < r->layers && !bad && r->db; l++)
            bad = r->mb->put(r->db, l, j->z, (uint32_t)j->x, (uint32_t)((((uint64_t)1 << j->z) - 1 - j->y)), j->png[l],
                             j->size[l]);
        if (!bad) {
            r->written++;
            bad = log_line(r, j->z, j->x, j->y, j->flag, j->hash[0], r->layers > 1 ? j->hash[1] : NULL);
        }
    }
    free(j->png[0]);
    free(j->png[1]);
    j->png[0] = j->png[1] = NULL;
    return bad;
}

/* Commit the done jobs in sequence order; wait for the next one while the
 * queue is full, after a failure, or (all) until every job is committed. */
static int pool_commit(run *r, int all)
{
    pool *pl = r->pl;
    int bad = 0;
    pthread_mutex_lock(&pl->mu);
    while (!bad && pl->head < pl->tail) {
        job *j = &pl->ring[pl->head % pl->cap];
        if (!j->done) {
            if (!all && !pl->abort && pl->fail_seq == UINT64_MAX && pl->tail - pl->head < pl->cap) break;
            pthread_cond_wait(&pl->cv, &pl->mu);
            continue;
        }
        pthread_mutex_unlock(&pl->mu);
        bad = commit(r, j);
        pthread_mutex_lock(&pl->mu);
        pl->head++;
        if (bad) pl->abort = 1;
    }
    pthread_mutex_unlock(&pl->mu);
    return bad;
}

/* Tile (z, x, y) is finished on the main thread with its pixels in p (the
 * caller's reference is passed on): queue its job, which boxes p into
 * quadrant q of parent (when not NULL) and stores it by `mode` (job). */
static int finish(run *r, pix *p, pix *parent, int q, uint32_t z, uint64_t x, uint64_t y, int mode)
{
    pool *pl = r->pl;
    uint8_t *written[2] = { NULL, NULL };
    if (!parent && !mode) {
        pix_release(pl, p);
        return 0;
    }
    if (r->P && mode && mode != 'e') { /* --halo: the ring is made here, where level_rect may render */
        pix_wait(pl, p);
        size_t n = (size_t)r->side * r->side * 4;
        for (int l = 0; l < r->layers; l++) {
            const uint8_t *f = with_halo(r, l, z, x, y, p->px[l]);
            if (f && !(written[l] = malloc(n))) cli_error("out of memory");
            if (!written[l]) {
                free(written[0]);
                pix_release(pl, p);
                return 1;
            }
            memcpy(written[l], f, n);
        }
    }
    if (pool_commit(r, 0)) { /* room in the queue */
        free(written[0]);
        free(written[1]);
        pix_release(pl, p);
        return 1;
    }
    pthread_mutex_lock(&pl->mu);
    if (parent) {
        parent->pending++;
        parent->refs++;
        p->parent = parent;
        p->q = q;
    }
    job *j = &pl->ring[pl->tail % pl->cap];
    memset(j, 0, sizeof *j);
    j->p = p;
    j->z = z, j->x = x, j->y = y;
    j->mode = mode;
    j->written[0] = written[0], j->written[1] = written[1];
    pl->tail++;
    pthread_cond_broadcast(&pl->cv);
    pthread_mutex_unlock(&pl->mu);
    if (!pl->nth) { /* --threads 1: run here */
        j->taken = 1;
        job_run(pl, &pl->ws[0], j, 0);
        j->done = 1;
        pl->next = pl->tail;
    }
    return pool_commit(r, 0);
}

/* A tile file read back, quietly: 0, or 1 (missing, unreadable, not a
 * regular file - a symbolic link is not followed, a FIFO not waited on -
 * or larger than any tile of `side` pixels can be). */
static int read_tile_file(const char *path, uint32_t side, char **data, size_t *size)
{
    *data = NULL;
    int fd = open(path, O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) return 1;
    struct stat st;
    /* a stored (level 0) RGBA PNG: 4 bytes a pixel, a filter byte a row, 5 bytes a 64 KiB block */
    uint64_t cap = (uint64_t)side * side * 4 * 2 + ((uint64_t)1 << 20);
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode) || (uint64_t)st.st_size > cap) {
        close(fd);
        return 1;
    }
    size_t n = (size_t)st.st_size, got = 0;
    char *b = malloc(n ? n : 1);
    while (b && got < n) {
        ssize_t k = read(fd, b + got, n - got);
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) break;
        got += (size_t)k;
    }
    close(fd);
    if (!b || got != n) {
        free(b);
        return 1;
    }
    *data = b;
    *size = n;
    return 0;
}

/* A logged tile's files, when each still has its logged hash: 1 (with
 * out, the S x S pixels of each layer decoded into out[layer]), else 0. */
static int logged_file_ok(run *r, uint32_t z, uint64_t x, uint64_t y, entry *e, uint8_t *const *out)
{
    if (e->checked && !out) return 1;
    if (r->layers > 1 && !e->has_n) return 0;
    int ok = 1;
    for (int l = 0; ok && l < r->layers; l++) {
        if (tile_path(r, z, x, y, 0, l)) return 0;
        char *bytes = NULL;
        size_t n = 0;
        if (read_tile_file(r->path, r->side, &bytes, &n)) return 0;
        uint8_t h[32];
        cli_sha256(bytes, n, h);
        ok = !memcmp(h, l ? e->nhash : e->hash, 32);
        if (ok && out) {
            uint8_t *dst = r->P ? r->full : out[l];
            if (decode_tile((const uint8_t *)bytes, n, r->side, dst)) {
                cli_error("%s: not a %u x %u tile of roadsplat", r->path, r->side, r->side);
                free(bytes);
                return -1;
            }
            if (r->P)
                for (uint32_t j = 0; j < r->S; j++)
                    memcpy(out[l] + (size_t)j * r->S * 4, r->full + ((size_t)(r->P + j) * r->side + r->P) * 4,
                           (size_t)r->S * 4);
        }
        free(bytes);
    }
    e->checked = (uint8_t)ok;
    return ok;
}

/* ---- the quadtree ---------------------------------------------------------------- */

/* Tile (z, x, y), its pixels boxed into quadrant q of parent when the
 * caller needs them (parent not NULL: a tile already done is then read back
 * from its files, or recomputed when it was road-free and not written).
 * record 0: compute only (a road-free tile recomputed for its parent).
 * *has_road: some pixel of the tile holds a road. */
static int build(run *r, uint32_t z, uint64_t x, uint64_t y, pix *parent, int q, int record, int *has_road)
{
    int need = parent != NULL;
    pix *p = NULL;
    if (z < r->zmin) { /* --tiling mercator: a level not written, whose pixels nothing needs */
        int any = 0;
        for (int k = 0; k < 4; k++) {
            uint64_t cx = 2 * x + (k & 1), cy = 2 * y + (k >> 1);
            int cr = 0;
            if (exists(r, z + 1, cx, cy) && build(r, z + 1, cx, cy, NULL, 0, record, &cr)) return 1;
            any |= cr;
        }
        *has_road = any;
        return 0;
    }
    entry *e = tfind(&r->tab, tkey(z, x, y));
    if (e && record && (e->flag == 'r' || e->flag == 'w' || e->flag == 'd')) {
        if (need && !(p = pix_new(r, 0))) return cli_error("out of memory for the tile buffers"), 1;
        int ok = logged_file_ok(r, z, x, y, e, need ? p->px : NULL);
        if (ok < 0) {
            pix_release(r->pl, p);
            return 1;
        }
        if (ok) {
            *has_road = e->flag == 'r';
            r->kept++;
            if (!need && r->a->resume && z < r->zmax && e->flag != 'd') {
                /* --resume: a kept tile's subtree is checked too (a child lost
                 * under an intact parent is made again) */
                for (int k = 0; k < 4; k++) {
                    uint64_t cx = 2 * x + (k & 1), cy = 2 * y + (k >> 1);
                    int cr = 0;
                    if (exists(r, z + 1, cx, cy) && build(r, z + 1, cx, cy, NULL, 0, 1, &cr)) return 1;
                }
                return 0;
            }
            r->done_finest += finest_count(r, z, x, y);
            return finish(r, p, parent, q, z, x, y, 0);
        }
        pix_release(r->pl, p);
        p = NULL;
        e = NULL; /* missing or changed: made again */
    }
    if (e && record && e->flag == 'e') {
        r->done_finest += finest_count(r, z, x, y);
        if (!need) {
            *has_road = 0;
            return 0;
        }
        record = 0; /* road-free: its pixels again, nothing written */
    }
    if (r->route && z == r->zd && zone_free(r, x, y)) {
        /* terrain only: this level's pixels rendered directly, no subtree */
        if (!(p = pix_new(r, 0))) return cli_error("out of memory for the tile buffers"), 1;
        for (int l = 0; l < r->layers; l++)
            if (splat_rect(r, 1, l, (int64_t)(x * r->S), (int64_t)(y * r->S), r->S, r->S, p->px[l], r->S, NULL)) {
                pix_release(r->pl, p);
                return 1;
            }
        *has_road = 0;
        r->direct++;
        if (record) {
            r->done_finest += finest_count(r, z, x, y);
            cli_progress_cb(&r->prog, r->done_finest, r->total_finest);
            return finish(r, p, parent, q, z, x, y, 'd');
        }
        return finish(r, p, parent, q, z, x, y, 0);
    } else if (z == r->zmax) {
        if (record && r->a->from_children && !e) {
            if (tile_path(r, z, x, y, 0, 0)) return 1;
            cli_error("--from-children: %s is missing or differs from its log: run its shard (with --resume) first",
                      r->path);
            return 1;
        }
        if (!(p = pix_new(r, 0))) return cli_error("out of memory for the tile buffers"), 1;
        if (render_tile(r, x, y, p->px, has_road)) {
            pix_release(r->pl, p);
            return 1;
        }
        if (record) {
            r->done_finest++;
            cli_progress_cb(&r->prog, r->done_finest, r->total_finest);
        }
    } else {
        /* the children's jobs box them into p; held (pending 1) until all are queued */
        if (!(p = pix_new(r, 1))) return cli_error("out of memory for the tile buffers"), 1;
        int any = 0;
        for (int k = 0; k < 4; k++) {
            uint64_t cx = 2 * x + (k & 1), cy = 2 * y + (k >> 1);
            if (!exists(r, z + 1, cx, cy)) continue;
            int cr = 0;
            if (build(r, z + 1, cx, cy, p, k, record, &cr)) {
                pix_release(r->pl, p);
                return 1;
            }
            any |= cr;
        }
        pix_unhold(r->pl, p);
        *has_road = any;
    }
    if (!record) {
        if (*has_road) {
            cli_error("tile %u/%llu/%llu: logged as road-free but holds a road (logs of other inputs?)", z,
                      (unsigned long long)x, (unsigned long long)file_y(r, z, y));
            pix_release(r->pl, p);
            return 1;
        }
        return finish(r, p, parent, q, z, x, y, 0);
    }
    if (*has_road || z <= r->zd) return finish(r, p, parent, q, z, x, y, *has_road ? 'r' : r->merc ? 'c' : 'w');
    return finish(r, p, parent, q, z, x, y, 'e');
}

/* The tiles of this run under (z, x, y), whose finest tiles have the
 * Morton ranks [rank, rank + count): whole subtrees inside [lo, hi) are
 * built; a subtree across a boundary is split. */
static int visit(run *r, uint32_t z, uint64_t x, uint64_t y, uint64_t rank)
{
    uint64_t cnt = finest_count(r, z, x, y);
    if (!cnt || rank + cnt <= r->lo || rank >= r->hi) return 0;
    if (z == r->zd && zone_free(r, x, y) && !(rank >= r->lo && rank + cnt <= r->hi))
        return 0; /* a terrain-only tile across shards: --from-children renders it */
    if (rank >= r->lo && rank + cnt <= r->hi) {
        int hr;
        return build(r, z, x, y, NULL, 0, 1, &hr);
    }
    for (int q = 0; q < 4; q++) {
        uint64_t cx = 2 * x + (q & 1), cy = 2 * y + (q >> 1);
        if (visit(r, z + 1, cx, cy, rank)) return 1;
        rank += finest_count(r, z + 1, cx, cy);
    }
    return 0;
}

/* ---- arguments ------------------------------------------------------------------- */

static int parse_shard(const char *v, uint32_t *i, uint32_t *n)
{
    const char *sl = strchr(v, '/');
    char a[32], b[32];
    if (!sl || sl == v || (size_t)(sl - v) >= sizeof a || strlen(sl + 1) >= sizeof b || !sl[1]) {
        cli_error("--shard: '%s' is not I/N (e.g. 0/4)", v);
        return 1;
    }
    memcpy(a, v, (size_t)(sl - v));
    a[sl - v] = '\0';
    strcpy(b, sl + 1);
    if (cli_parse_u32("--shard", a, i) || cli_parse_u32("--shard", b, n)) return 1;
    if (*n < 1 || *i >= *n) {
        cli_error("--shard: '%s': need N >= 1 and 0 <= I < N", v);
        return 1;
    }
    return 0;
}

/* 0 to run, 1 on a usage error, 2 after --help. */
static int parse_targs(int argc, char **argv, targs *a)
{
    const char *pos[3];
    int npos = 0, only_pos = 0;
    memset(a, 0, sizeof *a);
    a->tile = 256;
    a->zoom_min = a->zoom_max = -1;
    a->opt = calloc((size_t)argc + 1, sizeof *a->opt);
    if (!a->opt) {
        cli_error("out of memory");
        return 1;
    }
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i];
        if (only_pos || arg[0] != '-' || arg[1] == '\0') {
            if (npos == 3) {
                cli_error("tiles: unexpected argument '%s' (see roadsplat tiles --help)", arg);
                return 1;
            }
            pos[npos++] = arg;
            continue;
        }
        if (!strcmp(arg, "--")) { only_pos = 1; continue; }
        char name[64];
        const char *eq = strchr(arg, '='), *inl = eq ? eq + 1 : NULL, *v;
        size_t len = eq ? (size_t)(eq - arg) : strlen(arg);
        if (len >= sizeof name) len = sizeof name - 1;
        memcpy(name, arg, len);
        name[len] = '\0';
        if (!strcmp(name, "--help") || !strcmp(name, "-h")) {
            fputs(tiles_usage, stdout);
            return 2;
        }
        int *flag = !strcmp(name, "--quiet") || !strcmp(name, "-q") ? &a->quiet
                    : !strcmp(name, "--dense")                       ? &a->dense
                    : !strcmp(name, "--resume")                      ? &a->resume
                    : !strcmp(name, "--from-children")               ? &a->from_children
                    : !strcmp(name, "--normals")                     ? &a->normals
                    : !strcmp(name, "--render-all")                  ? &a->render_all
                    : !strcmp(name, "--viewer")                      ? &a->viewer
                                                                     : NULL;
        if (flag) {
            if (inl) { cli_error("%s takes no value", name); return 1; }
            *flag = 1;
            if (flag == &a->dense || flag == &a->normals || flag == &a->render_all) a->opt[a->nopt++] = arg;
            continue;
        }
        if (!strcmp(name, "--tile-size")) {
            if (cli_option_value(argc, argv, &i, name, inl, &v) || cli_parse_u32(name, v, &a->tile)) return 1;
            if (a->tile != 256 && a->tile != 512 && a->tile != 1024) {
                cli_error("--tile-size: '%s' must be 256, 512 or 1024", v);
                return 1;
            }
        } else if (!strcmp(name, "--scheme")) {
            if (cli_option_value(argc, argv, &i, name, inl, &v)) return 1;
            if (strcmp(v, "xyz") && strcmp(v, "tms")) {
                cli_error("--scheme: '%s' must be xyz or tms", v);
                return 1;
            }
            a->tms = v[0] == 't';
        } else if (!strcmp(name, "--format")) {
            if (cli_option_value(argc, argv, &i, name, inl, &v)) return 1;
            if (strcmp(v, "png") && strcmp(v, "mbtiles")) {
                cli_error("--format: '%s' must be png or mbtiles", v);
                return 1;
            }
            a->mbtiles = v[0] == 'm';
        } else if (!strcmp(name, "--normal-convention")) {
            int i0 = i;
            if (cli_option_value(argc, argv, &i, name, inl, &v)) return 1;
            if (strcmp(v, "gl") && strcmp(v, "dx")) {
                cli_error("--normal-convention: '%s' must be gl or dx", v);
                return 1;
            }
            a->normal.directx = v[0] == 'd';
            a->normal_given = a->conv_given = 1;
            for (int k = i0; k <= i; k++) a->opt[a->nopt++] = argv[k];
        } else if (!strcmp(name, "--normal-strength")) {
            int i0 = i;
            if (cli_option_value(argc, argv, &i, name, inl, &v) || cli_parse_double(name, v, &a->normal.strength))
                return 1;
            if (!(a->normal.strength > 0 && a->normal.strength <= 1e6)) {
                cli_error("--normal-strength: '%s' must be in (0, 1e6]", v);
                return 1;
            }
            a->normal_given = 1;
            for (int k = i0; k <= i; k++) a->opt[a->nopt++] = argv[k];
        } else if (!strcmp(name, "--halo")) {
            int i0 = i;
            if (cli_option_value(argc, argv, &i, name, inl, &v) || cli_parse_u32(name, v, &a->halo)) return 1;
            if (a->halo > 128) {
                cli_error("--halo: '%s' must be 0..128 pixels", v);
                return 1;
            }
            for (int k = i0; k <= i; k++) a->opt[a->nopt++] = argv[k];
        } else if (!strcmp(name, "--tiling")) {
            int i0 = i;
            if (cli_option_value(argc, argv, &i, name, inl, &v)) return 1;
            if (strcmp(v, "raster") && strcmp(v, "mercator")) {
                cli_error("--tiling: '%s' must be raster (the splat's pixel grid) or mercator (EPSG:3857 XYZ tiles)", v);
                return 1;
            }
            a->mercator = v[0] == 'm';
            for (int k = i0; k <= i; k++) a->opt[a->nopt++] = argv[k];
        } else if (!strcmp(name, "--zoom")) {
            int i0 = i;
            uint32_t z0 = 0, z1 = 0;
            if (cli_option_value(argc, argv, &i, name, inl, &v)) return 1;
            const char *dash = strchr(v, '-');
            char lo[16] = "";
            if (dash && (size_t)(dash - v) < sizeof lo) memcpy(lo, v, (size_t)(dash - v)), lo[dash - v] = '\0';
            if (dash ? (dash == v || (size_t)(dash - v) >= sizeof lo || cli_parse_u32(name, lo, &z0) ||
                        cli_parse_u32(name, dash + 1, &z1))
                     : cli_parse_u32(name, v, &z1))
                return 1;
            if (z1 > MAX_ZOOM || z0 > z1) {
                cli_error("--zoom: '%s' must be MAX or MIN-MAX with 0 <= MIN <= MAX <= %d", v, MAX_ZOOM);
                return 1;
            }
            a->zoom_max = (int)z1;
            if (dash) a->zoom_min = (int)z0;
            for (int k = i0; k <= i; k++) a->opt[a->nopt++] = argv[k];
        } else if (!strcmp(name, "--attribution")) {
            if (cli_option_value(argc, argv, &i, name, inl, &v)) return 1;
            a->attribution = v;
        } else if (!strcmp(name, "--shard")) {
            if (cli_option_value(argc, argv, &i, name, inl, &v) || parse_shard(v, &a->shard_i, &a->shard_n)) return 1;
            a->sharded = 1;
        } else {
            int i0 = i, sr = cli_splat_option(argc, argv, &i, name, inl, &a->s);
            if (sr < 0) sr = cli_lighting_option(argc, argv, &i, name, inl, &a->s);
            if (sr > 0) return 1;
            if (sr < 0) {
                cli_error("tiles: unknown option '%s' (see roadsplat tiles --help)", arg);
                return 1;
            }
            /* not in the fingerprint: they change no byte of a tile */
            if (strcmp(name, "--threads") && strcmp(name, "--gdal-trust") && strcmp(name, "--max-image-pixels"))
                for (int k = i0; k <= i; k++) a->opt[a->nopt++] = argv[k];
        }
    }
    if (npos != 3) {
        cli_error("tiles: expected DEM ROADS OUTDIR, got %d argument%s (see roadsplat tiles --help)", npos,
                  npos == 1 ? "" : "s");
        return 1;
    }
    a->dem = pos[0], a->roads = pos[1], a->out = pos[2];
    if (!a->sharded) a->shard_n = 1;
    if (a->sharded && a->from_children) {
        cli_error("--shard and --from-children are separate steps: shards first, then one --from-children run");
        return 1;
    }
    if (a->normal_given && !a->normals && (a->conv_given || !a->s.o.lighting.enable)) {
        cli_error("--normal-convention and --normal-strength need --normals (--normal-strength also serves "
                  "--lighting)");
        return 1;
    }
    if (cli_lighting_check(&a->s)) return 1;
    a->s.o.lighting.normal.strength = a->normal.strength;
    if (a->viewer && (a->mbtiles || a->halo || a->sharded)) {
        cli_error("--viewer shows a folder of plain tiles: not with --format mbtiles, --halo or --shard (run it with "
                  "--from-children)");
        return 1;
    }
    if (a->mercator && (a->halo || a->normals)) {
        cli_error("--tiling mercator resamples the colour: not with %s (use --tiling raster)",
                  a->halo ? "--halo" : "--normals (a normal map's vectors would have to turn with the grid)");
        return 1;
    }
    if (a->zoom_max >= 0 && !a->mercator) {
        cli_error("--zoom picks the levels of --tiling mercator; the raster grid's levels follow from the image size");
        return 1;
    }
    if (a->attribution && !a->viewer) {
        cli_error("--attribution is the viewer's attribution line: it needs --viewer");
        return 1;
    }
    if (a->mbtiles && (a->sharded || a->resume || a->from_children)) {
        cli_error("--format mbtiles is written by one process: use --format png for --shard, --resume and --from-children");
        return 1;
    }
    return 0;
}

/* ---- inputs, fingerprint, logs ------------------------------------------------- */

typedef struct input_hash {
    const char *role, *path;
    char hex[65]; /* "" for a folder (a GIS source) */
} input_hash;

/* The inputs this run loaded (the registry, cli/util.c), hashed from the
 * very bytes loaded - a pipe's too - in a fixed order of roles: *ih
 * malloc'd, *n entries. */
static int hash_inputs(input_hash **ih, int *n)
{
    /* the sidecars GDAL read beside a DEM or GIS roads (world files, .prj,
     * .aux.xml, a shapefile's .shx/.dbf) shape the output too */
    static const char *const roles[10][2] = { { "DEM", "DEM" }, { "ROADS", "ROADS" },
                                               { "--terrain-texture", "--terrain-texture" },
                                               { "--road-texture", "--road-texture" }, { "--styles", "--styles" },
                                               { "--atlas", "--atlas" }, { "--atlas-index", "--atlas-index" },
                                               { "surface image", "surface" }, { "DEM sidecar", "DEM sidecar" },
                                               { "ROADS sidecar", "ROADS sidecar" } };
    size_t m = cli_inputs_count();
    *n = 0;
    if (!(*ih = calloc(m ? m : 1, sizeof **ih))) {
        cli_error("out of memory");
        return 1;
    }
    for (int k = 0; k < 10; k++)
        for (size_t i = 0; i < m; i++) {
            const char *path, *role;
            int fd = cli_inputs_get(i, &path, &role);
            if (strcmp(role, roles[k][0])) continue;
            input_hash *h = &(*ih)[(*n)++];
            h->role = roles[k][1], h->path = path, h->hex[0] = '\0';
            uint8_t d[32];
            if (fd >= 0) {
                if (cli_sha256_fd(fd, d)) {
                    cli_error("%s: cannot read: %s", path, strerror(errno ? errno : EIO));
                    return 1;
                }
                cli_sha256_hex(d, h->hex);
            }
            if (k < 7) break; /* one file a role, but surface images and sidecars */
        }
    return 0;
}

/* 16 hex digits naming this run's temporaries: the process id, the clock
 * and the address of a stack variable, mixed. Unique among runs on one
 * host at a time, which is what two runs into one OUTDIR need. */
static void run_id(char out[17])
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    uint64_t v = (uint64_t)getpid() * 0x9E3779B97F4A7C15ull ^ (uint64_t)ts.tv_sec * 1000000007ull ^
                 (uint64_t)ts.tv_nsec ^ (uint64_t)(uintptr_t)&ts;
    v ^= v >> 31;
    v *= 0xBF58476D1CE4E5B9ull;
    v ^= v >> 29;
    snprintf(out, 17, "%016llx", (unsigned long long)v);
}

/* SHA-256 of everything that decides the tiles' bytes: runs of one
 * pyramid (shards, resumes, the merge) must agree on it. */
static void fingerprint(const targs *a, const input_hash *ih, int nin, char hex[65])
{
    cli_sha256_ctx s;
    char line[160];
    cli_sha256_init(&s);
    int n = snprintf(line, sizeof line, "roadsplat-tiles 2\ntile_size %u\nscheme %s\nformat %s\n", a->tile,
                     a->tms ? "tms" : "xyz", a->mbtiles ? "mbtiles" : "png");
    cli_sha256_update(&s, line, (size_t)n);
    for (int k = 0; k < a->nopt; k++) {
        cli_sha256_update(&s, "option ", 7);
        cli_sha256_update(&s, a->opt[k], strlen(a->opt[k]) + 1);
    }
    for (int k = 0; k < nin; k++) {
        n = snprintf(line, sizeof line, "input %s %s\n", ih[k].role, ih[k].hex[0] ? ih[k].hex : ih[k].path);
        cli_sha256_update(&s, line, (size_t)n);
    }
    uint8_t d[32];
    cli_sha256_final(&s, d);
    cli_sha256_hex(d, hex);
}

static char *join(const char *a, const char *b, const char *c)
{
    size_t n = strlen(a) + strlen(b) + (c ? strlen(c) : 0) + 2;
    char *p = malloc(n);
    if (p) snprintf(p, n, "%s/%s%s", a, b, c ? c : "");
    return p;
}

static int hexval(int c) { return c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : -1; }

/* A log inside the log folder (descriptor ld), opened without following
 * a symbolic link or waiting on a FIFO: only a regular file. The
 * descriptor, or -1 after a message naming path. */
static int open_log_file(int ld, const char *name, const char *path, int flags)
{
    int fd = openat(ld, name, flags | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC, 0666);
    struct stat st;
    if (fd < 0 || fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        if (fd >= 0 || errno == ELOOP)
            cli_error("%s: not a regular file (a symbolic link?); remove it", path);
        else
            cli_error("%s: %s", path, strerror(errno));
        if (fd >= 0) close(fd);
        return -1;
    }
    int fl = fcntl(fd, F_GETFL);
    if (fl >= 0) fcntl(fd, F_SETFL, fl & ~O_NONBLOCK);
    return fd;
}

/* Every log in OUTDIR/.tiles-log (descriptor ld) into the table (a line
 * cut by a kill is skipped); a log of another fingerprint is an error. */
static int load_logs(run *r, const char *dir, int ld)
{
    int dd = fcntl(ld, F_DUPFD_CLOEXEC, 3);
    DIR *d = dd >= 0 ? fdopendir(dd) : NULL;
    if (!d) {
        if (dd >= 0) close(dd);
        return 0;
    }
    struct dirent *de;
    int bad = 0;
    while (!bad && (de = readdir(d))) {
        size_t nl = strlen(de->d_name);
        if (nl < 5 || strcmp(de->d_name + nl - 4, ".log")) continue;
        char *p = join(dir, de->d_name, NULL);
        int fd = p ? open_log_file(ld, de->d_name, p, O_RDONLY) : -1;
        FILE *f = fd >= 0 ? fdopen(fd, "r") : NULL;
        if (!f) {
            if (fd >= 0) close(fd);
            if (!p) cli_error("out of memory");
            free(p);
            bad = 1;
            break;
        }
        char line[256], fp[80];
        int empty = !fgets(line, sizeof line, f); /* a run that has just begun its log */
        if (!empty && (sscanf(line, "roadsplat-tiles-log 1 %70s", fp) != 1 || strcmp(fp, r->fingerprint))) {
            cli_error("%s: made from other inputs or options than this run (remove it, or rerun that step with the "
                      "same inputs and options)", p);
            bad = 1;
        }
        while (!bad && fgets(line, sizeof line, f)) {
            unsigned z;
            unsigned long long x, y;
            char flag, hex[80], nhex[80];
            uint8_t h[32], nh[32];
            size_t L = strlen(line);
            if (!L || line[L - 1] != '\n') break; /* cut short */
            int nf = sscanf(line, "%u %llu %llu %c %70s %70s", &z, &x, &y, &flag, hex, nhex);
            if ((nf != 5 && nf != 6) || z > r->zmax || (flag != 'r' && flag != 'w' && flag != 'e' && flag != 'd') ||
                !exists(r, z, x, y))
                continue;
            int okh = flag == 'e' || (strlen(hex) == 64 && (nf == 5 || strlen(nhex) == 64));
            for (int k = 0; okh && flag != 'e' && k < 32; k++) {
                int hi = hexval(hex[2 * k]), lo = hexval(hex[2 * k + 1]);
                if (hi < 0 || lo < 0) okh = 0;
                else h[k] = (uint8_t)(hi << 4 | lo);
                if (nf == 6) {
                    hi = hexval(nhex[2 * k]), lo = hexval(nhex[2 * k + 1]);
                    if (hi < 0 || lo < 0) okh = 0;
                    else nh[k] = (uint8_t)(hi << 4 | lo);
                }
            }
            if (!okh) continue;
            if (!tput(&r->tab, tkey(z, x, y), flag, flag == 'e' ? NULL : h, flag == 'e' || nf == 5 ? NULL : nh)) {
                cli_error("out of memory");
                bad = 1;
            }
        }
        fclose(f);
        free(p);
    }
    closedir(d);
    return bad;
}

static int log_in_use(int ld, const char *name);

/* Remove the logs of earlier runs (a whole run without --resume): only
 * regular files of the log folder, never what a symbolic link there names,
 * never the log of a run still going. */
static void clear_logs(int ld, const char *keep)
{
    int dd = fcntl(ld, F_DUPFD_CLOEXEC, 3);
    DIR *d = dd >= 0 ? fdopendir(dd) : NULL;
    if (!d) {
        if (dd >= 0) close(dd);
        return;
    }
    struct dirent *de;
    while ((de = readdir(d))) {
        size_t nl = strlen(de->d_name);
        struct stat st;
        if (nl < 5 || strcmp(de->d_name + nl - 4, ".log") || !strcmp(de->d_name, keep)) continue;
        if (fstatat(ld, de->d_name, &st, AT_SYMLINK_NOFOLLOW) == 0 && S_ISREG(st.st_mode) &&
            !log_in_use(ld, de->d_name)) /* a live run's log stays */
            unlinkat(ld, de->d_name, 0);
    }
    closedir(d);
}

/* One "run ID" line of a log into r->old_ids (the most recent OLD_RUNS). */
static void old_run_line(run *r, const char *line, size_t n)
{
    if (n != 20 || memcmp(line, "run ", 4)) return;
    for (size_t i = 4; i < 20; i++)
        if (hexval(line[i]) < 0) return;
    if (!memcmp(line + 4, r->runid, 16)) return;
    if (r->n_old == OLD_RUNS) {
        memmove(r->old_ids[0], r->old_ids[1], sizeof r->old_ids[0] * (OLD_RUNS - 1));
        r->n_old--;
    }
    memcpy(r->old_ids[r->n_old], line + 4, 16);
    r->old_ids[r->n_old++][16] = '\0';
}

/* The ids of earlier runs named in this run's own log (its "run ID"
 * lines), read with pread: closing a second descriptor of the log would
 * drop this process's lock on it (fcntl locks are per process and file). */
static void read_old_runs(run *r, int fd)
{
    char buf[1 << 14], line[32];
    size_t ln = 0;
    int longline = 0;
    off_t off = 0;
    for (;;) {
        ssize_t k = pread(fd, buf, sizeof buf, off);
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) break;
        off += k;
        for (ssize_t i = 0; i < k; i++) {
            if (buf[i] == '\n') {
                if (!longline) old_run_line(r, line, ln);
                ln = 0, longline = 0;
            } else if (ln < sizeof line) {
                line[ln++] = buf[i];
            } else {
                longline = 1;
            }
        }
    }
}

/* Runs of one log hold a shared lock on it for their whole life; only a
 * run that could take it exclusively - no other run of this log is alive,
 * on this host or through the file system's locks - reads the earlier runs'
 * ids, whose leftover temporaries it will remove. The exclusive lock then
 * becomes shared at once (atomically, fcntl), so no later run ever takes a
 * live run's temporaries for leftovers. 1 when another run holds the log
 * (nothing locked, nothing read: this run then keeps a log of its own). */
static int lock_log(run *r, int fd)
{
    struct flock fl;
    memset(&fl, 0, sizeof fl);
    fl.l_type = F_WRLCK;
    fl.l_whence = SEEK_SET;
    if (fcntl(fd, F_SETLK, &fl) != 0) {
        if (errno == EAGAIN || errno == EACCES) return 1;
        read_old_runs(r, fd); /* a file system without locks: as if alone */
        return 0;
    }
    read_old_runs(r, fd);
    fl.l_type = F_RDLCK;
    while (fcntl(fd, F_SETLK, &fl) != 0 && errno == EINTR) {}
    return 0;
}

/* 1 when a live run holds a lock on the log `name` of the folder ld. */
static int log_in_use(int ld, const char *name)
{
    int fd = openat(ld, name, O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) return 0;
    struct flock fl;
    memset(&fl, 0, sizeof fl);
    fl.l_type = F_WRLCK;
    fl.l_whence = SEEK_SET;
    int busy = fcntl(fd, F_GETLK, &fl) == 0 && fl.l_type != F_UNLCK;
    close(fd);
    return busy;
}

/* ---- the manifest ------------------------------------------------------------- */

static int cmp_key(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

static void json_str(FILE *f, const char *s)
{
    fputc('"', f);
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\') fprintf(f, "\\%c", c);
        else if (c < 0x20) fprintf(f, "\\u%04x", c);
        else fputc(c, f);
    }
    fputc('"', f);
}

/* The manifest's levels, rule and frame for --tiling mercator. */
static void merc_manifest(const run *r, FILE *f)
{
    const cli_merc_grid *g = &r->mg;
    fprintf(f, "  \"tiling\": \"mercator\",\n");
    fprintf(f, "  \"source\": {\"texels\": %u, \"pixel_m\": %.17g, \"width\": %u, \"height\": %u},\n", r->T,
            r->in->geo.gt[1] / r->T, r->fw, r->fh);
    fprintf(f, "  \"levels\": {\"min\": %u, \"max\": %u, \"dense_max\": %u},\n", r->zmin, r->zmax, r->zd);
    fprintf(f, "  \"level_tiles\": {");
    for (uint32_t z = r->zmin; z <= r->zmax; z++) {
        uint64_t k = span(r, z);
        fprintf(f, "%s\"%u\": {\"x\": [%llu, %llu], \"y\": [%llu, %llu]}", z > r->zmin ? ", " : "", z,
                (unsigned long long)(r->fx0 / k), (unsigned long long)((r->fx0 + r->nx - 1) / k),
                (unsigned long long)(r->fy0 / k), (unsigned long long)((r->fy0 + r->ny - 1) / k));
    }
    fprintf(f, "},\n");
    fprintf(f, "  \"rule\": \"XYZ tiles of EPSG:3857 (Web Mercator): tile (z, x, y) covers x from %.9f + x*s to %.9f "
               "+ (x+1)*s and y from %.9f - y*s down to %.9f - (y+1)*s metres, s = %.9f / 2^z, y from the north; a tile "
               "of the finest level z = %u is the splat at %u texels per DEM cell resampled at its pixel centres "
               "(taken to the DEM's CRS by PROJ; alpha-weighted bilinear), transparent where the centre is off the "
               "DEM; a tile of level z < %u is the 2x2 box filter of its four children (alpha the rounded mean, "
               "colour the alpha-weighted rounded mean); tiles with no opaque pixel are not written; levels %u..%u "
               "are complete, a tile of a finer level is written only when it samples a road pixel (a viewer "
               "over-zooms its parent); levels below %u are not written; PNG RGB when every pixel is opaque, else "
               "RGBA\",\n",
            -CLI_MERC_HALF, -CLI_MERC_HALF, CLI_MERC_HALF, CLI_MERC_HALF, 2 * CLI_MERC_HALF, r->zmax, r->T, r->zmax,
            r->zmin, r->zd, r->zmin);
    fprintf(f, "  \"frame\": {\"crs\": \"EPSG:3857\", \"dem_crs\": ");
    json_str(f, r->in->geo.crs);
    fprintf(f, ", \"cell_size_m\": %.17g, \"pixel_m\": %.17g, \"pixel_note\": \"a finest-level pixel on the ground at "
               "the centre\", \"extent_3857\": [%.17g, %.17g, %.17g, %.17g], \"bounds_wgs84\": [%.12g, %.12g, %.12g, "
               "%.12g], \"center_wgs84\": [%.12g, %.12g]},\n",
            r->in->geo.gt[1], g->pixel_m, g->m[0], g->m[1], g->m[2], g->m[3], g->ll[0], g->ll[1], g->ll[2], g->ll[3],
            g->centre[0], g->centre[1]);
}

/* The manifest as JSON into f: everything but run-specific numbers, so a
 * single run and shards + merge give the same bytes. */
static int manifest(run *r, FILE *f, const input_hash *ih, int nin)
{
    const targs *a = r->a;
    size_t nw = 0, ne = 0, nn = 0;
    for (size_t i = 0; i < r->tab.cap; i++)
        if (r->tab.e[i].key) { if (r->tab.e[i].flag == 'e') ne++; else nw++; }
    uint64_t *keys = malloc((nw ? nw : 1) * sizeof *keys);
    if (!keys) {
        cli_error("out of memory");
        return 1;
    }
    size_t k = 0;
    for (size_t i = 0; i < r->tab.cap; i++)
        if (r->tab.e[i].key && r->tab.e[i].flag != 'e') keys[k++] = r->tab.e[i].key;
    qsort(keys, nw, sizeof *keys, cmp_key);
    double gt[6];
    int geo = !cli_geo_texture_gt(r->in, r->T, 0, 0, gt);
    rs_dem_frame fr;
    rs_dem_get_frame(r->in->dem, &fr);
    double cs = fr.cell_size > 0 ? fr.cell_size : 1;
    fprintf(f, "{\n  \"roadsplat_tiles\": 1,\n  \"roadsplat\": \"%s\",\n", rs_version_string());
    fprintf(f, "  \"tile_size\": %u,\n  \"halo\": %u,\n  \"scheme\": \"%s\",\n  \"format\": \"%s\",\n", r->S, r->P,
            a->tms ? "tms" : "xyz", a->mbtiles ? "mbtiles" : "png");
    fprintf(f, "  \"layers\": [\"colour\"%s],\n", r->layers > 1 ? ", \"normal\"" : "");
    if (r->layers > 1)
        fprintf(f, "  \"normal\": {\"path\": \"{z}/{x}/{y}_n.png\", \"convention\": \"%s\", \"encoding\": \"byte = "
                   "round((n / 2 + 1/2) * 255); R east, G %s, B up; alpha 0 beyond the image\", \"coarser\": \"the "
                   "alpha-weighted sum of the four children's decoded vectors (2 byte - 255), renormalised and encoded "
                   "again; alpha as for the colour\"},\n",
                a->normal.directx ? "dx" : "gl", a->normal.directx ? "south (image down)" : "north (image up)");
    fprintf(f, "  \"path\": \"%s\",\n", a->mbtiles ? (r->layers > 1 ? "tiles table (the normal map: normal_tiles, the same "
                                                                   "columns), tile_row = 2^z - 1 - y (MBTiles 1.3)"
                                                                 : "tiles table, tile_row = 2^z - 1 - y (MBTiles 1.3)")
                                                   : (a->tms ? "{z}/{x}/{y}.png, y = 2^z - 1 - row (row 0 at the top)"
                                                             : "{z}/{x}/{y}.png, y = row (row 0 at the top)"));
    if (r->merc) {
        merc_manifest(r, f);
        goto inputs;
    }
    fprintf(f, "  \"tiling\": \"raster\",\n");
    fprintf(f, "  \"image\": {\"width\": %u, \"height\": %u, \"texels\": %u},\n", r->fw, r->fh, r->T);
    fprintf(f, "  \"levels\": {\"min\": 0, \"max\": %u, \"dense_max\": %u},\n", r->zmax, r->zd);
    fprintf(f, "  \"level_tiles\": [");
    for (uint32_t z = 0; z <= r->zmax; z++) {
        uint64_t s = span(r, z);
        fprintf(f, "%s[%llu, %llu]", z ? ", " : "", (unsigned long long)((r->nx + s - 1) / s),
                (unsigned long long)((r->ny + s - 1) / s));
    }
    fprintf(f, "],\n");
    fprintf(f, "  \"rule\": \"tile (x, y) of the finest level z = %u is the window [x*%u, (x+1)*%u) x [y*%u, (y+1)*%u) of "
               "the %u x %u image, pixels beyond it transparent (0,0,0,0); a tile of level z < %u is the 2x2 box "
               "filter of its four children (alpha the rounded mean, colour the alpha-weighted rounded mean); "
               "levels 0..%u are complete, a tile of a finer level is written only when it holds a road (a viewer "
               "over-zooms its parent)%s; PNG RGB when every pixel is opaque, else RGBA%s\",\n",
            r->zmax, r->S, r->S, r->S, r->S, r->fw, r->fh, r->zmax, r->zd,
            r->route ? "; a tile of level dense_max whose area, grown by each road's reach and 2 DEM cells, meets no "
                       "road's bounding box is terrain only: it is rendered directly at its own pixel size (the same "
                       "splat at texels / 2^(max - dense_max)) and nothing below it is rendered or written"
                     : "",
            r->P ? "; with halo P, a tile's file is (S + 2P) square: the tile's S x S pixels framed by the P pixels "
                   "around them of the same level's image (= its neighbour tiles' pixels; transparent beyond the image)"
                 : "");
    fprintf(f, "  \"frame\": {\"cell_size_m\": %.17g, \"pixel_m\": %.17g", cs, cs / r->T);
    if (geo) {
        fprintf(f, ", \"geotransform\": [%.17g, %.17g, %.17g, %.17g, %.17g, %.17g], \"crs\": ", gt[0], gt[1], gt[2],
                gt[3], gt[4], gt[5]);
        if (r->in->geo.crs) json_str(f, r->in->geo.crs);
        else fputs("null", f);
        fprintf(f, ", \"note\": \"geotransform of the finest level; level z has pixels 2^(%u - z) times larger\"",
                r->zmax);
        fprintf(f, ", \"extent\": [%.17g, %.17g, %.17g, %.17g]", gt[0], gt[3] + r->fh * gt[5], gt[0] + r->fw * gt[1],
                gt[3]);
    } else {
        fprintf(f, ", \"local\": \"metres from DEM sample (0,0), y down\", \"extent\": [0, 0, %.17g, %.17g]",
                r->fw * (cs / r->T), r->fh * (cs / r->T));
    }
    fprintf(f, "},\n");
inputs:
    fprintf(f, "  \"inputs\": [");
    for (int i = 0; i < nin; i++) {
        fprintf(f, "%s\n    {\"role\": \"%s\", \"path\": ", i ? "," : "", ih[i].role);
        json_str(f, ih[i].path);
        if (ih[i].hex[0]) fprintf(f, ", \"sha256\": \"%s\"}", ih[i].hex);
        else fprintf(f, ", \"sha256\": null}");
    }
    fprintf(f, "\n  ],\n  \"options\": [");
    for (int i = 0; i < a->nopt; i++) {
        fputs(i ? ", " : "", f);
        json_str(f, a->opt[i]);
    }
    fprintf(f, "],\n  \"fingerprint\": \"%s\",\n", r->fingerprint);
    if (r->layers > 1) nn = nw;
    fprintf(f, "  \"tiles_written\": %zu,\n  \"normal_tiles_written\": %zu,\n  \"tiles_road_free_not_written\": %zu,\n  \"tiles\": {",
            nw, nn, ne);
    for (size_t i = 0; i < nw; i++) {
        uint64_t key = keys[i] - 1;
        uint32_t z = (uint32_t)(key >> 58);
        uint64_t x = key >> 29 & ((1u << 29) - 1), y = key & ((1u << 29) - 1);
        entry *e = tfind(&r->tab, keys[i]);
        char hex[65];
        cli_sha256_hex(e->hash, hex);
        fprintf(f, "%s\n    \"%u/%llu/%llu\": \"%s\"", i ? "," : "", z, (unsigned long long)x,
                (unsigned long long)file_y(r, z, y), hex);
        if (r->layers > 1) {
            cli_sha256_hex(e->nhash, hex);
            fprintf(f, ",\n    \"%u/%llu/%llu_n\": \"%s\"", z, (unsigned long long)x, (unsigned long long)file_y(r, z, y),
                    hex);
        }
    }
    fprintf(f, "\n  }\n}\n");
    free(keys);
    return ferror(f) != 0;
}

/* ---- terrain-only subtrees ------------------------------------------------------- */

/* The road-free level-zd tiles (r->zfree) and the direct splatter: a
 * level-zd tile is terrain only when its area meets no road's box, the
 * bounding box of the road's points grown by its reach (half width or its
 * farthest line, plus casing, plus the largest marking of the atlas, plus
 * its explicit markings' |t| and size) and a margin of 2 DEM cells. Only
 * when T is divisible by 2^(zmax - zd) (the direct splat's texel count is
 * a whole number), and not with --dense, --terrain-texture, --normals,
 * lit output (lit by the normals; not a tiles option yet) or a DEM with
 * nodata: a texture's detail, or the normals of rough terrain,
 * rendered at the coarser size are not the mean of the finer pixels (mean
 * differences of 10 and 9 of 255 measured, against 0.2-0.4 for the tint
 * and hillshade; docs/tiles.md), and the nodata mask is per pixel. 0, or 1
 * after a message. */
static int route_setup(run *r, rs_ctx *ctx, const cli_splat_input *in, const rs_road_grid *grid, rs_splatter **dsp)
{
    const targs *a = r->a;
    uint32_t k = r->zmax - r->zd;
    if (r->merc || a->dense || a->render_all || k == 0 || k > 20 || r->T % (1u << k)) return 0;
    rs_splat_options o = a->s.o;
    if (o.surface.terrain_texture || a->normals || o.lighting.enable || in->nodata)
        return 0; /* docs/tiles.md, "Sparse levels" */
    o.texels = r->T >> k;
    o.progress = NULL;
    o.progress_user = NULL;
    if (rs_splatter_create(ctx, in->dem, NULL, grid, &o, dsp) && rs_splatter_create(ctx, in->dem, in->roads, NULL, &o, dsp)) {
        cli_error("%s: %s", a->roads, rs_ctx_message(ctx));
        return 1;
    }
    rs_splatter_size(*dsp, &r->dw, &r->dh);
    uint64_t sk = (uint64_t)1 << k;
    if (r->dw != (r->fw + sk - 1) / sk || r->dh != (r->fh + sk - 1) / sk) return 0; /* not the same grid: no route */
    r->zx = (r->nx + sk - 1) / sk;
    r->zy = (r->ny + sk - 1) / sk;
    if (!(r->zfree = malloc(r->zx * r->zy))) {
        cli_error("out of memory");
        return 1;
    }
    memset(r->zfree, 1, r->zx * r->zy);
    /* the largest marking of the atlas */
    double mark_max = 0;
    rs_atlas *own = NULL;
    const rs_atlas *atlas = in->atlas;
    if (!o.markings.disable) {
        if (!atlas && !rs_atlas_default(ctx, &own)) atlas = own;
        for (size_t i = 0, n = atlas ? rs_atlas_count(atlas) : 0; i < n; i++) {
            double L = 0, W = 0;
            if (!rs_atlas_get(atlas, i, NULL, &L, &W, NULL, NULL)) mark_max = fmax(mark_max, fmax(L, W));
        }
        if (!atlas) mark_max = 1e9; /* unknown: no route */
    }
    rs_atlas_free(ctx, own);
    rs_dem_frame fr;
    rs_dem_get_frame(in->dem, &fr);
    double cs = fr.cell_size > 0 ? fr.cell_size : 1, tile_m = cs / r->T * (double)r->S * (double)sk;
    size_t nroads = rs_roads_count(in->roads), nmarks = o.markings.disable ? 0 : rs_roads_mark_count(in->roads);
    double *extra = calloc(nroads ? nroads : 1, sizeof *extra);
    if (!extra) {
        cli_error("out of memory");
        return 1;
    }
    for (size_t m = 0; m < nmarks; m++) {
        rs_mark mk;
        if (rs_roads_get_mark(in->roads, m, &mk) || mk.road >= nroads) continue;
        double e = fabs(mk.t) + fmax(fmax(mk.length, mk.width), mark_max);
        if (e > extra[mk.road]) extra[mk.road] = e;
    }
    for (size_t i = 0; i < nroads; i++) {
        const double *xy;
        size_t n;
        double width = 0;
        if (rs_roads_get(in->roads, i, NULL, &width, &xy, &n) || !n) continue;
        double reach = width / 2;
        rs_style st;
        if (!o.style.disable && !rs_road_style(ctx, in->roads, i, o.style.styles, o.style.profile, &st)) {
            for (uint32_t l = 0; l < st.line_count; l++) reach = fmax(reach, fabs(st.line[l].offset) + st.line[l].width / 2);
            reach += st.casing_width;
        }
        reach += mark_max + 2 * cs;
        if (extra[i] + 2 * cs > reach) reach = extra[i] + 2 * cs;
        double x0 = xy[0], x1 = xy[0], y0 = xy[1], y1 = xy[1];
        for (size_t j = 1; j < n; j++) {
            x0 = fmin(x0, xy[2 * j]), x1 = fmax(x1, xy[2 * j]);
            y0 = fmin(y0, xy[2 * j + 1]), y1 = fmax(y1, xy[2 * j + 1]);
        }
        /* local metres from sample (0,0), in level-zd tiles */
        double tx0 = floor((x0 - fr.origin_x - reach) / tile_m), tx1 = floor((x1 - fr.origin_x + reach) / tile_m);
        double ty0 = floor((y0 - fr.origin_y - reach) / tile_m), ty1 = floor((y1 - fr.origin_y + reach) / tile_m);
        if (!(tx1 >= 0 && ty1 >= 0 && tx0 < (double)r->zx && ty0 < (double)r->zy)) {
            if (isnan(tx0) || isnan(tx1) || isnan(ty0) || isnan(ty1)) memset(r->zfree, 0, r->zx * r->zy);
            continue;
        }
        uint64_t a0 = tx0 < 0 ? 0 : (uint64_t)tx0, a1 = tx1 >= (double)r->zx ? r->zx - 1 : (uint64_t)tx1;
        uint64_t b0 = ty0 < 0 ? 0 : (uint64_t)ty0, b1 = ty1 >= (double)r->zy ? r->zy - 1 : (uint64_t)ty1;
        for (uint64_t ty = b0; ty <= b1; ty++) memset(r->zfree + ty * r->zx + a0, 0, a1 - a0 + 1);
    }
    free(extra);
    r->route = 1;
    return 0;
}

/* The work under (z, x, y) in finest-tile renders: a terrain-only tile
 * counts as one (it is one render of S x S pixels). */
static uint64_t work(const run *r, uint32_t z, uint64_t x, uint64_t y)
{
    if (!exists(r, z, x, y)) return 0;
    if (z == r->zmax || (z == r->zd && zone_free(r, x, y))) return 1;
    uint64_t w = 0;
    for (int q = 0; q < 4; q++) w += work(r, z + 1, 2 * x + (q & 1), 2 * y + (q >> 1));
    return w;
}

/* The Morton rank of the first finest tile after `target` units of work
 * (terrain-only tiles are not split: a boundary inside one moves to its
 * start). */
static uint64_t work_bound(const run *r, uint64_t target)
{
    uint32_t z = 0;
    uint64_t x = 0, y = 0, rank = 0, done = 0;
    for (;;) {
        if (z == r->zmax || (z == r->zd && zone_free(r, x, y))) return rank;
        int q = 0;
        for (; q < 4; q++) {
            uint64_t cx = 2 * x + (q & 1), cy = 2 * y + (q >> 1), w = work(r, z + 1, cx, cy);
            if (done + w > target) {
                x = cx, y = cy;
                break;
            }
            done += w;
            rank += finest_count(r, z + 1, cx, cy);
        }
        if (q == 4) return rank;
        z++;
    }
}

/* ---- main ------------------------------------------------------------------------ */

/* OUTDIR/tiles.xml, GDAL's description of the pyramid (cli_tiles_gdal_xml)
 * for a georeferenced run: the level dense_max, the finest complete one
 * (a finer level lacks its road-free tiles, which GDAL would read as
 * holes). */
static int gdal_description(const run *r)
{
    double ul[2], px;
    uint32_t z = r->zd, k = r->zmax - z;
    if (r->merc) {
        if ((uint64_t)r->S << z > 0x7fffffffull) return 0; /* GDAL's raster size is an int: no description */
        px = 2 * CLI_MERC_HALF / ((double)r->S * (double)((uint64_t)1 << z));
        ul[0] = -CLI_MERC_HALF, ul[1] = CLI_MERC_HALF;
        return cli_tiles_gdal_xml(r->a->out, ul, px, z, r->S, r->a->tms, "EPSG:3857");
    }
    double gt[6];
    if (cli_geo_texture_gt(r->in, r->T, 0, 0, gt) || !r->in->geo.crs) return 0;
    px = gt[1] * (double)((uint64_t)1 << k);
    ul[0] = gt[0], ul[1] = gt[3];
    if ((uint64_t)r->S << z > 0x7fffffffull) return 0;
    return cli_tiles_gdal_xml(r->a->out, ul, px, z, r->S, r->a->tms, r->in->geo.crs);
}

static uint32_t floor_log2(uint32_t v)
{
    uint32_t k = 0;
    while (v >> (k + 1)) k++;
    return k;
}

/* First Morton rank of shard i of n over `total` finest tiles. */
static uint64_t shard_bound(uint64_t total, uint32_t i, uint32_t n)
{
    return total / n * i + total % n * i / n; /* floor(total * i / n) without overflow */
}

int cli_tiles_main(int argc, char **argv)
{
    targs a;
    int pr = parse_targs(argc, argv, &a);
    if (pr) {
        free(a.opt);
        return pr == 2 ? 0 : 1;
    }
    int rc = 1;
    rs_ctx *ctx = NULL;
    cli_splat_input in;
    rs_road_grid *grid = NULL;
    rs_splatter *sp = NULL, *dsp = NULL;
    run r;
    cli_out mout, mani;
    input_hash *ih = NULL;
    int nin = 0;
    char *logdir = NULL;
    int logfd = -1;
    memset(&in, 0, sizeof in);
    memset(&r, 0, sizeof r);
    memset(&mout, 0, sizeof mout);
    memset(&mani, 0, sizeof mani);
    r.a = &a;
    r.S = a.tile;
    r.P = a.halo;
    r.side = r.S + 2 * r.P;
    r.layers = a.normals ? 2 : 1;

    /* the output: a folder (made here; its parent must exist) or one file */
    struct stat st;
    if (!a.out[0]) {
        cli_error("tiles: OUTDIR is empty");
        goto done;
    }
    if (a.mbtiles) {
        const cli_file_role outs[1] = { { a.out, "OUT" } };
        const cli_file_role ins[2] = { { a.dem, "DEM" }, { a.roads, "ROADS" } };
        if (cli_check_outputs(outs, 1, ins, 2)) goto done;
#ifndef RS_WITH_SQLITE
        cli_error("--format mbtiles: this roadsplat was built without SQLite (make deps installs libsqlite3-dev; rebuild)");
        goto done;
#else
        void *sym = cli_module_symbol("mbtiles", "cli_mbtiles_api_v2", "--format mbtiles");
        if (!sym) goto done;
        r.mb = sym;
#endif
    } else {
        if (stat(a.out, &st) == 0 && !S_ISDIR(st.st_mode)) {
            cli_error("%s: OUTDIR exists and is not a folder", a.out);
            goto done;
        }
        if (mkdir(a.out, 0777) != 0 && errno != EEXIST) {
            cli_error("%s: cannot create the folder: %s", a.out, strerror(errno));
            goto done;
        }
    }

    /* the splat, with no limit on the output size: tiles never hold it */
    rs_limits lim;
    memset(&lim, 0, sizeof lim);
    lim.max_pixels = (uint64_t)1 << 52;
    cli_splat_limits(&a.s, &lim);
    rs_result res = rs_ctx_create(NULL, &lim, &ctx);
    if (res) {
        cli_error("%s", rs_strerror(res));
        goto done;
    }
    cli_inputs_keep_pipes(1); /* the manifest hashes a pipe's bytes too */
    /* the default 8 texels set before the load, which puts the surface
     * textures on the world's pixel grid at this texel size (with 0 it
     * divided by zero) */
    if (!a.s.o.texels && !a.s.pixel_size) a.s.o.texels = 8;
    if (cli_splat_input_load(ctx, a.dem, a.roads, &a.s, &in)) goto done;
    /* every file the run read (the styles' surface images too) is hashed
     * as loaded; an MBTiles OUT naming one of them is refused now */
    if ((a.mbtiles && cli_inputs_check_output(a.out, "OUT")) || hash_inputs(&ih, &nin)) goto done;
    fingerprint(&a, ih, nin, r.fingerprint);
    run_id(r.runid);
    if (a.mercator) { /* the grid, and the splat's texels the tiles are resampled from */
        if (cli_merc_open(&in, a.dem, r.S, a.s.o.texels ? a.s.o.texels : 8, a.zoom_min, a.zoom_max, &r.merc, &r.mg))
            goto done;
        /* the source splat's texels, and its surface textures on the world's pixel
         * grid at that size (as cli_splat_input_load puts them for the options') */
        double px = in.geo.gt[1] / r.mg.texels, wx = (in.geo.gt[0] + in.geo.gt[1] / 2) / px,
               wy = -(in.geo.gt[3] + in.geo.gt[5] / 2) / px;
        a.s.o.texels = r.mg.texels;
        if (fabs(wx) < 1e15 && fabs(wy) < 1e15) {
            a.s.o.surface.texel_offset_x = (int64_t)floor(wx + 0.5);
            a.s.o.surface.texel_offset_y = (int64_t)floor(wy + 0.5);
        }
    }
    if ((res = rs_splat_size(ctx, in.dem, &a.s.o, &r.fw, &r.fh))) {
        cli_error("%s: %s", a.dem, rs_ctx_message(ctx));
        goto done;
    }
    r.in = &in;
    r.T = a.s.o.texels ? a.s.o.texels : 8;
    r.nx = (r.fw + (uint64_t)r.S - 1) / r.S;
    r.ny = (r.fh + (uint64_t)r.S - 1) / r.S;
    while (!r.merc && ((uint64_t)1 << r.zmax) < (r.nx > r.ny ? r.nx : r.ny)) r.zmax++;
    if (r.merc) r.nx = r.mg.nx, r.ny = r.mg.ny, r.fx0 = r.mg.fx0, r.fy0 = r.mg.fy0, r.zmax = r.mg.zmax, r.zmin = r.mg.zmin;
    if (r.zmax > MAX_ZOOM) {
        cli_error("%s: a %u x %u image needs more than %d levels of %u-pixel tiles", a.dem, r.fw, r.fh, MAX_ZOOM, r.S);
        goto done;
    }
    uint32_t lt = floor_log2(r.T);
    r.zd = a.dense || lt >= r.zmax ? (a.dense ? r.zmax : 0) : r.zmax - lt;
    if (r.merc && !a.dense) r.zd = r.mg.zd;
    uint64_t total = r.nx * r.ny;
    r.lo = shard_bound(total, a.shard_i, a.shard_n);
    r.hi = shard_bound(total, a.shard_i + 1, a.shard_n);
    r.total_finest = r.hi - r.lo;

    /* logs: read (--resume, --from-children), then this run's own */
    if (!a.mbtiles) {
        logdir = join(a.out, LOG_DIR, NULL);
        if (!logdir || (mkdir(logdir, 0777) != 0 && errno != EEXIST)) {
            cli_error("%s/%s: cannot create the folder: %s", a.out, LOG_DIR, strerror(errno));
            goto done;
        }
        /* the log folder itself, never a symbolic link to another folder */
        if ((logfd = open(logdir, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC)) < 0) {
            cli_error("%s: %s; it must be a real folder (remove it)", logdir,
                      errno == ELOOP || errno == ENOTDIR ? "is a symbolic link or not a folder" : strerror(errno));
            goto done;
        }
        char name[64];
        if (a.from_children) snprintf(name, sizeof name, "merge.log");
        else if (a.sharded) snprintf(name, sizeof name, "shard-%u-of-%u.log", a.shard_i, a.shard_n);
        else snprintf(name, sizeof name, "whole.log");
        if (a.resume || a.from_children) {
            if (load_logs(&r, logdir, logfd)) goto done;
        } else if (!a.sharded) {
            clear_logs(logfd, name);
        }
        r.log_path = join(logdir, name, NULL);
        int append = a.resume || a.from_children;
        int lfd = r.log_path ? open_log_file(logfd, name, r.log_path, O_RDWR | O_CREAT | (append ? O_APPEND : 0)) : -1;
        if (lfd < 0) goto done;
        if (lock_log(&r, lfd)) { /* the earlier runs' ids: before the truncation below */
            /* another run of this step into OUTDIR is alive: a log of this run's own, "NAME-RUNID.log" */
            char own[96];
            close(lfd);
            snprintf(own, sizeof own, "%.*s-%s.log", (int)(strlen(name) - 4), name, r.runid);
            free(r.log_path);
            r.log_path = join(logdir, own, NULL);
            lfd = r.log_path ? open_log_file(logfd, own, r.log_path, O_RDWR | O_CREAT | O_EXCL) : -1;
            if (lfd < 0) goto done;
            lock_log(&r, lfd);
            append = 0;
        }
        if (!append && (ftruncate(lfd, 0) != 0 || lseek(lfd, 0, SEEK_SET) != 0)) {
            cli_error("%s: %s", r.log_path, strerror(errno));
            close(lfd);
            goto done;
        }
        if (!(r.log = fdopen(lfd, append ? "a+" : "w+"))) {
            cli_error("%s: %s", r.log_path, strerror(errno));
            close(lfd);
            goto done;
        }
        if (append) { /* a line cut by a kill ends here */
            long end = (fseek(r.log, 0, SEEK_END), ftell(r.log));
            if (end > 0 && fseek(r.log, end - 1, SEEK_SET) == 0 && fgetc(r.log) != '\n') {
                fseek(r.log, 0, SEEK_END);
                fputc('\n', r.log);
            }
            fseek(r.log, 0, SEEK_END);
            if (end <= 0) fprintf(r.log, "roadsplat-tiles-log 1 %s\n", r.fingerprint);
        } else {
            fprintf(r.log, "roadsplat-tiles-log 1 %s\n", r.fingerprint);
            for (int k = 0; k < r.n_old; k++) fprintf(r.log, "run %s\n", r.old_ids[k]); /* still to clean */
        }
        fprintf(r.log, "run %s\n", r.runid);
        if (fflush(r.log) != 0) {
            cli_error("%s: write failed: %s", r.log_path, strerror(errno));
            goto done;
        }
    } else {
        r.log = fopen("/dev/null", "w");
        r.log_path = join(a.out, "", NULL);
        if (!r.log || !r.log_path) {
            cli_error("/dev/null: %s", strerror(errno));
            goto done;
        }
        if (cli_out_open(&mout, a.out)) goto done;
        fclose(mout.f);
        mout.f = NULL;
        if (!(r.db = r.mb->open(mout.tmp, a.out, a.normals))) goto done;
    }

    if (cli_splatter_prepare(ctx, &in, a.roads, &a.s, a.quiet, &grid, &sp)) goto done;
    r.sp = sp;
    if (route_setup(&r, ctx, &in, grid, &dsp)) goto done;
    r.dsp = dsp;
    if (r.route && a.shard_n > 1) { /* shards of equal work rather than equal tile counts */
        uint64_t wt = work(&r, 0, 0, 0);
        r.lo = work_bound(&r, shard_bound(wt, a.shard_i, a.shard_n));
        r.hi = a.shard_i + 1 == a.shard_n ? r.nx * r.ny : work_bound(&r, shard_bound(wt, a.shard_i + 1, a.shard_n));
        r.total_finest = r.hi - r.lo;
    }
    {
        cli_splat_job j0;
        cli_splat_job_init(&j0, sp, &a.s, 1);
        r.threads = j0.threads;
    }
    for (int l = 0; l < r.layers; l++)
        for (uint32_t d = 0; d <= r.zmax; d++)
            if (r.P && !(r.lbuf[l][d] = malloc((size_t)r.S * r.S * 4))) {
                cli_error("out of memory for the tile buffers");
                goto done;
            }
    size_t side2 = (size_t)r.side * r.side;
    if (!(r.full = malloc(side2 * 4)) || !(r.scratch = malloc(side2 * 4)) ||
        (r.layers > 1 && !(r.nrgb = malloc(side2 * 3)))) {
        cli_error("out of memory for the tile buffers");
        goto done;
    }
    cli_progress_init(&r.prog, "tiles", a.quiet);
    if (pool_start(&r, r.threads > 1 ? r.threads : 0)) goto done;
    r.one_band = r.pl->nth > 0;
    int bad = visit(&r, 0, 0, 0, 0) || pool_commit(&r, 1);
    cli_progress_done(&r.prog);
    pool_stop(&r, bad);
    if (bad) goto done;
    if (fflush(r.log) != 0 || ferror(r.log)) {
        cli_error("%s: write failed: %s", r.log_path, strerror(errno ? errno : EIO));
        goto done;
    }

    if (!a.sharded) {
        if (a.mbtiles) {
            char *text = NULL, num[32];
            size_t tn = 0;
            FILE *mf = open_memstream(&text, &tn);
            int mb = !mf || manifest(&r, mf, ih, nin);
            if (mf && fclose(mf) != 0) mb = 1;
            const char *base = strrchr(a.out, '/') ? strrchr(a.out, '/') + 1 : a.out;
            mb = mb || r.mb->meta(r.db, "name", base) || r.mb->meta(r.db, "format", "png") ||
                 r.mb->meta(r.db, "type", "baselayer") || r.mb->meta(r.db, "version", "1") ||
                 r.mb->meta(r.db, "description", "roadsplat terrain texture with roads");
            snprintf(num, sizeof num, "%u", r.zmin);
            mb = mb || r.mb->meta(r.db, "minzoom", num);
            if (r.merc) { /* MBTiles 1.3: WGS84 bounds and centre, for web-map tiles only */
                char bounds[160], center[160];
                cli_merc_bounds_text(&r.mg, bounds, sizeof bounds);
                cli_merc_center_text(&r.mg, center, sizeof center);
                mb = mb || r.mb->meta(r.db, "bounds", bounds) || r.mb->meta(r.db, "center", center);
            }
            snprintf(num, sizeof num, "%u", r.zmax);
            mb = mb || r.mb->meta(r.db, "maxzoom", num) || r.mb->meta(r.db, "roadsplat_manifest", text);
            free(text);
            void *db = r.db;
            r.db = NULL;
            if (r.mb->close(db, !mb) || mb) goto done;
            cli_out *one[1] = { &mout }; /* closed: SQLite wrote it */
            if (cli_out_commit_all(one, 1)) goto done;
        } else {
            char *mp = join(a.out, "tiles.json", NULL);
            if (!mp || cli_out_open(&mani, mp)) {
                free(mp);
                goto done;
            }
            free(mp);
            if (manifest(&r, mani.f, ih, nin)) {
                cli_error("%s: write failed: %s", mani.path, strerror(errno ? errno : EIO));
                goto done;
            }
            if (cli_out_commit(&mani)) goto done;
            if (gdal_description(&r)) goto done;
            if (a.viewer) {
                cli_viewer_info vi = { r.S, r.fw, r.fh, r.zmax, r.zd, a.tms, "roadsplat tiles",
                                       a.attribution ? a.attribution : "rendered with roadsplat", r.merc != NULL,
                                       r.zmin, { r.mg.ll[0], r.mg.ll[1], r.mg.ll[2], r.mg.ll[3] } };
                if (cli_tiles_viewer(a.out, &vi)) goto done;
            }
        }
    }
    if (!a.quiet && !r.merc && in.geo.georef && !a.sharded)
        fprintf(stderr, "roadsplat: note: %s: the raster tiling is the DEM's own pixel grid, not Web Mercator: "
                        "web maps and MBTiles readers would misplace it (%s); --tiling mercator writes web-map "
                        "tiles\n",
                a.out, a.mbtiles ? "its roadsplat_manifest records the georeference" : "tiles.xml opens it in place with GDAL");
    if (!a.quiet)
        fprintf(stderr,
                "roadsplat: tiles: %llu rendered, %llu written, %llu road-free not written, %llu kept from earlier runs, "
                "%llu terrain-only rendered at level %u%s\n",
                (unsigned long long)r.rendered, (unsigned long long)r.written, (unsigned long long)r.road_free,
                (unsigned long long)r.kept, (unsigned long long)r.direct, r.zd,
                a.sharded ? "; run --from-children once every shard is done" : "");
    rc = 0;
done:
    pool_stop(&r, 1);
    if (r.db) r.mb->close(r.db, 0);
    cli_out_abort(&mout);
    cli_out_abort(&mani);
    if (r.log) fclose(r.log);
    for (int l = 0; l < 2; l++)
        for (uint32_t d = 0; d <= MAX_ZOOM + 1; d++) free(r.lbuf[l][d]);
    free(r.full);
    free(r.scratch);
    free(r.nrgb);
    free(r.path);
    free(r.log_path);
    free(r.tab.e);
    free(logdir);
    if (logfd >= 0) close(logfd);
    free(ih);
    cli_inputs_clear();
    rs_splatter_free(ctx, dsp);
    cli_merc_close(r.merc);
    free(r.zfree);
    rs_splatter_free(ctx, sp);
    rs_road_grid_free(ctx, grid);
    cli_splat_input_free(ctx, &in);
    rs_ctx_free(ctx);
    free(a.opt);
    return rc;
}
