/* roadsplat-gdal.so: the GDAL layer of the CLI (issue 17), loaded on first
 * use (cli/module.c) so that runs without GIS data never map GDAL. Reads
 * georeferenced DEMs and OGR road sources, writes GeoTIFFs; the splat
 * itself stays in the library, which never sees GDAL. Interface and rules:
 * cli/gis.h; the road attribute mapping: docs/gis.md. */
#include "gis.h"

#include <cpl_conv.h>
#include <gdal_alg.h>
#include <cpl_error.h>
#include <cpl_string.h>
#include <gdal.h>
#include <ogr_api.h>
#include <ogr_srs_api.h>

#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

/* GDAL's last error as one line (newlines folded), or `fallback`. */
static const char *last_error(const char *fallback)
{
    static char buf[400];
    const char *m = CPLGetLastErrorMsg();
    if (!m || !m[0]) return fallback;
    size_t n = 0;
    for (; m[n] && n + 1 < sizeof buf; n++) buf[n] = (m[n] == '\n' || m[n] == '\r') ? ' ' : m[n];
    buf[n] = '\0';
    return buf;
}

/* Untrusted inputs (no --gdal-trust): GDAL makes no network request.
 * /vsicurl/ reads only files of an extension nothing has, every HTTP
 * request of GDAL's own (schemas, the HTTP driver, WMS, ...) goes to a
 * proxy on the discard port of this host, which refuses it, and a VRT
 * cannot read raw bytes of any file. Paths that are URLs never reach GDAL
 * (cli_gdal_path_check). */
static void network_off(void)
{
    static const char *const opts[][2] = {
        { "CPL_VSIL_CURL_ALLOWED_EXTENSIONS", ".roadsplat-network-disabled" },
        { "CPL_VSIL_CURL_ALLOWED_FILENAME", "roadsplat-network-disabled" },
        { "GDAL_HTTP_PROXY", "127.0.0.1:9" },
        { "GDAL_HTTPS_PROXY", "127.0.0.1:9" },
        { "GDAL_HTTP_MAX_RETRY", "0" },
        { "GDAL_HTTP_TIMEOUT", "1" },
        { "GML_DOWNLOAD_WFS_SCHEMA", "NO" },
        { "GML_SKIP_RESOLVE_ELEMS", "ALL" },
        { "GDAL_VRT_ENABLE_RAWRASTERBAND", "NO" },
        { "GDAL_VRT_ENABLE_PYTHON", "NO" },
    };
    for (size_t i = 0; i < sizeof opts / sizeof opts[0]; i++) CPLSetConfigOption(opts[i][0], opts[i][1]);
}

static void init(void)
{
    static int done;
    if (!done) {
        done = 1;
        GDALAllRegister();
        CPLSetErrorHandler(CPLQuietErrorHandler); /* messages come from us, one line each */
    }
    if (!cli_gdal_trusted()) network_off();
}

/* The drivers untrusted DEMs and roads are opened with: formats of one
 * local file (or a folder of them) that read no other file by a name
 * written inside it. A VRT is checked first (vrt_sources_local). */
static const char *const dem_drivers[] = { "GTiff", "AAIGrid", "GSAG", "GSBG", "GS7BG", "SRTMHGT", "EHdr", "ENVI",
                                           "XYZ", "USGSDEM", "HFA", "PNG", "JPEG", "BMP", "GIF", "BT", "ERS", "RST",
                                           "JP2OpenJPEG", "NetCDF", "VRT", NULL };
static const char *const road_drivers[] = { "GeoJSON", "GeoJSONSeq", "ESRIJSON", "TopoJSON", "GPKG", "SQLite",
                                            "ESRI Shapefile", "OSM", "FlatGeobuf", "GML", "KML", "CSV",
                                            "OpenFileGDB", "MapInfo File", "GPX", NULL };

/* Image formats a DEM without georeference is read in by OpenImageIO, as
 * before GDAL: when GDAL does not open one, OpenImageIO gets the file. */
static int image_format(const char *driver)
{
    static const char *const names[] = { "PNG", "GTiff", "JPEG", "BMP", "PNM", "EXR", "WEBP", "HEIF", "JPEGXL", "DDS",
                                         NULL };
    for (size_t i = 0; names[i]; i++)
        if (!strcmp(names[i], driver)) return 1;
    return 0;
}

/* Untrusted: 0 when the driver that identifies `name` (GDAL's name for the
 * input `path`) is allowed (list),
 * 2 when none does, 1 after a message naming the driver and the flag. */
static int driver_allowed(const char *name, const char *path, unsigned kind, const char *const *list,
                          const char *what)
{
    if (cli_gdal_trusted()) return 0;
    GDALDriverH d = GDALIdentifyDriverEx(name, kind, NULL, NULL);
    if (!d) return 2;
    const char *dn = GDALGetDriverShortName(d);
    for (size_t i = 0; list[i]; i++)
        if (!strcmp(list[i], dn)) return 0;
    if (image_format(dn)) return 2; /* OpenImageIO reads it, from that one file */
    cli_error("%s: GDAL reads it with its %s driver, which roadsplat uses for %s only with --gdal-trust (it may "
              "read other files or the network; docs/ROBUSTNESS.md)", path, dn, what);
    return 1;
}

static int vrt_sources_local(const char *path, int depth);

/* The elements under n (siblings and their children, XML depth `level`)
 * of the VRT `path`: 0, or 1 after a message (vrt_sources_local). */
static int vrt_nodes_local(const char *path, const CPLXMLNode *n, int depth, int level)
{
    if (level > 32) {
        cli_error("%s: the VRT is nested too deeply", path);
        return 1;
    }
    for (; n; n = n->psNext) {
        if (n->eType != CXT_Element) continue;
        if (!strcmp(n->pszValue, "VRTRasterBand")) {
            const char *sub = CPLGetXMLValue(n, "subClass", NULL);
            if (sub && strcmp(sub, "VRTSourcedRasterBand")) {
                cli_error("%s: a VRT band of kind %s is read only with --gdal-trust (docs/ROBUSTNESS.md)", path, sub);
                return 1;
            }
        } else if (!strcmp(n->pszValue, "SourceFilename")) {
            const char *rel = CPLGetXMLValue(n, "relativeToVRT", "0");
            const char *v = CPLGetXMLValue(n, NULL, "");
            if (strcmp(rel, "1") || !v[0] || v[0] == '/' || strstr(v, "..") || strchr(v, ':')) {
                cli_error("%s: the VRT reads '%.200s', not a file beside it; roadsplat follows such a VRT only with "
                          "--gdal-trust (docs/ROBUSTNESS.md)", path, v);
                return 1;
            }
            char *src = CPLStrdup(CPLFormFilename(CPLGetPath(path), v, NULL));
            int bad = vrt_sources_local(src, depth + 1);
            CPLFree(src);
            if (bad) return 1;
        }
        if (n->psChild && vrt_nodes_local(path, n->psChild, depth, level + 1)) return 1;
    }
    return 0;
}

/* A VRT is opened untrusted only when every source it names is a file
 * in its own folder or below (relativeToVRT, no "..", no /vsi or URL),
 * itself checked when it is a VRT, and no band is of a kind that reads
 * raw bytes or runs code. 0, or 1 after a message. */
static int vrt_sources_local(const char *path, int depth)
{
    if (cli_gdal_trusted()) return 0;
    GDALDriverH d = GDALIdentifyDriverEx(path, GDAL_OF_RASTER, NULL, NULL);
    if (!d || strcmp(GDALGetDriverShortName(d), "VRT")) return 0;
    if (depth > 4) {
        cli_error("%s: VRTs nested more than 4 deep", path);
        return 1;
    }
    CPLXMLNode *root = CPLParseXMLFile(path);
    if (!root) {
        cli_error("%s: not a VRT roadsplat can read (%s)", path, last_error("XML error"));
        return 1;
    }
    int bad = vrt_nodes_local(path, root, depth, 0);
    CPLDestroyXMLNode(root);
    return bad;
}

/* "EPSG:X" when the CRS has (or is identified with) an EPSG code, else
 * its WKT; malloc'd. */
static char *crs_text(OGRSpatialReferenceH srs)
{
    OGRSpatialReferenceH c = OSRClone(srs);
    const char *auth, *code;
    char *out = NULL;
    if (c && (OSRGetAuthorityName(c, NULL) || OSRAutoIdentifyEPSG(c) == OGRERR_NONE) &&
        (auth = OSRGetAuthorityName(c, NULL)) && !strcmp(auth, "EPSG") && (code = OSRGetAuthorityCode(c, NULL))) {
        out = malloc(strlen(code) + 6);
        if (out) sprintf(out, "EPSG:%s", code);
    }
    if (!out) {
        char *wkt = NULL;
        if (OSRExportToWkt(srs, &wkt) == OGRERR_NONE && wkt) {
            out = malloc(strlen(wkt) + 1);
            if (out) strcpy(out, wkt);
        }
        CPLFree(wkt);
    }
    if (c) OSRDestroySpatialReference(c);
    return out;
}

static OGRSpatialReferenceH srs_from(const char *text)
{
    OGRSpatialReferenceH s = OSRNewSpatialReference(NULL);
    if (!s) return NULL;
    if (OSRSetFromUserInput(s, text) != OGRERR_NONE) {
        OSRDestroySpatialReference(s);
        return NULL;
    }
    OSRSetAxisMappingStrategy(s, OAMS_TRADITIONAL_GIS_ORDER); /* x = easting / longitude */
    return s;
}

static int utm_epsg(double lon, double lat)
{
    int zone = (int)floor((lon + 180.0) / 6.0) + 1;
    if (zone < 1) zone = 1;
    if (zone > 60) zone = 60;
    return (lat >= 0 ? 32600 : 32700) + zone;
}

/* ---- reading an input once (docs/ROBUSTNESS.md, "trust model") ------------- */

/* GDAL reads the bytes the run registered, not the name again: the input
 * (opened once by the caller, cli_input) and the sidecar files GDAL would
 * look for beside it are copied from descriptors into a private /vsimem/
 * folder, up to this many bytes together (a pipe: at most this many).
 * Beyond it, and for a VRT (which reads its sources by name), a netCDF
 * file (its library opens the name itself) or a folder, GDAL opens the
 * name and the file found there afterwards must still be the inode that
 * was registered. */
#define GDAL_COPY_LIMIT ((size_t)1 << 30)
#define GDAL_MAX_SIDECARS 32

typedef struct sidecar {
    char *path;
    int fd;
    char *bytes;
    size_t size;
} sidecar;

typedef struct gdal_source {
    cli_input *in;      /* fd -1: a name GDAL reads itself (--gdal-trust: a URL, a /vsi path) */
    char name[4200];    /* what GDAL opens */
    char dir[64];       /* the private /vsimem/ folder; "" when GDAL opens the name */
    char *bytes;        /* the input's bytes in that folder */
    size_t size;
    sidecar side[GDAL_MAX_SIDECARS];
    size_t nside;
} gdal_source;

/* A file GDAL reads beside `base` (the input's file name): BASE.x for x of
 * its own sidecars (.aux.xml, overviews, masks), STEM.x for world files,
 * .prj, raw headers and the parts of a shapefile, MapInfo table, CSV or
 * GML (STEM: base without its extension). Case-insensitive, as GDAL. */
static int is_sidecar(const char *entry, const char *base)
{
    static const char *const of_base[] = { "aux.xml", "ovr", "msk", "aux", NULL };
    static const char *const of_stem[] = { "tfw", "tifw", "tiffw", "wld", "jgw", "jpgw", "pgw", "pngw", "gfw",
                                           "gifw", "bpw", "bmpw", "j2w", "prj", "hdr", "stx", "clr", "rrd", "ige",
                                           "aux", "aux.xml", "shx", "dbf", "cpg", "qix", "sbn", "sbx", "csvt",
                                           "xsd", "gfs", "dat", "map", "id", "ind", NULL };
    size_t nb = strlen(base);
    const char *dot = strrchr(base, '.');
    size_t ns = dot && dot != base ? (size_t)(dot - base) : nb;
    if (!strcmp(entry, base)) return 0;
    if (!strncasecmp(entry, base, nb) && entry[nb] == '.')
        for (size_t i = 0; of_base[i]; i++)
            if (!strcasecmp(entry + nb + 1, of_base[i])) return 1;
    if (!strncasecmp(entry, base, ns) && entry[ns] == '.')
        for (size_t i = 0; of_stem[i]; i++)
            if (!strcasecmp(entry + ns + 1, of_stem[i])) return 1;
    return 0;
}

static int read_fd_all(int fd, char *buf, size_t size)
{
    size_t n = 0;
    while (n < size) {
        ssize_t k = pread(fd, buf + n, size - n, (off_t)n);
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) return 1;
        n += (size_t)k;
    }
    return 0;
}

static void sidecars_free(gdal_source *s)
{
    for (size_t i = 0; i < s->nside; i++) {
        free(s->side[i].path);
        free(s->side[i].bytes);
        if (s->side[i].fd >= 0) close(s->side[i].fd);
    }
    s->nside = 0;
}

/* The sidecars of the regular file s->in, opened (regular files only) and
 * their sizes added to *total. 0, or 1 after a message. */
static int sidecars_open(gdal_source *s, uint64_t *total)
{
    const char *path = s->in->path, *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    char dir[4096];
    size_t nd = slash ? (size_t)(slash - path) : 0;
    if (nd + 2 > sizeof dir) return 0;
    if (slash) {
        memcpy(dir, path, nd ? nd : 1); /* "/x": the root */
        dir[nd ? nd : 1] = '\0';
    } else {
        strcpy(dir, ".");
    }
    DIR *d = opendir(dir);
    if (!d) return 0; /* not listable: GDAL would not find sidecars either */
    struct dirent *e;
    int bad = 0;
    while (!bad && (e = readdir(d)) != NULL) {
        if (!is_sidecar(e->d_name, base)) continue;
        if (s->nside == GDAL_MAX_SIDECARS) break;
        size_t n = strlen(dir) + strlen(e->d_name) + 2;
        char *p = malloc(n);
        if (!p) { bad = 1; cli_error("out of memory"); break; }
        if (slash) snprintf(p, n, "%s/%s", dir, e->d_name);
        else snprintf(p, n, "%s", e->d_name); /* named as the input is, for messages */
        /* not blocking on a FIFO; only regular files are read */
        int fd = open(p, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
        struct stat st;
        if (fd < 0 || fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
            if (fd >= 0) close(fd);
            free(p);
            continue;
        }
        sidecar *c = &s->side[s->nside++];
        c->path = p;
        c->fd = fd;
        c->bytes = NULL;
        c->size = (size_t)st.st_size;
        *total += (uint64_t)st.st_size;
    }
    closedir(d);
    return bad;
}

/* Makes s->name, the name GDAL opens for the input: 0, or 1 after a
 * message. */
static int source_open(gdal_source *s, cli_input *in)
{
    static unsigned serial; /* folders of one process */
    memset(s, 0, sizeof *s);
    s->in = in;
    snprintf(s->name, sizeof s->name, "%s", in->path);
    if (in->fd < 0 || S_ISDIR(in->st.st_mode)) return 0; /* GDAL opens the name */
    int pipe = !S_ISREG(in->st.st_mode);
    if (!pipe) {
        char head[sizeof in->head + 1];
        memcpy(head, in->head, in->got);
        head[in->got] = '\0';
        static const unsigned char hdf5[8] = { 0x89, 'H', 'D', 'F', '\r', '\n', 0x1A, '\n' };
        if (strstr(head, "<VRTDataset") || (in->got >= 4 && !memcmp(head, "CDF", 3)) ||
            (in->got >= 8 && !memcmp(head, hdf5, 8)))
            return 0;
        uint64_t total = (uint64_t)in->st.st_size;
        if (sidecars_open(s, &total)) return 1;
        if (total > GDAL_COPY_LIMIT) { /* too large to copy: GDAL opens the name, checked after */
            sidecars_free(s);
            return 0;
        }
    }
    if (cli_input_read_all(in, GDAL_COPY_LIMIT, &s->bytes, &s->size)) {
        sidecars_free(s);
        return 1;
    }
    for (size_t i = 0; i < s->nside; i++) {
        sidecar *c = &s->side[i];
        if (!(c->bytes = malloc(c->size ? c->size : 1)) || read_fd_all(c->fd, c->bytes, c->size)) {
            cli_error("%s: cannot read: %s", c->path, c->bytes ? strerror(errno ? errno : EIO) : "out of memory");
            return 1; /* source_close frees */
        }
    }
    const char *slash = strrchr(in->path, '/'), *base = slash ? slash + 1 : in->path;
    snprintf(s->dir, sizeof s->dir, "/vsimem/roadsplat-%ld-%u", (long)getpid(), ++serial);
    snprintf(s->name, sizeof s->name, "%s/%s", s->dir, base[0] ? base : "input");
    VSILFILE *f = VSIFileFromMemBuffer(s->name, (GByte *)s->bytes, s->size, FALSE);
    int bad = !f;
    if (f) VSIFCloseL(f);
    for (size_t i = 0; !bad && i < s->nside; i++) {
        char n[4200];
        const char *cs = strrchr(s->side[i].path, '/');
        snprintf(n, sizeof n, "%s/%s", s->dir, cs ? cs + 1 : s->side[i].path);
        f = VSIFileFromMemBuffer(n, (GByte *)s->side[i].bytes, s->side[i].size, FALSE);
        bad = !f;
        if (f) VSIFCloseL(f);
    }
    if (bad) cli_error("%s: out of memory for GDAL's copy", in->path);
    return bad;
}

/* Frees the copies; a pipe's bytes go back to the input when `hand_back`
 * (for the next reader: OpenImageIO). */
static void source_close(gdal_source *s, int hand_back)
{
    if (s->dir[0]) VSIRmdirRecursive(s->dir);
    if (hand_back && s->bytes && !S_ISREG(s->in->st.st_mode)) cli_input_keep(s->in, s->bytes, s->size);
    else free(s->bytes);
    s->bytes = NULL;
    sidecars_free(s);
}

/* GDAL opened the name: the file there must still be the one registered
 * (a file replaced between the two opens would be loaded from one inode
 * and registered and hashed from another). 0, or 1 after a message. */
static int source_verify(const gdal_source *s)
{
    struct stat st;
    if (s->dir[0] || s->in->fd < 0) return 0;
    if (stat(s->in->path, &st) != 0 || st.st_dev != s->in->st.st_dev || st.st_ino != s->in->st.st_ino) {
        cli_error("%s: the file was replaced while it was read; run again", s->in->path);
        return 1;
    }
    return 0;
}

/* The input and its sidecars into the run's registry under role (NULL:
 * not registered). 0, or 1 after a message. */
static int source_register(const gdal_source *s, const char *role)
{
    if (!role || s->in->fd < 0) return 0;
    int pipe = !S_ISREG(s->in->st.st_mode) && !S_ISDIR(s->in->st.st_mode);
    if (cli_inputs_add(s->in->path, role, s->in->fd, pipe ? s->bytes : NULL, s->size)) return 1;
    char r[96];
    snprintf(r, sizeof r, "%s sidecar", role);
    for (size_t i = 0; i < s->nside; i++)
        if (cli_inputs_add(s->side[i].path, r, s->side[i].fd, NULL, 0)) return 1;
    return 0;
}

/* GDAL's last error as one line with the private name replaced by the
 * input's. */
static const char *source_error(const gdal_source *s, const char *fallback)
{
    static char buf[600];
    const char *m = last_error(fallback);
    size_t nn = strlen(s->name), o = 0;
    if (!s->dir[0]) return m;
    while (*m && o + 1 < sizeof buf) {
        if (!strncmp(m, s->name, nn)) {
            int k = snprintf(buf + o, sizeof buf - o, "%s", s->in->path);
            o = k < 0 || (size_t)k >= sizeof buf - o ? sizeof buf - 1 : o + (size_t)k;
            m += nn;
        } else {
            buf[o++] = *m++;
        }
    }
    buf[o] = '\0';
    return buf;
}

/* ---- DEMs ------------------------------------------------------------------ */

static int read_dem(const gdal_source *s, uint32_t max_side, uint32_t *w, uint32_t *h, float **z, size_t *nodata,
                    cli_geo *geo)
{
    const char *path = s->in->path, *name = s->name;
    int allowed = driver_allowed(name, path, GDAL_OF_RASTER, dem_drivers, "DEMs");
    if (allowed) return allowed;
    if (!s->dir[0] && vrt_sources_local(name, 0)) return 1; /* a VRT is never copied */
    const int trusted = cli_gdal_trusted();
    GDALDatasetH ds = GDALOpenEx(name, GDAL_OF_RASTER | GDAL_OF_READONLY, trusted ? NULL : dem_drivers, NULL, NULL);
    if (!ds) {
        /* a format GDAL knows but could not open: GDAL's reason, not OpenImageIO's */
        GDALDriverH d = GDALIdentifyDriverEx(name, GDAL_OF_RASTER, NULL, NULL);
        const char *dn = d ? GDALGetDriverShortName(d) : NULL;
        if (!dn || image_format(dn)) return 2;
        cli_error("%s: GDAL (%s driver): %s", path, dn, source_error(s, "cannot open it"));
        return 1;
    }
    const char *drv = GDALGetDriverShortName(GDALGetDatasetDriver(ds));
    double gt[6];
    int has_gt = GDALGetGeoTransform(ds, gt) == CE_None;
    OGRSpatialReferenceH srs = GDALGetSpatialRef(ds);
    int plain = !strcmp(drv, "PNG") || !strcmp(drv, "GTiff") || !strcmp(drv, "JPEG") || !strcmp(drv, "BMP");
    if (!has_gt && !srs && plain) { /* an image without georeference: read as before */
        GDALClose(ds);
        return 2;
    }
    int rc = 1;
    int nb = GDALGetRasterCount(ds);
    int W = GDALGetRasterXSize(ds), H = GDALGetRasterYSize(ds);
    if (nb != 1) {
        cli_error("%s: the raster has %d bands; a DEM has one (pick it: gdal_translate -b 1 %s dem.tif)", path, nb,
                  path);
        goto out;
    }
    if (W < 2 || H < 2 || (max_side && ((uint32_t)W > max_side || (uint32_t)H > max_side))) {
        cli_error("%s: DEM is %dx%d; width and height must be 2..%u", path, W, H, max_side);
        goto out;
    }
    if (!has_gt) { gt[0] = 0; gt[1] = 1; gt[2] = 0; gt[3] = 0; gt[4] = 0; gt[5] = -1; }
    if (cli_geo_check_gt(path, gt)) goto out;
    if (gt[2] != 0 || gt[4] != 0) {
        cli_error("%s: the geotransform is rotated (terms %g and %g); roadsplat needs a north-up grid: "
                  "gdalwarp %s north_up.tif", path, gt[2], gt[4], path);
        goto out;
    }
    if (!(gt[1] > 0) || !(gt[5] < 0)) {
        cli_error("%s: the grid is not north-up (pixel size %g x %g); roadsplat needs x growing east and rows "
                  "going south: gdalwarp %s north_up.tif", path, gt[1], gt[5], path);
        goto out;
    }
    if (fabs(gt[1] + gt[5]) > 1e-9 * gt[1]) {
        cli_error("%s: pixels are not square (%.12g x %.12g); resample them: gdalwarp -tr %.12g %.12g %s square.tif",
                  path, gt[1], -gt[5], gt[1], gt[1], path);
        goto out;
    }
    if (srs && OSRIsGeographic(srs)) {
        double lon = gt[0] + gt[1] * W / 2.0, lat = gt[3] + gt[5] * H / 2.0;
        char *c = crs_text(srs);
        int e = utm_epsg(lon, lat);
        cli_error("%s: the DEM is in geographic degrees (%.60s); roadsplat needs metres: "
                  "gdalwarp -t_srs EPSG:%d -r bilinear %s dem_utm.tif", path, c && strlen(c) < 40 ? c : "lat/lon", e,
                  path);
        free(c);
        goto out;
    }
    if (srs) {
        double f = OSRGetLinearUnits(srs, NULL);
        if (fabs(f - 1.0) > 1e-9) {
            cli_error("%s: the CRS's unit is %g m, not a metre; warp it to a metre CRS (gdalwarp -t_srs EPSG:...)",
                      path, f);
            goto out;
        }
    }
    GDALRasterBandH b = GDALGetRasterBand(ds, 1);
    size_t n = (size_t)W * (size_t)H;
    float *buf = malloc(n * sizeof *buf);
    if (!buf) {
        cli_error("%s: out of memory for a %dx%d DEM", path, W, H);
        goto out;
    }
    /* row by row as doubles: a sample beyond the float range is an error
     * naming it, not a silent nodata (an inf after the conversion) */
    double *row = malloc((size_t)W * sizeof *row);
    if (!row) {
        cli_error("%s: out of memory for a %dx%d DEM", path, W, H);
        free(buf);
        goto out;
    }
    int has_nd0 = 0;
    double nd0 = GDALGetRasterNoDataValue(b, &has_nd0);
    for (int y = 0; y < H; y++) {
        if (GDALRasterIO(b, GF_Read, 0, y, W, 1, row, W, 1, GDT_Float64, 0, 0) != CE_None) {
            cli_error("%s: %s", path, source_error(s, "cannot read the raster"));
            free(row);
            free(buf);
            goto out;
        }
        for (int x = 0; x < W; x++) {
            double v = row[x];
            if (isfinite(v) && fabs(v) > FLT_MAX && !(has_nd0 && v == nd0)) {
                cli_error("%s: the sample at column %d, row %d is %.12g, beyond the float range of heights (%g); "
                          "scale the DEM (gdal_translate -scale) or mark it nodata", path, x, y, v, (double)FLT_MAX);
                free(row);
                free(buf);
                goto out;
            }
            buf[(size_t)y * W + x] = has_nd0 && v == nd0 ? NAN : (float)v;
        }
    }
    free(row);
    int has_nd = 0;
    double nd = GDALGetRasterNoDataValue(b, &has_nd);
    float ndf = (float)nd;
    for (size_t i = 0; i < n; i++) {
        if ((has_nd && buf[i] == ndf) || buf[i] != buf[i] || isinf(buf[i])) {
            buf[i] = NAN;
            (*nodata)++;
        }
    }
    *w = (uint32_t)W;
    *h = (uint32_t)H;
    *z = buf;
    geo->georef = 1;
    memcpy(geo->gt, gt, sizeof gt);
    geo->crs = srs ? crs_text(srs) : NULL;
    rc = 0;
out:
    GDALClose(ds);
    return rc;
}

/* The start of a read of an input: 0 with s open, or 1 after a message. */
static int source_begin(gdal_source *s, cli_input *in)
{
    init();
    CPLErrorReset();
    if (cli_gdal_path_check(in->path)) return 1;
    if (source_open(s, in)) {
        source_close(s, 0);
        return 1;
    }
    return 0;
}

/* The end of a read that returned rc: checked and registered when rc is 0
 * (-1 when that fails, after a message), then closed (a pipe's bytes
 * handed back on 2: not GDAL's). */
static int source_end(gdal_source *s, const char *role, int rc)
{
    if (rc == 0 && (source_verify(s) || source_register(s, role))) rc = -1;
    source_close(s, rc == 2);
    return rc;
}

int cli_gdal_read_dem_input(cli_input *in, const char *role, uint32_t max_side, uint32_t *w, uint32_t *h, float **z,
                            size_t *nodata, cli_geo *geo)
{
    memset(geo, 0, sizeof *geo);
    *z = NULL;
    *nodata = 0;
    gdal_source s;
    if (source_begin(&s, in)) return 1;
    int rc = source_end(&s, role, read_dem(&s, max_side, w, h, z, nodata, geo));
    if (rc < 0) {
        free(*z);
        *z = NULL;
        cli_geo_free(geo);
        rc = 1;
    }
    return rc;
}

/* ---- roads ----------------------------------------------------------------- */

typedef struct sbuf {
    char *s;
    size_t n, cap;
    int oom;
} sbuf;

static void put(sbuf *b, const char *fmt, ...)
{
    va_list ap;
    if (b->oom) return;
    for (;;) {
        va_start(ap, fmt);
        int k = vsnprintf(b->s ? b->s + b->n : NULL, b->s ? b->cap - b->n : 0, fmt, ap);
        va_end(ap);
        if (k < 0) { b->oom = 1; return; }
        if (b->s && (size_t)k < b->cap - b->n) { b->n += (size_t)k; return; }
        size_t nc = b->cap ? b->cap * 2 : 4096;
        while (nc < b->n + (size_t)k + 1) nc *= 2;
        char *p = realloc(b->s, nc);
        if (!p) { b->oom = 1; return; }
        b->s = p;
        b->cap = nc;
    }
}

/* A quoted string of the road format: \" and \\ escaped, control
 * characters and bytes of broken UTF-8 as '?'. */
static void put_quoted(sbuf *b, const char *s)
{
    put(b, "\"");
    const unsigned char *p = (const unsigned char *)s;
    while (*p) {
        unsigned char c = *p;
        size_t k = 1;
        if (c >= 0x80) { /* one whole UTF-8 sequence, or '?' */
            size_t need = c >= 0xF0 && c < 0xF5 ? 4 : c >= 0xE0 ? 3 : c >= 0xC2 && c < 0xE0 ? 2 : 0;
            size_t j = 1;
            while (need && j < need && (p[j] & 0xC0) == 0x80) j++;
            if (need && j == need) {
                put(b, "%.*s", (int)need, (const char *)p);
                p += need;
                continue;
            }
            put(b, "?");
        } else if (c == '"' || c == '\\') put(b, "\\%c", c);
        else if (c < 0x20 || c == 0x7F) put(b, " ");
        else put(b, "%c", c);
        p += k;
    }
    put(b, "\"");
}

/* OpenStreetMap highway= (or Geofabrik fclass=) to a road class of the
 * format; NULL: not a road for cars, bikes or feet (skipped). Documented
 * in docs/gis.md. */
static const char *class_for(const char *hw)
{
    static const char *const same[] = { "motorway", "trunk", "primary", "secondary", "tertiary", "motorway_link",
                                        "trunk_link", "primary_link", "secondary_link", "tertiary_link",
                                        "residential", "service", "track", "path", "footway", "cycleway" };
    static const char *const map[][2] = { { "unclassified", "tertiary" }, { "living_street", "residential" },
                                          { "road", "residential" }, { "pedestrian", "footway" },
                                          { "steps", "footway" }, { "corridor", "footway" },
                                          { "bridleway", "path" }, { "busway", "service" },
                                          { "bus_guideway", "service" } };
    for (size_t i = 0; i < sizeof same / sizeof same[0]; i++)
        if (!strcmp(hw, same[i])) return same[i];
    for (size_t i = 0; i < sizeof map / sizeof map[0]; i++)
        if (!strcmp(hw, map[i][0])) return map[i][1];
    if (!strncmp(hw, "track_grade", 11)) return "track";
    return NULL;
}

/* A field's value by name (NULL: no such field or unset). */
static const char *field(OGRFeatureH f, const char *name)
{
    int i = OGR_F_GetFieldIndex(f, name);
    if (i < 0 || !OGR_F_IsFieldSetAndNotNull(f, i)) return NULL;
    const char *v = OGR_F_GetFieldAsString(f, i);
    return v && v[0] ? v : NULL;
}

/* A key of an hstore string, GDAL's `other_tags` ("k"=>"v", "k2"=>"v2";
 * the OSM driver's, kept by ogr2ogr in GeoJSON, GeoPackage, ...), copied
 * unescaped into out; NULL when absent or NULL. Keys and values are quoted
 * with \" and \\ escaped; blanks around => and the commas are allowed. */
static const char *hstore(const char *tags, const char *key, char *out, size_t cap)
{
    if (!tags || !cap) return NULL;
    const char *p = tags;
    char kbuf[128];
    for (;;) {
        while (*p == ' ' || *p == ',') p++;
        if (*p != '"') return NULL;
        /* the key, unescaped (cut at the buffer: a long key never matches) */
        size_t kn = 0;
        int klong = 0;
        for (p++; *p && *p != '"'; p++) {
            if (*p == '\\' && p[1]) p++;
            if (kn + 1 < sizeof kbuf) kbuf[kn++] = *p;
            else klong = 1;
        }
        if (!*p) return NULL;
        kbuf[kn] = '\0';
        p++;
        while (*p == ' ') p++;
        if (p[0] != '=' || p[1] != '>') return NULL;
        p += 2;
        while (*p == ' ') p++;
        int match = !klong && !strcmp(kbuf, key);
        if (!strncmp(p, "NULL", 4)) {
            p += 4;
            if (match) return NULL;
            continue;
        }
        if (*p != '"') return NULL;
        size_t o = 0;
        for (p++; *p && *p != '"'; p++) {
            if (*p == '\\' && p[1]) p++;
            if (match && o + 1 < cap) out[o++] = *p;
        }
        if (match) {
            out[o] = '\0';
            return out;
        }
        if (!*p) return NULL;
        p++;
    }
}

/* A tag from a field of that name, else from other_tags. */
static const char *tag(OGRFeatureH f, const char *tags, const char *key, char *out, size_t cap)
{
    const char *v = field(f, key);
    if (v) return v;
    return hstore(tags, key, out, cap);
}

static int lanes_ok(const char *v)
{
    size_t n = strlen(v);
    if (n < 1 || n > 2) return 0;
    for (size_t i = 0; i < n; i++)
        if (!isdigit((unsigned char)v[i])) return 0;
    int k = atoi(v);
    return k >= 1 && k <= 16;
}

/* OSM layer= values: whole numbers -5..5 (the wiki's range), else dropped. */
static int layer_ok(const char *v)
{
    char *end;
    errno = 0;
    long n = strtol(v, &end, 10);
    return end != v && *end == '\0' && errno == 0 && n >= -5 && n <= 5 && (v[0] == '-' || (v[0] >= '0' && v[0] <= '9'));
}

/* OSM width values: "7", "7.5", "7,5", with a unit "7.5 m", "7.5m",
 * "7 metres", "12 ft", "3.5 feet", "12'" and feet and inches "12'6\"":
 * metres, or 0 when unreadable or outside 0.1..200 m. */
static double width_m(const char *v)
{
    char buf[40];
    size_t n = strlen(v);
    if (n >= sizeof buf) return 0;
    for (size_t i = 0; i <= n; i++) buf[i] = v[i] == ',' ? '.' : v[i];
    char *e;
    const char *s = buf;
    while (*s == ' ') s++;
    if ((!isdigit((unsigned char)*s) && *s != '.') || strpbrk(s, "xXeE")) return 0; /* no sign, inf, hex */
    for (size_t k = strlen(buf); k > 0 && buf[k - 1] == ' '; k--) buf[k - 1] = '\0';
    double d = strtod(s, &e);
    if (e == s) return 0;
    while (*e == ' ') e++;
    static const char *const metre[] = { "", "m", "meter", "meters", "metre", "metres" };
    static const char *const foot[] = { "ft", "feet", "foot", "'" };
    double f = 0;
    for (size_t i = 0; i < sizeof metre / sizeof metre[0] && !f; i++)
        if (!strcmp(e, metre[i])) f = 1;
    for (size_t i = 0; i < sizeof foot / sizeof foot[0] && !f; i++)
        if (!strcmp(e, foot[i])) f = 0.3048;
    if (!f && *e == '\'') { /* feet and inches: 12'6" */
        const char *q = e + 1;
        while (*q == ' ') q++;
        if (isdigit((unsigned char)*q)) {
            char *r;
            double in = strtod(q, &r);
            if (r[0] == '"' && r[1] == '\0' && in < 12) {
                d += in / 12;
                f = 0.3048;
            }
        }
    }
    d *= f;
    if (!(d >= 0.1 && d <= 200)) return 0;
    return d;
}

static const char *oneway_of(const char *v)
{
    if (!strcmp(v, "yes") || !strcmp(v, "true") || !strcmp(v, "1") || !strcmp(v, "F")) return "yes";
    if (!strcmp(v, "no") || !strcmp(v, "false") || !strcmp(v, "0") || !strcmp(v, "B")) return "no";
    if (!strcmp(v, "-1") || !strcmp(v, "reverse") || !strcmp(v, "T")) return "-1";
    return NULL;
}

#define DEFAULT_WIDTH 5.5 /* m: a road with no class, lanes or width (docs/gis.md) */

/* Zebra crossings: OSM highway=crossing nodes with crossing=zebra,
 * crossing:markings=zebra or crossing_ref=zebra, in the target CRS, sorted
 * by x; a road point within CROSSING_TOL of one gets `crossing=zebra`. */
#define CROSSING_TOL 0.05 /* m: OSM's 1e-7 degree node grid is about 1 cm */
typedef struct crossing {
    double x, y;
    int used;
} crossing;

typedef struct road_ctx {
    sbuf *b;
    OGRCoordinateTransformationH ct;
    size_t roads, points, zebras;
    size_t signal_nodes, unmarked_nodes; /* crossing nodes not drawn (docs/gis.md) */
    int failed_transform;
    crossing *cx;
    size_t ncx, capcx;
} road_ctx;

static int cmp_crossing(const void *a, const void *b)
{
    double u = ((const crossing *)a)->x, v = ((const crossing *)b)->x;
    return u < v ? -1 : u > v;
}

/* The crossing at (x, y), or NULL. */
static crossing *crossing_at(road_ctx *R, double x, double y)
{
    size_t lo = 0, hi = R->ncx;
    while (lo < hi) { /* the first with cx.x >= x - tol */
        size_t m = lo + (hi - lo) / 2;
        if (R->cx[m].x < x - CROSSING_TOL) lo = m + 1;
        else hi = m;
    }
    for (size_t i = lo; i < R->ncx && R->cx[i].x <= x + CROSSING_TOL; i++)
        if (fabs(R->cx[i].y - y) <= CROSSING_TOL) return &R->cx[i];
    return NULL;
}

/* One LineString as a road block under the header already written;
 * zebras: mark its points that are crossing nodes. */
static int put_line(road_ctx *R, OGRGeometryH g, const char *header, int zebras)
{
    int n = OGR_G_GetPointCount(g);
    if (n < 2) return 0;
    double *x = malloc((size_t)n * sizeof *x), *y = malloc((size_t)n * sizeof *y);
    if (!x || !y) { free(x); free(y); R->b->oom = 1; return 0; }
    for (int i = 0; i < n; i++) {
        x[i] = OGR_G_GetX(g, i);
        y[i] = OGR_G_GetY(g, i);
    }
    if (R->ct && !OCTTransform(R->ct, n, x, y, NULL)) {
        R->failed_transform++;
        free(x); free(y);
        return 0;
    }
    put(R->b, "%s\n", header);
    for (int i = 0; i < n; i++) {
        crossing *c = zebras && R->ncx ? crossing_at(R, x[i], y[i]) : NULL;
        put(R->b, "%.15g %.15g%s\n", x[i], y[i], c ? " crossing=zebra" : "");
        if (c) {
            c->used = 1;
            R->zebras++;
        }
    }
    put(R->b, "end\n");
    R->roads++;
    R->points += (size_t)n;
    free(x); free(y);
    return 1;
}

static int is_line(OGRwkbGeometryType t)
{
    t = wkbFlatten(t);
    return t == wkbLineString || t == wkbMultiLineString;
}

static const char *geom_word(OGRwkbGeometryType t)
{
    switch (wkbFlatten(t)) {
    case wkbPoint: return "points";
    case wkbMultiPoint: return "multipoints";
    case wkbPolygon: return "polygons";
    case wkbMultiPolygon: return "multipolygons";
    case wkbGeometryCollection: return "geometry collections";
    default: return "non-line geometries";
    }
}

/* What a crossing node's tags say about its road markings (docs/gis.md):
 * crossing:markings first (no; zebra, yes, ladder...), then
 * crossing_ref=zebra, then crossing= (zebra, marked, uncontrolled: a
 * marked crossing, drawn as the zebra; traffic_signals; unmarked, no,
 * informal). */
enum { CX_NONE, CX_ZEBRA, CX_SIGNALS, CX_UNMARKED };
static int crossing_kind(OGRFeatureH f, const char *tags)
{
    char t1[64], t2[64];
    const char *hw = tag(f, tags, "highway", t1, sizeof t1);
    if (!hw || (strcmp(hw, "crossing") && strcmp(hw, "traffic_signals"))) return CX_NONE;
    const char *m = tag(f, tags, "crossing:markings", t2, sizeof t2);
    if (m) {
        if (!strcmp(m, "no")) return CX_UNMARKED;
        if (!strcmp(m, "zebra") || !strcmp(m, "yes") || !strncmp(m, "ladder", 6)) return CX_ZEBRA;
    }
    const char *r = tag(f, tags, "crossing_ref", t2, sizeof t2);
    if (r && !strcmp(r, "zebra")) return CX_ZEBRA;
    const char *c = tag(f, tags, "crossing", t2, sizeof t2);
    if (!c) return CX_NONE;
    if (!strcmp(c, "zebra") || !strcmp(c, "marked") || !strcmp(c, "uncontrolled")) return CX_ZEBRA;
    if (!strcmp(c, "traffic_signals")) return CX_SIGNALS;
    if (!strcmp(c, "unmarked") || !strcmp(c, "no") || !strcmp(c, "informal")) return CX_UNMARKED;
    return CX_NONE;
}

/* The zebra crossings of a layer's Point features, reprojected with ct,
 * appended to R->cx. 0, or 1 when out of memory. */
static int collect_crossings(road_ctx *R, OGRLayerH l)
{
    OGRFeatureH f;
    OGR_L_ResetReading(l);
    while ((f = OGR_L_GetNextFeature(l)) != NULL) {
        OGRGeometryH g = OGR_F_GetGeometryRef(f);
        int kind = g && wkbFlatten(OGR_G_GetGeometryType(g)) == wkbPoint ? crossing_kind(f, field(f, "other_tags"))
                                                                          : CX_NONE;
        R->signal_nodes += kind == CX_SIGNALS;
        R->unmarked_nodes += kind == CX_UNMARKED;
        if (kind == CX_ZEBRA) {
            double x = OGR_G_GetX(g, 0), y = OGR_G_GetY(g, 0);
            if (!R->ct || OCTTransform(R->ct, 1, &x, &y, NULL)) {
                if (R->ncx == R->capcx) {
                    size_t nc = R->capcx ? 2 * R->capcx : 64;
                    crossing *p = realloc(R->cx, nc * sizeof *p);
                    if (!p) { OGR_F_Destroy(f); return 1; }
                    R->cx = p;
                    R->capcx = nc;
                }
                R->cx[R->ncx].x = x;
                R->cx[R->ncx].y = y;
                R->cx[R->ncx].used = 0;
                R->ncx++;
            }
        }
        OGR_F_Destroy(f);
    }
    return 0;
}

static int roads_text(const gdal_source *s, const cli_gdal_roads_opts *o, char **text, size_t *size)
{
    const char *path = s->in->path, *gname = s->name;
    const char *shown = o->shown ? o->shown : path;
    if (driver_allowed(gname, shown, GDAL_OF_VECTOR, road_drivers, "roads") == 1) return 1;
    const char *const *allow = cli_gdal_trusted() ? NULL : road_drivers;
    GDALDatasetH ds = GDALOpenEx(gname, GDAL_OF_VECTOR | GDAL_OF_READONLY, allow, NULL, NULL);
    if (!ds) {
        cli_error("%s: not a vector source GDAL can read (%s)", shown,
                  source_error(s, "unknown format or broken file"));
        return 1;
    }
    int rc = 1;
    sbuf b = { NULL, 0, 0, 0 };
    OGRSpatialReferenceH src = NULL, dst = NULL;
    road_ctx R;
    memset(&R, 0, sizeof R);
    R.b = &b;
    const char *drv = GDALGetDriverShortName(GDALGetDatasetDriver(ds));
    int osm = !strcmp(drv, "OSM");
    OGRLayerH layer = NULL;
    int nl = GDALDatasetGetLayerCount(ds);
    if (o->layer) {
        layer = GDALDatasetGetLayerByName(ds, o->layer);
        if (!layer) {
            char names[300] = "";
            for (int i = 0; i < nl && strlen(names) < 240; i++)
                snprintf(names + strlen(names), sizeof names - strlen(names), "%s'%s'", i ? ", " : "",
                         OGR_L_GetName(GDALDatasetGetLayer(ds, i)));
            cli_error("%s: no layer '%s' (layers: %s)", shown, o->layer, nl ? names : "none");
            goto out;
        }
    } else if (osm) {
        layer = GDALDatasetGetLayerByName(ds, "lines");
    } else {
        for (int i = 0; i < nl && !layer; i++)
            if (is_line(OGR_L_GetGeomType(GDALDatasetGetLayer(ds, i)))) layer = GDALDatasetGetLayer(ds, i);
        if (!layer && nl > 0) layer = GDALDatasetGetLayer(ds, 0);
    }
    if (!layer) {
        cli_error("%s: the source has no layers", shown);
        goto out;
    }
    const char *lname = OGR_L_GetName(layer);
    OGRwkbGeometryType lt = OGR_L_GetGeomType(layer);
    if (wkbFlatten(lt) != wkbUnknown && !is_line(lt)) {
        cli_error("%s: layer '%s' holds %s, not lines (LineString or MultiLineString)%s", shown, lname, geom_word(lt),
                  nl > 1 ? "; pick another with --layer" : "");
        goto out;
    }
    if (o->where && OGR_L_SetAttributeFilter(layer, o->where) != OGRERR_NONE) {
        cli_error("%s: --where '%s': %s", shown, o->where, last_error("invalid expression"));
        goto out;
    }
    OGRSpatialReferenceH lsrs = OGR_L_GetSpatialRef(layer);
    if (!lsrs) {
        cli_error("%s: layer '%s' has no coordinate system; give it one: ogr2ogr -a_srs EPSG:4326 roads.gpkg %s",
                  shown, lname, path);
        goto out;
    }
    src = OSRClone(lsrs);
    OSRSetAxisMappingStrategy(src, OAMS_TRADITIONAL_GIS_ORDER);
    if (o->dst_crs) {
        dst = srs_from(o->dst_crs);
        if (!dst) {
            cli_error("%s: cannot read the target CRS '%.80s'", shown, o->dst_crs);
            goto out;
        }
    } else if (OSRIsGeographic(src)) { /* the UTM zone of the extent's centre */
        OGREnvelope env;
        if (OGR_L_GetExtent(layer, &env, 1) != OGRERR_NONE) { /* OSM: none; from the features */
            int any = 0;
            OGRFeatureH f;
            OGR_L_ResetReading(layer);
            while ((f = OGR_L_GetNextFeature(layer)) != NULL) {
                OGRGeometryH g = OGR_F_GetGeometryRef(f);
                OGREnvelope e;
                if (g && !OGR_G_IsEmpty(g)) {
                    OGR_G_GetEnvelope(g, &e);
                    if (!any) env = e;
                    if (e.MinX < env.MinX) env.MinX = e.MinX;
                    if (e.MinY < env.MinY) env.MinY = e.MinY;
                    if (e.MaxX > env.MaxX) env.MaxX = e.MaxX;
                    if (e.MaxY > env.MaxY) env.MaxY = e.MaxY;
                    any = 1;
                }
                OGR_F_Destroy(f);
            }
            if (!any) {
                cli_error("%s: layer '%s' has no features%s", shown, lname, o->where ? " matching --where" : "");
                goto out;
            }
        }
        char code[32];
        snprintf(code, sizeof code, "EPSG:%d", utm_epsg((env.MinX + env.MaxX) / 2, (env.MinY + env.MaxY) / 2));
        dst = srs_from(code);
    } else {
        dst = OSRClone(src);
        OSRSetAxisMappingStrategy(dst, OAMS_TRADITIONAL_GIS_ORDER);
    }
    if (!dst) {
        cli_error("%s: out of memory", shown);
        goto out;
    }
    if (OSRIsGeographic(dst)) {
        cli_error("%s: the target CRS is in degrees; roads need a metre CRS (e.g. a UTM zone, EPSG:326xx)", shown);
        goto out;
    }
    if (!OSRIsSame(src, dst)) {
        R.ct = OCTNewCoordinateTransformation(src, dst);
        if (!R.ct) {
            cli_error("%s: cannot reproject layer '%s' to the DEM's CRS: %s", shown, lname,
                      last_error("no transformation"));
            goto out;
        }
    }
    char *dcrs = crs_text(dst);
    put(&b, "# roads from %s, layer '%s' (roadsplat convert; docs/gis.md)\nframe world ", shown, lname);
    if (dcrs && !strchr(dcrs, ' ') && !strchr(dcrs, '"') && !strchr(dcrs, '#')) put(&b, "%s\n", dcrs);
    else put_quoted(&b, dcrs ? dcrs : ""), put(&b, "\n");
    free(dcrs);

    /* zebra crossings: OSM's points layer (a second handle: the OSM driver
     * reads its layers in one stream), or the Point features of a layer of
     * mixed geometries (GeoJSON from OSM) */
    if (osm) {
        GDALDatasetH pds = GDALOpenEx(gname, GDAL_OF_VECTOR | GDAL_OF_READONLY, allow, NULL, NULL);
        OGRLayerH pl = pds ? GDALDatasetGetLayerByName(pds, "points") : NULL;
        int oom = 0;
        if (pl) {
            /* a speed-up only: crossing_kind checks */
            OGR_L_SetAttributeFilter(pl, "highway IN ('crossing', 'traffic_signals')");
            oom = collect_crossings(&R, pl);
        }
        if (pds) GDALClose(pds);
        if (oom) b.oom = 1;
    } else if (wkbFlatten(lt) == wkbUnknown && collect_crossings(&R, layer)) {
        b.oom = 1;
    }
    if (R.ncx) qsort(R.cx, R.ncx, sizeof *R.cx, cmp_crossing);

    size_t feats = 0, not_lines = 0, not_roads = 0, no_highway = 0, tunnels = 0;
    /* OSM data (the OSM driver, or a layer with highway-like fields: an
     * ogr2ogr export): only highway=* ways are roads unless --where says
     * which features are; a plain line layer's features all are */
    int osm_layer = osm;
    {
        OGRFeatureDefnH fd = OGR_L_GetLayerDefn(layer);
        const char *keys[] = { "highway", "fclass", "other_tags", "area:highway" };
        for (size_t k = 0; k < sizeof keys / sizeof keys[0]; k++)
            if (OGR_FD_GetFieldIndex(fd, keys[k]) >= 0) osm_layer = 1;
    }
    OGRFeatureH f;
    OGR_L_ResetReading(layer);
    while ((f = OGR_L_GetNextFeature(layer)) != NULL) {
        feats++;
        OGRGeometryH g = OGR_F_GetGeometryRef(f);
        if (!g || !is_line(OGR_G_GetGeometryType(g))) {
            not_lines++;
            OGR_F_Destroy(f);
            continue;
        }
        const char *tags = field(f, "other_tags");
        char t0[64], t1[64], t2[64], t3[64], t4[256];
        const char *hw = tag(f, tags, "highway", t0, sizeof t0);
        if (!hw) hw = field(f, "fclass");
        if (!hw) hw = tag(f, tags, "area:highway", t0, sizeof t0);
        const char *cls = hw ? class_for(hw) : NULL;
        if (hw && !cls) {
            not_roads++;
            OGR_F_Destroy(f);
            continue;
        }
        if (!hw && osm_layer && !o->where) { /* a fence, river, railway, ...: not a road */
            no_highway++;
            OGR_F_Destroy(f);
            continue;
        }
        /* a tunnel runs under the ground, which is what the texture shows
         * (an aerial view has no road there): skipped and counted, unless
         * --where chose the features (docs/gis.md) */
        char t5[64], t6[64], t7[64], t8[64], t9[64];
        const char *tun = tag(f, tags, "tunnel", t5, sizeof t5);
        if (tun && strcmp(tun, "no") && strcmp(tun, "building_passage") && !o->where) {
            tunnels++;
            OGR_F_Destroy(f);
            continue;
        }
        const char *name = field(f, "name");
        char fid[40];
        if (!name) {
            const char *oid = field(f, "osm_id");
            if (oid) snprintf(fid, sizeof fid, "way%.30s", oid);
            else snprintf(fid, sizeof fid, "feature%lld", (long long)OGR_F_GetFID(f));
            name = fid;
        }
        sbuf h = { NULL, 0, 0, 0 };
        put(&h, "road ");
        put_quoted(&h, name);
        const char *lanes = tag(f, tags, "lanes", t1, sizeof t1);
        const char *wv = tag(f, tags, "width", t2, sizeof t2);
        const char *ow = tag(f, tags, "oneway", t3, sizeof t3);
        const char *tl = tag(f, tags, "turn:lanes", t4, sizeof t4);
        double wd = wv ? width_m(wv) : 0;
        if (lanes && !lanes_ok(lanes)) lanes = NULL;
        if (wd > 0) put(&h, " width %.6g", wd);
        else if (!cls && !lanes) put(&h, " width %g", DEFAULT_WIDTH);
        if (cls) put(&h, " class=%s", cls);
        if (hw && strcmp(hw, cls)) put(&h, " highway="), put_quoted(&h, hw);
        if (lanes) put(&h, " lanes=%s", lanes);
        if (ow && oneway_of(ow)) put(&h, " oneway=%s", oneway_of(ow));
        if (tl) put(&h, " turn:lanes="), put_quoted(&h, tl);
        /* roundabouts and priority roads (the network's ranks), bridges and
         * layers (which surface lies on top where roads cross) */
        const char *jn = tag(f, tags, "junction", t6, sizeof t6), *pr = tag(f, tags, "priority_road", t7, sizeof t7);
        const char *br = tag(f, tags, "bridge", t8, sizeof t8), *ly = tag(f, tags, "layer", t9, sizeof t9);
        if (jn) put(&h, " junction="), put_quoted(&h, jn);
        if (pr) put(&h, " priority_road="), put_quoted(&h, pr);
        if (br && strcmp(br, "no")) put(&h, " bridge="), put_quoted(&h, br);
        if (ly && layer_ok(ly)) put(&h, " layer=%s", ly);
        if (h.oom) {
            free(h.s);
            OGR_F_Destroy(f);
            b.oom = 1;
            break;
        }
        /* zebras across roads for vehicles, not along the footway that crosses */
        int zebras = !cls || (strcmp(cls, "footway") && strcmp(cls, "path") && strcmp(cls, "cycleway"));
        if (wkbFlatten(OGR_G_GetGeometryType(g)) == wkbLineString) put_line(&R, g, h.s, zebras);
        else
            for (int k = 0; k < OGR_G_GetGeometryCount(g); k++)
                put_line(&R, OGR_G_GetGeometryRef(g, k), h.s, zebras);
        free(h.s);
        OGR_F_Destroy(f);
    }
    if (b.oom) {
        cli_error("%s: out of memory", shown);
        goto out;
    }
    if (R.roads == 0) {
        if (feats == 0)
            cli_error("%s: layer '%s' has no features%s", shown, lname, o->where ? " matching --where" : "");
        else if (R.failed_transform)
            cli_error("%s: layer '%s': no line could be reprojected to the target CRS (%s)", shown, lname,
                      last_error("outside its area"));
        else
            cli_error("%s: layer '%s' has no road lines (%zu features: %zu not LineString/MultiLineString, %zu "
                      "highway= values that are not roads, %zu without highway=*%s)", shown, lname, feats, not_lines,
                      not_roads, no_highway, no_highway ? "; --where selects other features" : "");
        goto out;
    }
    put(&b, "# %zu roads, %zu points from %zu features (skipped: %zu not lines, %zu not roads, %zu without "
            "highway, %zu tunnels, %d not reprojectable)\n", R.roads, R.points, feats, not_lines, not_roads, no_highway,
        tunnels, R.failed_transform);
    if (R.signal_nodes || R.unmarked_nodes)
        put(&b, "# crossing nodes not drawn: %zu traffic_signals, %zu unmarked\n", R.signal_nodes,
            R.unmarked_nodes);
    if (o->counts) {
        cli_gdal_road_counts *c = o->counts;
        c->features = feats;
        c->roads = R.roads;
        c->no_highway = no_highway;
        c->tunnels = tunnels;
        c->not_roads = not_roads;
        c->not_lines = not_lines;
        c->not_reprojected = (size_t)R.failed_transform;
        c->zebra_nodes = R.ncx;
        c->zebra_points = R.zebras;
        c->signal_nodes = R.signal_nodes;
        c->unmarked_nodes = R.unmarked_nodes;
        c->set = 1;
    }
    if (R.ncx) {
        size_t used = 0;
        for (size_t i = 0; i < R.ncx; i++) used += R.cx[i].used != 0;
        put(&b, "# %zu zebra crossing nodes: %zu on roads (%zu crossing=zebra points), %zu on no road for "
                "vehicles\n", R.ncx, used, R.zebras, R.ncx - used);
    }
    if (b.oom) {
        cli_error("%s: out of memory", shown);
        goto out;
    }
    *text = b.s;
    *size = b.n;
    b.s = NULL;
    rc = 0;
out:
    free(b.s);
    free(R.cx);
    if (R.ct) OCTDestroyCoordinateTransformation(R.ct);
    if (src) OSRDestroySpatialReference(src);
    if (dst) OSRDestroySpatialReference(dst);
    GDALClose(ds);
    return rc;
}

int cli_gdal_roads_text_input(cli_input *in, const char *role, const cli_gdal_roads_opts *o, char **text,
                              size_t *size)
{
    *text = NULL;
    *size = 0;
    gdal_source s;
    if (source_begin(&s, in)) return 1;
    int rc = source_end(&s, role, roads_text(&s, o, text, size));
    if (rc < 0) {
        free(*text);
        *text = NULL;
        *size = 0;
        rc = 1;
    }
    return rc;
}

/* ---- CRS helpers ------------------------------------------------------------- */

int cli_gdal_same_crs(const char *a, const char *b, const char *shown)
{
    init();
    OGRSpatialReferenceH x = srs_from(a), y = srs_from(b);
    int r = -1;
    if (!x || !y) cli_error("%s: cannot read the CRS '%.80s'", shown, x ? b : a);
    else r = OSRIsSame(x, y) ? 1 : 0;
    if (x) OSRDestroySpatialReference(x);
    if (y) OSRDestroySpatialReference(y);
    return r;
}

char *cli_gdal_prj_text(const char *crs, const char *shown)
{
    init();
    OGRSpatialReferenceH s = srs_from(crs);
    char *wkt = NULL, *out = NULL;
    const char *opts[] = { "FORMAT=WKT1_ESRI", NULL };
    if (s && OSRExportToWktEx(s, &wkt, opts) == OGRERR_NONE && wkt) {
        out = malloc(strlen(wkt) + 1);
        if (out) strcpy(out, wkt);
    }
    if (!out) cli_error("%s: cannot write the CRS '%.80s' as a .prj", shown, crs);
    CPLFree(wkt);
    if (s) OSRDestroySpatialReference(s);
    return out;
}

/* ---- GeoTIFF output ------------------------------------------------------------ */

/* Why a write failed, in the user's terms: a full file system is named
 * as such (libtiff reports it as "Seek error at scanline 512" and the
 * like), anything else as GDAL's message. */
static const char *write_error(const char *path, uint64_t raw, const char *fallback)
{
    static char buf[160];
    char *dir = CPLStrdup(CPLGetPath(path));
    struct statvfs sv;
    /* less room left than the image holds uncompressed: the likely cause */
    int full = statvfs(dir[0] ? dir : ".", &sv) == 0 && (uint64_t)sv.f_bavail * sv.f_frsize < raw;
    CPLFree(dir);
    if (full) {
        snprintf(buf, sizeof buf, "the file system is full (%llu KiB free there; the image holds %llu KiB before "
                 "compression)", (unsigned long long)((uint64_t)sv.f_bavail * sv.f_frsize >> 10),
                 (unsigned long long)(raw >> 10));
        return buf;
    }
    return last_error(fallback);
}

/* The GeoTIFF at path read back whole: synced, every band of the full
 * image equal to data, every overview readable. GDAL's writers (the COG
 * driver above all) can lose a write error on a full disk and leave a
 * truncated file behind: this is the check that catches it. 0, or 1
 * after a message naming shown. */
static int verify_tiff(const char *path, const char *shown, uint32_t w, uint32_t h, int channels, int bits,
                       const void *data)
{
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    int bad = fd < 0 || (fsync(fd) != 0 && errno != EINVAL);
    int e = errno;
    if (fd >= 0) close(fd);
    if (bad) {
        cli_error("%s: write failed: %s", shown, strerror(e ? e : EIO));
        return 1;
    }
    static const char *const gtiff[] = { "GTiff", NULL };
    CPLErrorReset();
    GDALDatasetH ds = GDALOpenEx(path, GDAL_OF_RASTER | GDAL_OF_READONLY, gtiff, NULL, NULL);
    size_t bytes = bits == 16 ? 2 : 1, row = (size_t)w * channels * bytes;
    unsigned char *buf = ds ? malloc(row) : NULL;
    bad = !ds || !buf || GDALGetRasterXSize(ds) != (int)w || GDALGetRasterYSize(ds) != (int)h ||
          GDALGetRasterCount(ds) != channels;
    int bands[4] = { 1, 2, 3, 4 };
    GDALDataType dt = bits == 16 ? GDT_UInt16 : GDT_Byte;
    for (uint32_t y = 0; !bad && y < h; y++)
        bad = GDALDatasetRasterIO(ds, GF_Read, 0, (int)y, (int)w, 1, buf, (int)w, 1, dt, channels, bands,
                                  (GSpacing)channels * bytes, (GSpacing)row, (GSpacing)bytes) != CE_None ||
              memcmp(buf, (const unsigned char *)data + (size_t)y * row, row) != 0;
    for (int b = 1; !bad && b <= channels; b++) {
        GDALRasterBandH band = GDALGetRasterBand(ds, b);
        for (int o = 0, no = GDALGetOverviewCount(band); !bad && o < no; o++) {
            GDALRasterBandH ov = GDALGetOverview(band, o);
            CPLErrorReset();
            GDALChecksumImage(ov, 0, 0, GDALGetRasterBandXSize(ov), GDALGetRasterBandYSize(ov));
            bad = CPLGetLastErrorType() >= CE_Failure;
        }
    }
    if (bad) cli_error("%s: write failed: %s", shown, write_error(path, (uint64_t)row * h, "the GeoTIFF did not reach the disk whole"));
    free(buf);
    if (ds) GDALClose(ds);
    return bad;
}

int cli_gdal_write_tiff(const char *path, const char *shown, uint32_t w, uint32_t h, int channels, int bits,
                        const void *data, const double gt[6], const char *crs, int cog)
{
    init();
    CPLErrorReset();
    GDALDataType dt = bits == 16 ? GDT_UInt16 : GDT_Byte;
    int bytes = bits == 16 ? 2 : 1;
    GDALDriverH mem = GDALGetDriverByName("MEM"), gtiff = GDALGetDriverByName(cog ? "COG" : "GTiff");
    if (!mem || !gtiff) {
        cli_error("%s: this GDAL has no %s driver", shown, cog ? "COG" : "GTiff");
        return 1;
    }
    GDALDatasetH src = GDALCreate(mem, "", (int)w, (int)h, channels, dt, NULL);
    if (!src) {
        cli_error("%s: out of memory for a %ux%u image", shown, w, h);
        return 1;
    }
    int bands[4] = { 1, 2, 3, 4 };
    int rc = 1;
    OGRSpatialReferenceH srs = NULL;
    if (GDALDatasetRasterIO(src, GF_Write, 0, 0, (int)w, (int)h, (void *)data, (int)w, (int)h, dt, channels, bands,
                            (GSpacing)channels * bytes, (GSpacing)w * channels * bytes, bytes) != CE_None) {
        cli_error("%s: %s", shown, last_error("cannot fill the image"));
        goto out;
    }
    if (channels >= 3) { /* the COG driver copies these (GTiff also takes PHOTOMETRIC=RGB below) */
        GDALSetRasterColorInterpretation(GDALGetRasterBand(src, 1), GCI_RedBand);
        GDALSetRasterColorInterpretation(GDALGetRasterBand(src, 2), GCI_GreenBand);
        GDALSetRasterColorInterpretation(GDALGetRasterBand(src, 3), GCI_BlueBand);
    }
    if (channels == 4) GDALSetRasterColorInterpretation(GDALGetRasterBand(src, 4), GCI_AlphaBand);
    if (gt) GDALSetGeoTransform(src, (double *)gt);
    if (crs) {
        srs = srs_from(crs);
        if (!srs) {
            cli_error("%s: cannot read the CRS '%.80s'", shown, crs);
            goto out;
        }
        GDALSetSpatialRef(src, srs);
    }
    const char *topts[] = { "TILED=YES", "BLOCKXSIZE=256", "BLOCKYSIZE=256", "COMPRESS=DEFLATE",
                            channels >= 3 ? "PHOTOMETRIC=RGB" : "PHOTOMETRIC=MINISBLACK",
                            channels == 4 ? "ALPHA=UNASSOCIATED" : NULL, NULL };
    const char *copts[] = { "COMPRESS=DEFLATE", "BLOCKSIZE=256", "OVERVIEWS=AUTO", NULL };
    GDALDatasetH out = GDALCreateCopy(gtiff, path, src, FALSE, (char **)(cog ? copts : topts), NULL, NULL);
    if (!out) {
        cli_error("%s: write failed: %s", shown, write_error(path, (uint64_t)w * h * channels * bytes, "GDAL could not write it"));
        goto out;
    }
    CPLErrorReset();
    GDALClose(out); /* void in GDAL 3.6: a failed flush shows as an error state */
    if (CPLGetLastErrorType() >= CE_Failure) {
        cli_error("%s: write failed: %s", shown, write_error(path, (uint64_t)w * h * channels * bytes, "GDAL could not close it"));
        goto out;
    }
    if (verify_tiff(path, shown, w, h, channels, bits, data)) goto out;
    rc = 0;
out:
    if (srs) OSRDestroySpatialReference(srs);
    GDALClose(src);
    return rc;
}
