/* png_repeat IN.png [LEVEL]: the PNG writer's bytes in this process
 * (docs/packaging.md "Deterministic bytes"). IN is a PNG that roadsplat
 * wrote with --png-level 0 (8-bit, every row unfiltered); its pixels are
 * encoded again by cli/png.c at LEVEL (default: the CLI's default) and the
 * 64-bit FNV-1a hash of the bytes is printed. The same pixels must give the
 * same bytes in every process: ISA-L's level 1 did not, about once in a
 * thousand processes, depending on where the process was loaded, which no
 * single process shows. tests/cli_odr_test.sh runs it in 1000. */
#include "png.h"

#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

/* What cli/png.c takes from cli/util.c, which would bring OpenImageIO and
 * its start-up into every one of the test's processes: errors go to
 * stderr; the file and option helpers are not reached from
 * cli_png_encode. */
void cli_error(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("png_repeat: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
}
int cli_parse_u32(const char *option, const char *s, uint32_t *out) { (void)option, (void)s, (void)out; return 1; }
int cli_out_open(cli_out *o, const char *path) { (void)o, (void)path; return 1; }
void cli_out_abort(cli_out *o) { (void)o; }
void cli_temp_forget(const char *tmp) { (void)tmp; }

static uint32_t be32(const unsigned char *p) { return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3]; }

int main(int argc, char **argv)
{
    if (argc < 2 || argc > 3) {
        fprintf(stderr, "usage: png_repeat IN.png [LEVEL]\n");
        return 2;
    }
    FILE *f = fopen(argv[1], "rb");
    if (!f) { perror(argv[1]); return 1; }
    unsigned char *d = NULL;
    size_t n = 0, cap = 0, got;
    do {
        if (n == cap && !(d = realloc(d, cap = cap ? 2 * cap : 1 << 20))) return 1;
        got = fread(d + n, 1, cap - n, f);
        n += got;
    } while (got);
    fclose(f);
    /* the chunks: IHDR's size and colour type, the IDAT data joined */
    uint32_t w = 0, h = 0;
    int ch = 0;
    unsigned char *z = malloc(n ? n : 1);
    size_t zn = 0;
    for (size_t i = 8; z && i + 12 <= n;) {
        uint32_t len = be32(d + i);
        if (len > n - i - 12) break;
        const unsigned char *t = d + i + 4, *p = d + i + 8;
        if (!memcmp(t, "IHDR", 4) && len >= 13) {
            w = be32(p), h = be32(p + 4);
            ch = p[8] != 8 ? 0 : p[9] == 2 ? 3 : p[9] == 6 ? 4 : 0;
        } else if (!memcmp(t, "IDAT", 4)) {
            memcpy(z + zn, p, len);
            zn += len;
        }
        i += 12 + (size_t)len;
    }
    if (!z || !w || !h || !ch) {
        fprintf(stderr, "png_repeat: %s: not an 8-bit RGB or RGBA PNG\n", argv[1]);
        return 1;
    }
    size_t row = (size_t)w * (size_t)ch;
    uLongf raw_n = (uLongf)(h * (row + 1));
    unsigned char *raw = malloc(raw_n), *px = malloc(h * row);
    if (!raw || !px || uncompress(raw, &raw_n, z, (uLong)zn) != Z_OK || raw_n != h * (row + 1)) {
        fprintf(stderr, "png_repeat: %s: its image data do not inflate\n", argv[1]);
        return 1;
    }
    for (uint32_t y = 0; y < h; y++) {
        if (raw[y * (row + 1)] != 0) {
            fprintf(stderr, "png_repeat: %s: row %u is filtered (write it with --png-level 0)\n", argv[1], y);
            return 1;
        }
        memcpy(px + y * row, raw + y * (row + 1) + 1, row);
    }
    char *out = NULL;
    size_t out_n = 0;
    FILE *m = open_memstream(&out, &out_n);
    cli_png_image img = { w, h, ch, 8, px };
    cli_png_options opt = { argc > 2 ? atoi(argv[2]) : -1, NULL, NULL, 0 };
    if (!m || cli_png_encode(m, "png_repeat", &img, &opt) || fclose(m)) return 1;
    uint64_t hash = 1469598103934665603ull;
    for (size_t i = 0; i < out_n; i++) hash = (hash ^ (unsigned char)out[i]) * 1099511628211ull;
    printf("%016llx %zu\n", (unsigned long long)hash, out_n);
    free(out);
    free(px);
    free(raw);
    free(z);
    free(d);
    return 0;
}
