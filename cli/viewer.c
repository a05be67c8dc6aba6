/* `roadsplat tiles --viewer`: OUTDIR/index.html showing the pyramid on a
 * Leaflet map (issue 28, docs/tiles.md "Viewer"), with Leaflet copied from
 * Debian's libjs-leaflet into OUTDIR/leaflet/ (no CDN: the folder works
 * offline and from file://).
 *
 * Raster tiling (image space): Leaflet's CRS.Simple, one map unit =
 * 2^zmax image pixels, so a level-z tile spans S / 2^z units as Leaflet's
 * zoom z does; image y runs down, latitude up (lat = -y). Levels above
 * dense_max hold only tiles with roads: they are a second layer over the
 * complete levels, whose missing tiles stay transparent, so the coarser
 * picture shows through wherever no finer tile was written.
 *
 * Mercator tiling (EPSG:3857 XYZ tiles): Leaflet's default CRS, the tiles
 * at their geographic place, the same two layers; #Z/LAT/LON views. No
 * basemap: the page loads nothing from the network. */
#include "viewer.h"
#include "cli.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define LEAFLET_DIR "/usr/share/javascript/leaflet"

static char *join2(const char *a, const char *b)
{
    size_t na = strlen(a), nb = strlen(b);
    char *p = malloc(na + nb + 2);
    if (!p) return NULL;
    memcpy(p, a, na);
    size_t k = na;
    if (k && p[k - 1] != '/') p[k++] = '/';
    memcpy(p + k, b, nb + 1);
    return p;
}

/* Copies one file of Leaflet into OUTDIR/leaflet/ (atomic, like every output). */
static int copy_asset(const char *outdir, const char *name)
{
    char *src = join2(LEAFLET_DIR, name), *dir = join2(outdir, "leaflet"), *dst = dir ? join2(dir, name) : NULL;
    char *data = NULL;
    size_t n = 0;
    int rc = 1;
    cli_out o;
    memset(&o, 0, sizeof o);
    if (!src || !dst) cli_error("out of memory");
    else if (cli_read_file(src, (size_t)16 << 20, &data, &n))
        cli_error("--viewer: Leaflet is missing (%s); install it: apt-get install libjs-leaflet (or run 'make deps')",
                  src);
    else if (cli_out_open(&o, dst) == 0) {
        if (fwrite(data, 1, n, o.f) != n) cli_error("%s: write failed: %s", dst, strerror(errno ? errno : EIO));
        else rc = cli_out_commit(&o);
    }
    cli_out_abort(&o);
    free(src);
    free(dir);
    free(dst);
    free(data);
    return rc;
}

/* Writes s into the HTML with <, >, & and quotes escaped. */
static void put_escaped(FILE *f, const char *s)
{
    for (; *s; s++) {
        switch (*s) {
        case '<': fputs("&lt;", f); break;
        case '>': fputs("&gt;", f); break;
        case '&': fputs("&amp;", f); break;
        case '"': fputs("&quot;", f); break;
        case '\'': fputs("&#39;", f); break;
        default: fputc(*s, f);
        }
    }
}

/* The attribution inside a JS string inside HTML: both escaped. */
static void put_js_attribution(FILE *f, const char *s)
{
    for (; *s; s++) {
        if (*s == '\\' || *s == '\'') fputc('\\', f);
        if (*s == '<') fputs("&lt;", f);
        else if (*s == '>') fputs("&gt;", f);
        else if (*s == '&') fputs("&amp;", f);
        else if (*s == '\n' || *s == '\r') fputc(' ', f);
        else fputc(*s, f);
    }
}

/* The script of a Web Mercator pyramid: Leaflet's default CRS (EPSG:3857). */
static void mercator_script(FILE *f, const cli_viewer_info *v)
{
    fprintf(f, "var S = %u, zmin = %u, zmax = %u, zdense = %u, tms = %s;\n", v->tile, v->zmin, v->zmax, v->zdense,
            v->tms ? "true" : "false");
    fprintf(f, "var bounds = L.latLngBounds([%.12g, %.12g], [%.12g, %.12g]);\n", v->bounds[1], v->bounds[0],
            v->bounds[3], v->bounds[2]);
    /* Leaflet's zoom z is the XYZ zoom only for 256-pixel tiles: a 512 tile is
     * shown at zoomOffset -1 */
    fprintf(f, "var off = -Math.round(Math.log2(S / 256));\n");
    fprintf(f, "var map = L.map('map', { minZoom: Math.max(0, zmin - off - 2), maxZoom: zmax - off + 2, zoomSnap: 0.25 });\n");
    fprintf(f, "var opts = { tileSize: S, zoomOffset: off, tms: tms, bounds: bounds, minZoom: Math.max(0, zmin - off - 2),"
               " maxZoom: zmax - off + 2 };\n");
    fprintf(f, "// the complete levels, stretched beyond zdense; the sparse ones over them\n");
    fprintf(f, "L.tileLayer('{z}/{x}/{y}.png', Object.assign({}, opts, { minNativeZoom: zmin - off, maxNativeZoom: zdense - off,"
               " errorTileUrl: '', attribution: '");
    put_js_attribution(f, v->attribution);
    fprintf(f, "' })).addTo(map);\n");
    fprintf(f, "if (zmax > zdense) L.tileLayer('{z}/{x}/{y}.png', Object.assign({}, opts, { minZoom: zdense + 1 - off,"
               " minNativeZoom: zdense + 1 - off, maxNativeZoom: zmax - off, errorTileUrl: '' })).addTo(map);\n");
    fprintf(f, "// #Z/LAT/LON: zoom Z centred there; else the whole map\n"
               "var m = location.hash.match(/^#([\\d.]+)\\/(-?[\\d.]+)\\/(-?[\\d.]+)$/);\n"
               "if (m) map.setView([+m[2], +m[3]], +m[1], { animate: false });\n"
               "else map.fitBounds(bounds);\n"
               "var touched = !!m;\n"
               "['mousedown', 'wheel', 'touchstart', 'keydown'].forEach(function (e) {\n"
               "  map.getContainer().addEventListener(e, function () { touched = true; }); });\n"
               "map.on('resize', function () { if (!touched) map.fitBounds(bounds); });\n"
               "map.on('moveend', function () { var c = map.getCenter();\n"
               "  history.replaceState(null, '', '#' + map.getZoom() + '/' + c.lat.toFixed(7) + '/' + c.lng.toFixed(7)); });\n"
               "map.setMaxBounds(bounds.pad(0.5));\n");
}

int cli_tiles_viewer(const char *outdir, const cli_viewer_info *v)
{
    char *ldir = join2(outdir, "leaflet"), *idir = ldir ? join2(ldir, "images") : NULL;
    if (!ldir || !idir) {
        free(ldir);
        free(idir);
        cli_error("out of memory");
        return 1;
    }
    int rc = 1;
    if ((mkdir(ldir, 0777) != 0 && errno != EEXIST) || (mkdir(idir, 0777) != 0 && errno != EEXIST)) {
        cli_error("%s: cannot create: %s", idir, strerror(errno));
        goto out;
    }
    static const char *const assets[] = { "leaflet.js", "leaflet.css", "images/layers.png", "images/layers-2x.png" };
    for (size_t i = 0; i < sizeof assets / sizeof *assets; i++)
        if (copy_asset(outdir, assets[i])) goto out;
    char *ip = join2(outdir, "index.html");
    if (!ip) {
        cli_error("out of memory");
        goto out;
    }
    cli_out o;
    memset(&o, 0, sizeof o);
    if (cli_out_open(&o, ip) != 0) {
        free(ip);
        goto out;
    }
    free(ip);
    FILE *f = o.f;
    const double unit = (double)(1ull << v->zmax); /* image pixels per map unit */
    fprintf(f, "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
               "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<title>");
    put_escaped(f, v->title);
    fprintf(f, "</title>\n<link rel=\"stylesheet\" href=\"leaflet/leaflet.css\">\n"
               "<style>html, body, #map { height: 100%%; margin: 0; background: #ddd; }</style>\n"
               "<script src=\"leaflet/leaflet.js\"></script>\n</head>\n<body>\n<div id=\"map\"></div>\n<script>\n");
    fprintf(f, "// written by roadsplat tiles --viewer (docs/tiles.md, \"Viewer\")\n");
    if (v->mercator) {
        mercator_script(f, v);
        fprintf(f, "</script>\n</body>\n</html>\n");
        goto written;
    }
    fprintf(f, "var S = %u, W = %u, H = %u, zmax = %u, zdense = %u, unit = %.17g, tms = %s;\n", v->tile, v->width,
            v->height, v->zmax, v->zdense, unit, v->tms ? "true" : "false");
    fprintf(f, "var Tiles = L.TileLayer.extend({ getTileUrl: function (c) {\n"
               "  var y = tms ? (Math.pow(2, c.z) - 1 - c.y) : c.y;\n"
               "  return c.z + '/' + c.x + '/' + y + '.png'; } });\n");
    fprintf(f, "var bounds = L.latLngBounds([-H / unit, 0], [0, W / unit]);\n");
    fprintf(f, "var map = L.map('map', { crs: L.CRS.Simple, minZoom: 0, maxZoom: zmax + 2, zoomSnap: 0.25, attributionControl: true });\n");
    fprintf(f, "var opts = { tileSize: S, noWrap: true, bounds: bounds, minZoom: 0, maxZoom: zmax + 2 };\n");
    fprintf(f, "// the complete levels, stretched beyond zdense; the sparse ones over them\n");
    fprintf(f, "new Tiles('', Object.assign({}, opts, { maxNativeZoom: zdense, attribution: '");
    put_js_attribution(f, v->attribution);
    fprintf(f, "' })).addTo(map);\n");
    fprintf(f, "if (zmax > zdense) new Tiles('', Object.assign({}, opts, { minZoom: zdense + 1, maxNativeZoom: zmax,"
               " errorTileUrl: '' })).addTo(map);\n");
    fprintf(f, "// #Z/X/Y: zoom Z centred on image pixel (X, Y); else the whole image\n"
               "var m = location.hash.match(/^#(\\d+)\\/([\\d.]+)\\/([\\d.]+)$/);\n"
               "if (m) map.setView([-m[3] / unit, +m[2] / unit], +m[1], { animate: false });\n"
               "else map.fitBounds(bounds);\n"
               "// the first layout may come before the window has its size: fit again\n"
               "// on resize until the user moves the map\n"
               "var touched = !!m;\n"
               "['mousedown', 'wheel', 'touchstart', 'keydown'].forEach(function (e) {\n"
               "  map.getContainer().addEventListener(e, function () { touched = true; }); });\n"
               "map.on('resize', function () { if (!touched) map.fitBounds(bounds); });\n"
               "map.on('moveend', function () { var c = map.getCenter();\n"
               "  history.replaceState(null, '', '#' + map.getZoom() + '/' + Math.round(c.lng * unit) + '/' + "
               "Math.round(-c.lat * unit)); });\n"
               "map.setMaxBounds(bounds.pad(0.5));\n</script>\n</body>\n</html>\n");
written:
    if (fflush(f) != 0 || ferror(f)) {
        cli_error("%s: write failed: %s", o.path, strerror(errno ? errno : EIO));
        cli_out_abort(&o);
        goto out;
    }
    rc = cli_out_commit(&o);
out:
    free(ldir);
    free(idir);
    return rc;
}
