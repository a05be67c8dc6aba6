/* CLI helpers: error lines, strict option parsing, whole-file reads,
 * atomic output files, the monotonic clock and DEM loading. */
#include "cli.h"

#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <locale.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

void cli_error(const char *fmt, ...)
{
    va_list ap;
    fputs("roadsplat: ", stderr);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
}

double cli_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1000.0 + (double)ts.tv_nsec / 1e6;
}

/* ---- numbers -------------------------------------------------------------- */

/* Parse [s, s+n) as a decimal number with the same rules as the library's
 * files: sign, digits, '.', exponent; no comma, hex, inf or nan. strtod
 * does the conversion, but only after the characters are checked, and on a
 * copy whose '.' is replaced by the current locale's decimal point, so a
 * host locale can neither break nor widen what is accepted. */
static int strict_double(const char *s, size_t n, double *out) /* 1 ok, 0 bad, -1 out of range */
{
    char buf[128];
    int digits = 0;
    if (n == 0 || n >= sizeof buf - 8) return 0;
    for (size_t i = 0; i < n; i++) {
        char c = s[i];
        if (c >= '0' && c <= '9') digits = 1;
        else if (c != '+' && c != '-' && c != '.' && c != 'e' && c != 'E') return 0;
    }
    if (!digits) return 0;
    const char *dp = localeconv()->decimal_point;
    size_t dpl = dp && dp[0] ? strlen(dp) : 1, o = 0;
    if (dpl > 4) return 0;
    for (size_t i = 0; i < n; i++) {
        if (s[i] == '.' && dp && dp[0]) { memcpy(buf + o, dp, dpl); o += dpl; }
        else buf[o++] = s[i];
    }
    buf[o] = '\0';
    char *end;
    errno = 0;
    double v = strtod(buf, &end);
    if (end != buf + o) return 0;
    if (!isfinite(v) || (errno == ERANGE && fabs(v) > 1.0)) return -1;
    *out = v;
    return 1;
}

int cli_parse_double(const char *option, const char *s, double *out)
{
    int k = s ? strict_double(s, strlen(s), out) : 0;
    if (k < 0) {
        cli_error("%s: '%s' is out of range", option, s);
        return 1;
    }
    if (k == 0) {
        cli_error("%s: '%s' is not a number%s", option, s ? s : "",
                  s && strchr(s, ',') ? " (use '.' as the decimal point)" : "");
        return 1;
    }
    return 0;
}

static int strict_u32(const char *s, size_t n, uint32_t *out)
{
    uint64_t v = 0;
    if (n == 0) return 0;
    for (size_t i = 0; i < n; i++) {
        if (s[i] < '0' || s[i] > '9') return 0;
        v = v * 10 + (uint64_t)(s[i] - '0');
        if (v > UINT32_MAX) return 0;
    }
    *out = (uint32_t)v;
    return 1;
}

int cli_parse_u32(const char *option, const char *s, uint32_t *out)
{
    if (!s || !strict_u32(s, strlen(s), out)) {
        cli_error("%s: '%s' is not a whole number in 0..4294967295", option, s ? s : "");
        return 1;
    }
    return 0;
}

int cli_parse_vec(const char *option, const char *s, double *out, int n)
{
    const char *p = s;
    int i = 0;
    if (s && n >= 1 && n <= 4) {
        for (; i < n; i++) {
            const char *c = strchr(p, ',');
            size_t len = c ? (size_t)(c - p) : strlen(p);
            if (strict_double(p, len, &out[i]) != 1) break;
            if (i == n - 1) { if (c) break; }
            else if (!c) break;
            p = c ? c + 1 : p + len;
        }
    }
    if (i != n) {
        cli_error("%s: '%s' is not %s (numbers with '.' as the decimal point, separated by ',')", option,
                  s ? s : "", n == 3 ? "X,Y,Z" : "X,Y");
        return 1;
    }
    return 0;
}

int cli_parse_size(const char *option, const char *s, uint32_t *w, uint32_t *h)
{
    const char *x = s ? strpbrk(s, "xX") : NULL;
    if (!x || !strict_u32(s, (size_t)(x - s), w) || !strict_u32(x + 1, strlen(x + 1), h) || !*w || !*h) {
        cli_error("%s: '%s' is not a size WxH (positive whole numbers)", option, s ? s : "");
        return 1;
    }
    return 0;
}

/* ---- files ---------------------------------------------------------------- */

int cli_read_file(const char *path, size_t limit, char **data, size_t *size)
{
    *data = NULL;
    *size = 0;
    FILE *f = fopen(path, "rb");
    if (!f) { cli_error("%s: %s", path, strerror(errno)); return 1; }
    struct stat st;
    memset(&st, 0, sizeof st);
    if (fstat(fileno(f), &st) == 0 && S_ISDIR(st.st_mode)) {
        fclose(f);
        cli_error("%s: is a directory", path);
        return 1;
    }
    if (limit && S_ISREG(st.st_mode) && (uint64_t)st.st_size > (uint64_t)limit) { /* before allocating */
        fclose(f);
        cli_error("%s: file is larger than the %zu-byte limit", path, limit);
        return 1;
    }
    size_t cap = 1 << 16, n = 0;
    if (S_ISREG(st.st_mode) && st.st_size > 0 && (uint64_t)st.st_size < SIZE_MAX - 1) cap = (size_t)st.st_size + 1;
    if (limit && cap > limit + 1) cap = limit + 1;
    char *buf = malloc(cap);
    if (!buf) { fclose(f); cli_error("%s: out of memory", path); return 1; }
    for (;;) {
        if (n + 1 >= cap) { /* keep room for the terminating NUL */
            if (limit && n > limit) break;
            size_t nc = cap > SIZE_MAX / 2 ? SIZE_MAX : cap * 2;
            if (limit && nc > limit + 2) nc = limit + 2;
            char *nb = nc > cap ? realloc(buf, nc) : NULL;
            if (!nb) { free(buf); fclose(f); cli_error("%s: out of memory", path); return 1; }
            buf = nb;
            cap = nc;
        }
        size_t got = fread(buf + n, 1, cap - 1 - n, f);
        n += got;
        if (got == 0) break;
    }
    int err = ferror(f);
    int saved = errno;
    fclose(f);
    if (err) { free(buf); cli_error("%s: read error: %s", path, strerror(saved)); return 1; }
    if (limit && n > limit) {
        free(buf);
        cli_error("%s: file is larger than the %zu-byte limit", path, limit);
        return 1;
    }
    buf[n] = '\0';
    *data = buf;
    *size = n;
    return 0;
}

static char *dup_str(const char *s)
{
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (d) memcpy(d, s, n);
    return d;
}

int cli_out_open(cli_out *o, const char *path)
{
    memset(o, 0, sizeof *o);
    /* rename() would replace a device, FIFO or folder entry instead of
     * writing to it (as root even /dev/full): only regular files are OUT. */
    struct stat st;
    if (stat(path, &st) == 0 && !S_ISREG(st.st_mode)) {
        cli_error("%s: %s; the output must be a regular file", path,
                  S_ISDIR(st.st_mode) ? "is a directory" : "exists and is not a regular file");
        return 1;
    }
    const char *slash = strrchr(path, '/');
    size_t dirlen = slash ? (size_t)(slash - path) + 1 : 0;
    size_t n = strlen(path) + 16;
    o->path = dup_str(path);
    o->tmp = malloc(n);
    if (!o->path || !o->tmp) {
        free(o->path); free(o->tmp); o->path = o->tmp = NULL;
        cli_error("%s: out of memory", path);
        return 1;
    }
    /* Hidden sibling "DIR/.NAME.XXXXXX": same file system, so rename is atomic. */
    snprintf(o->tmp, n, "%.*s.%s.XXXXXX", (int)dirlen, path, path + dirlen);
    int fd = mkstemp(o->tmp);
    if (fd < 0) {
        cli_error("%s: cannot create a temporary file next to it: %s", path, strerror(errno));
        free(o->path); free(o->tmp); o->path = o->tmp = NULL;
        return 1;
    }
    /* mkstemp makes 0600; give the output the usual 0666 & ~umask. */
    mode_t mask = umask(0);
    umask(mask);
    if (fchmod(fd, 0666 & ~mask) != 0) { /* not fatal */ }
    o->f = fdopen(fd, "wb");
    if (!o->f) {
        int e = errno;
        close(fd);
        unlink(o->tmp);
        cli_error("%s: %s", path, strerror(e));
        free(o->path); free(o->tmp); o->path = o->tmp = NULL;
        return 1;
    }
    return 0;
}

void cli_out_abort(cli_out *o)
{
    if (o->f) fclose(o->f);
    if (o->tmp) unlink(o->tmp);
    free(o->path);
    free(o->tmp);
    o->f = NULL;
    o->path = o->tmp = NULL;
}

int cli_out_commit(cli_out *o)
{
    if (!o->f || !o->tmp) return 1;
    int bad = 0, e = 0;
    if (fflush(o->f) != 0 || ferror(o->f)) { bad = 1; e = errno; }
    if (!bad && fsync(fileno(o->f)) != 0 && errno != EINVAL) { bad = 1; e = errno; }
    if (fclose(o->f) != 0 && !bad) { bad = 1; e = errno; }
    o->f = NULL;
    if (!bad && rename(o->tmp, o->path) != 0) { bad = 1; e = errno; }
    if (bad) {
        cli_error("%s: write failed: %s", o->path, strerror(e ? e : EIO));
        cli_out_abort(o);
        return 1;
    }
    /* Make the rename itself durable; best effort. */
    const char *slash = strrchr(o->path, '/');
    if (slash) {
        char *dir = dup_str(o->path);
        if (dir) {
            dir[slash - o->path + (slash == o->path)] = '\0';
            int fd = open(dir, O_RDONLY);
            if (fd >= 0) { (void)fsync(fd); close(fd); }
            free(dir);
        }
    } else {
        int fd = open(".", O_RDONLY);
        if (fd >= 0) { (void)fsync(fd); close(fd); }
    }
    free(o->path);
    free(o->tmp);
    o->path = o->tmp = NULL;
    return 0;
}

/* ---- DEM ------------------------------------------------------------------ */

/* An image read through OpenImageIO: a DEM (gray float) or a texture (RGBA8). */
typedef struct image_read {
    const char *path;
    uint32_t max_side, *w, *h;
    float **z;
    uint8_t **rgba;
} image_read;

static int run_read(const image_read *r)
{
    if (r->z) return cli_image_read_gray_float(r->path, r->max_side, r->w, r->h, r->z);
    return cli_image_read_rgba8(r->path, r->w, r->h, r->rgba);
}

/* OpenImageIO 2.4 leaves libpng's default error handler in place, which
 * prints "libpng error: ..." on stderr before OpenImageIO reports the same
 * problem. Run the read with stderr sent to an unlinked temporary file and
 * pass on only our own "roadsplat: " lines, so a bad image still costs
 * exactly one line. Without a temporary file the read runs unfiltered. */
static int read_image_quietly(const image_read *r)
{
    fflush(stderr);
    FILE *cap = tmpfile();
    int saved = cap ? dup(2) : -1;
    if (saved < 0 || dup2(fileno(cap), 2) < 0) {
        if (saved >= 0) close(saved);
        if (cap) fclose(cap);
        return run_read(r);
    }
    int rc = run_read(r);
    fflush(stderr);
    dup2(saved, 2);
    close(saved);
    rewind(cap);
    char buf[512];
    int at_start = 1, keep = 0, printed = 0;
    while (fgets(buf, sizeof buf, cap)) {
        if (at_start) keep = strncmp(buf, "roadsplat: ", 11) == 0;
        if (keep) { fputs(buf, stderr); printed = 1; }
        at_start = strchr(buf, '\n') != NULL;
    }
    fclose(cap);
    if (keep && !at_start) fputc('\n', stderr);
    if (rc && !printed) cli_error("%s: cannot read image", r->path);
    return rc;
}

int cli_load_texture(const char *path, uint32_t *w, uint32_t *h, uint8_t **rgba)
{
    image_read r = { path, 0, w, h, NULL, rgba };
    return read_image_quietly(&r);
}

/* The first line that is not blank or a '#' comment starts with the
 * keyword "road" (docs/road-format.md), within the first n bytes. */
static int looks_like_roads(const char *p, size_t n)
{
    size_t i = 0;
    while (i < n) {
        while (i < n && (p[i] == ' ' || p[i] == '\t' || p[i] == '\r' || p[i] == '\n')) i++;
        if (i < n && p[i] == '#') {
            while (i < n && p[i] != '\n') i++;
            continue;
        }
        return n - i >= 5 && memcmp(p + i, "road", 4) == 0 && (p[i + 4] == ' ' || p[i + 4] == '\t');
    }
    return 0;
}

rs_dem *cli_load_dem(rs_ctx *ctx, const char *path)
{
    char head[4096];
    FILE *f = fopen(path, "rb");
    if (!f) { cli_error("%s: %s", path, strerror(errno)); return NULL; }
    size_t got = fread(head, 1, sizeof head, f);
    fclose(f);
    rs_dem *dem = NULL;
    /* DEM and ROADS swapped on the command line: say so, rather than pass a
     * text file to OpenImageIO ("could not find a format reader"). */
    if (looks_like_roads(head, got)) {
        cli_error("%s: this is a road file, not a DEM (arguments in the wrong order?)", path);
        return NULL;
    }
    /* A .pgm name goes to our reader even with a wrong magic, for its message. */
    size_t pl = strlen(path);
    int pgm_name = pl >= 4 && path[pl - 4] == '.' && (path[pl - 3] | 0x20) == 'p' && (path[pl - 2] | 0x20) == 'g' &&
                   (path[pl - 1] | 0x20) == 'm';
    if (pgm_name || (got >= 2 && head[0] == 'P' && (head[1] == '2' || head[1] == '5'))) {
        /* Large enough for any DEM within the default limits, even as P2. */
        size_t limit = SIZE_MAX > 0xFFFFFFFFu ? (size_t)1 << 33 : (size_t)1 << 30;
        char *data;
        size_t size;
        if (cli_read_file(path, limit, &data, &size)) return NULL;
        rs_result rc = rs_dem_parse_pgm(ctx, data, size, &dem);
        free(data);
        if (rc != RS_OK) {
            cli_error("%s: %s", path, rs_ctx_message(ctx)[0] ? rs_ctx_message(ctx) : rs_strerror(rc));
            return NULL;
        }
        return dem;
    }
    uint32_t w, h;
    float *z;
    rs_limits lim;
    rs_ctx_limits(ctx, &lim);
    image_read r = { path, lim.max_dem_side, &w, &h, &z, NULL };
    if (read_image_quietly(&r)) return NULL;
    rs_result rc = rs_dem_create(ctx, w, h, z, &dem);
    free(z);
    if (rc != RS_OK) {
        cli_error("%s: %s", path, rs_ctx_message(ctx)[0] ? rs_ctx_message(ctx) : rs_strerror(rc));
        return NULL;
    }
    return dem;
}
