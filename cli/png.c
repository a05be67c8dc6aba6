/* PNG writer of the CLI: the container (signature, IHDR, IDAT, IEND) is
 * written here, the deflate stream by libdeflate. OpenImageIO 2.4 wrote
 * PNGs through libpng at zlib level 6 with adaptive filters, 89 % of a
 * large run (docs/packaging.md has the measurements behind the choices).
 *
 * - Filter: UP on every row but the first (SUB). On the splat textures UP
 *   compresses best of the five PNG filters at every level, and it costs
 *   one subtraction per byte; the adaptive heuristic picked Paeth there,
 *   which is 6 % larger.
 * - Deflate: libdeflate compresses the whole filtered image in one call, as
 *   one zlib stream (PNG allows only one). libdeflate has no flush points,
 *   so the stream cannot be split into bands compressed in parallel; its
 *   level 1 in one thread was faster than zlib level 1 in two bands on the
 *   shared 2-core machine, and 12 % smaller.
 * - Memory: the filtered copy and the output are allocated with mmap and
 *   MADV_HUGEPAGE when large: first touch of 64 MB in 4 KiB pages cost
 *   200 ms on the benchmark machine, against 10 ms in huge pages.
 *
 * Every failure prints one line "roadsplat: SHOWN: problem" and returns 1. */
#define _DEFAULT_SOURCE 1 /* MAP_ANONYMOUS, MADV_HUGEPAGE */
#include "cli.h"

#include <errno.h>
#include <fcntl.h>
#include <libdeflate.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

/* Buffers of at least this size come from mmap (huge pages when allowed). */
#define BIG_ALLOC ((size_t)4 << 20)
/* IDAT chunk payload; the progress bar advances per chunk written. */
#define IDAT_CHUNK ((size_t)1 << 20)

typedef struct big_buf {
    uint8_t *p;
    size_t n;
    int mapped;
} big_buf;

static int big_alloc(big_buf *b, size_t n)
{
    b->n = n;
    b->mapped = 0;
    b->p = NULL;
    if (n >= BIG_ALLOC) {
        void *m = mmap(NULL, n, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        if (m != MAP_FAILED) {
#ifdef MADV_HUGEPAGE
            (void)madvise(m, n, MADV_HUGEPAGE); /* a hint; fine when refused */
#endif
            b->p = m;
            b->mapped = 1;
            return 0;
        }
    }
    b->p = malloc(n ? n : 1);
    return b->p ? 0 : 1;
}

static void big_free(big_buf *b)
{
    if (b->mapped) munmap(b->p, b->n);
    else free(b->p);
    b->p = NULL;
}

static void put_be32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)(v >> 24);
    p[1] = (uint8_t)(v >> 16);
    p[2] = (uint8_t)(v >> 8);
    p[3] = (uint8_t)v;
}

static uint32_t get_be32(const uint8_t *p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

static int write_chunk(FILE *f, const char type[4], const uint8_t *data, size_t n)
{
    uint8_t hdr[8], crc[4];
    put_be32(hdr, (uint32_t)n);
    memcpy(hdr + 4, type, 4);
    uint32_t c = libdeflate_crc32(0, hdr + 4, 4);
    if (n) c = libdeflate_crc32(c, data, n);
    put_be32(crc, c);
    return fwrite(hdr, 1, 8, f) == 8 && (n == 0 || fwrite(data, 1, n, f) == n) && fwrite(crc, 1, 4, f) == 4;
}

/* Row y of the image as PNG bytes (16-bit samples big-endian) into out. */
static void raw_row(const uint8_t *data, size_t row_bytes, uint32_t y, int bits, uint8_t *out)
{
    const uint8_t *src = data + (size_t)y * row_bytes;
    if (bits == 8) {
        memcpy(out, src, row_bytes);
        return;
    }
    const uint16_t *s16 = (const uint16_t *)(const void *)src;
    for (size_t i = 0; i < row_bytes / 2; i++) {
        out[2 * i] = (uint8_t)(s16[i] >> 8);
        out[2 * i + 1] = (uint8_t)(s16[i] & 0xFF);
    }
}

/* The filtered image: per row one filter byte, then the filtered bytes. */
static void filter_rows(const cli_png_image *img, size_t row_bytes, size_t bpp, int filter, uint8_t *out,
                        uint8_t *prev, uint8_t *cur, const cli_png_options *opt)
{
    for (uint32_t y = 0; y < img->height; y++) {
        uint8_t *o = out + (size_t)y * (row_bytes + 1);
        const uint8_t *r;
        if (img->bits == 8) r = (const uint8_t *)img->data + (size_t)y * row_bytes;
        else { raw_row(img->data, row_bytes, y, 16, cur); r = cur; }
        const uint8_t *p = y == 0 ? NULL : img->bits == 8 ? r - row_bytes : prev;
        if (!filter) {
            o[0] = 0;
            memcpy(o + 1, r, row_bytes);
        } else if (y == 0) { /* SUB: no row above */
            o[0] = 1;
            memcpy(o + 1, r, bpp < row_bytes ? bpp : row_bytes);
            for (size_t i = bpp; i < row_bytes; i++) o[1 + i] = (uint8_t)(r[i] - r[i - bpp]);
        } else { /* UP */
            o[0] = 2;
            for (size_t i = 0; i < row_bytes; i++) o[1 + i] = (uint8_t)(r[i] - p[i]);
        }
        if (img->bits == 16) { uint8_t *t = prev; prev = cur; cur = t; }
        if (opt && opt->progress && (y & 255) == 255) opt->progress(opt->progress_user, (uint64_t)y * 100 / img->height, 1000);
    }
}

int cli_png_encode(FILE *f, const char *shown, const cli_png_image *img, const cli_png_options *opt)
{
    static const uint8_t sig[8] = { 0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n' };
    int level = opt && opt->level >= 0 ? opt->level : CLI_PNG_LEVEL_DEFAULT;
    const uint32_t w = img->width, h = img->height;
    const int channels = img->channels, bits = img->bits;
    if (channels < 1 || channels > 4 || (bits != 8 && bits != 16) || !w || !h || !img->data || w > 0x7fffffffu ||
        h > 0x7fffffffu || level > CLI_PNG_LEVEL_MAX) {
        cli_error("%s: cannot write a %ux%u PNG with %d channels of %d bits at level %d", shown, w, h, channels, bits,
                  level);
        return 1;
    }
    const size_t bpp = (size_t)channels * (size_t)(bits / 8);
    if ((size_t)w > (SIZE_MAX - 1) / bpp / 2 || (size_t)h > SIZE_MAX / 2 / ((size_t)w * bpp + 1)) {
        cli_error("%s: image too large for this machine (%ux%u)", shown, w, h);
        return 1;
    }
    const size_t row_bytes = (size_t)w * bpp, filtered = (row_bytes + 1) * (size_t)h;
    big_buf fb = { NULL, 0, 0 }, zb = { NULL, 0, 0 };
    uint8_t *rows = NULL;
    struct libdeflate_compressor *c = libdeflate_alloc_compressor(level);
    int ok = 0;
    if (!c || big_alloc(&fb, filtered) || (bits == 16 && !(rows = malloc(2 * row_bytes)))) {
        cli_error("%s: out of memory for a %ux%u PNG", shown, w, h);
        goto done;
    }
    filter_rows(img, row_bytes, bpp, level > 0, fb.p, rows, rows ? rows + row_bytes : NULL, opt);
    if (opt && opt->progress) opt->progress(opt->progress_user, 100, 1000);
    size_t bound = libdeflate_zlib_compress_bound(c, filtered);
    if (big_alloc(&zb, bound)) {
        cli_error("%s: out of memory for a %ux%u PNG", shown, w, h);
        goto done;
    }
    size_t zn = libdeflate_zlib_compress(c, fb.p, filtered, zb.p, bound);
    big_free(&fb);
    if (!zn) {
        cli_error("%s: compression failed", shown);
        goto done;
    }
    if (opt && opt->progress) opt->progress(opt->progress_user, 900, 1000);

    uint8_t ihdr[13];
    put_be32(ihdr, w);
    put_be32(ihdr + 4, h);
    ihdr[8] = (uint8_t)bits;
    ihdr[9] = (uint8_t)(channels == 1 ? 0 : channels == 2 ? 4 : channels == 3 ? 2 : 6); /* colour type */
    ihdr[10] = ihdr[11] = ihdr[12] = 0; /* deflate, adaptive filtering, no interlace */
    ok = fwrite(sig, 1, 8, f) == 8 && write_chunk(f, "IHDR", ihdr, sizeof ihdr);
    for (size_t off = 0; ok && off < zn; off += IDAT_CHUNK) {
        size_t n = zn - off < IDAT_CHUNK ? zn - off : IDAT_CHUNK;
        ok = write_chunk(f, "IDAT", zb.p + off, n);
        if (opt && opt->progress) opt->progress(opt->progress_user, 900 + (uint64_t)(off + n) * 100 / zn, 1000);
    }
    ok = ok && write_chunk(f, "IEND", NULL, 0) && fflush(f) == 0 && !ferror(f);
    if (!ok) cli_error("%s: write failed: %s", shown, strerror(errno ? errno : EIO));
done:
    if (c) libdeflate_free_compressor(c);
    if (fb.p) big_free(&fb);
    if (zb.p) big_free(&zb);
    free(rows);
    return !ok;
}

int cli_png_write(const char *path, const char *shown, const cli_png_image *img, const cli_png_options *opt)
{
    cli_out o;
    if (!shown) shown = path;
    if (cli_out_open(&o, path)) return 1;
    int bad = cli_png_encode(o.f, shown, img, opt);
    if (!bad) {
        /* Close the temporary (its write errors reported) before checking it. */
        int e = 0;
        if (fflush(o.f) != 0 || ferror(o.f)) { bad = 1; e = errno; }
        if (!bad && fsync(fileno(o.f)) != 0 && errno != EINVAL) { bad = 1; e = errno; }
        if (fclose(o.f) != 0 && !bad) { bad = 1; e = errno; }
        o.f = NULL;
        if (bad) cli_error("%s: write failed: %s", shown, strerror(e ? e : EIO));
        else if (!cli_png_file_complete(o.tmp)) {
            cli_error("%s: write failed: the PNG did not reach the disk whole", shown);
            bad = 1;
        } else if (rename(o.tmp, o.path) != 0) {
            cli_error("%s: write failed: %s", shown, strerror(errno));
            bad = 1;
        }
    }
    if (bad) {
        cli_out_abort(&o);
        return 1;
    }
    cli_temp_forget(o.tmp); /* renamed: no longer ours to remove on a signal */
    free(o.path);
    free(o.tmp);
    return 0;
}

int cli_image_write_png(const char *path, uint32_t w, uint32_t h, int channels, int bits, const void *data)
{
    cli_png_image img = { w, h, channels, bits, data };
    return cli_png_write(path, path, &img, NULL);
}

int cli_image_write_png_as(const char *path, const char *shown, uint32_t w, uint32_t h, int channels, int bits,
                           const void *data)
{
    cli_png_image img = { w, h, channels, bits, data };
    return cli_png_write(path, shown, &img, NULL);
}

/* 1 when the file at `path` is a whole PNG: the signature, then chunks
 * whose lengths chain exactly to an IEND at the end of the file, every CRC
 * right. OUT is only renamed into place after this check (a full disk or a
 * file size limit must never leave a truncated image under the OUT name). */
int cli_png_file_complete(const char *path)
{
    static const unsigned char sig[8] = { 0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n' };
    FILE *f = fopen(path, "rb");
    if (!f) return 0;
    unsigned char hdr[8], buf[1 << 15];
    int ok = fread(hdr, 1, 8, f) == 8 && memcmp(hdr, sig, 8) == 0, seen_iend = 0, first = 1;
    while (ok && !seen_iend) {
        if (fread(hdr, 1, 8, f) != 8) { ok = 0; break; }
        uint32_t len = get_be32(hdr);
        if (len > 0x7FFFFFFFu || (first && memcmp(hdr + 4, "IHDR", 4) != 0)) { ok = 0; break; }
        first = 0;
        seen_iend = memcmp(hdr + 4, "IEND", 4) == 0;
        uint32_t c = libdeflate_crc32(0, hdr + 4, 4);
        for (uint32_t left = len; left > 0;) {
            size_t want = left < sizeof buf ? left : sizeof buf;
            if (fread(buf, 1, want, f) != want) { ok = 0; break; }
            c = libdeflate_crc32(c, buf, want);
            left -= (uint32_t)want;
        }
        if (!ok || fread(hdr, 1, 4, f) != 4) { ok = 0; break; }
        ok = get_be32(hdr) == c;
    }
    ok = ok && seen_iend && fgetc(f) == EOF && !ferror(f);
    fclose(f);
    return ok;
}

int cli_parse_png_level(const char *option, const char *s, int *level)
{
    uint32_t u;
    if (cli_parse_u32(option, s, &u)) return 1;
    if (u > CLI_PNG_LEVEL_MAX) {
        cli_error("%s: '%s' must be 0..%d", option, s, CLI_PNG_LEVEL_MAX);
        return 1;
    }
    *level = (int)u;
    return 0;
}

/* Into an existing temporary of the caller's (truncated), no rename. */
int cli_image_write_png_file(const char *path, const char *shown, uint32_t w, uint32_t h, int channels, int bits,
                             const void *data)
{
    cli_png_image img = { w, h, channels, bits, data };
    FILE *f = fopen(path, "wb");
    if (!f) {
        cli_error("%s: write failed: %s", shown, strerror(errno));
        return 1;
    }
    int bad = cli_png_encode(f, shown, &img, NULL), e = 0;
    if (!bad) {
        if (fflush(f) != 0 || ferror(f)) { bad = 1; e = errno; }
        if (!bad && fsync(fileno(f)) != 0 && errno != EINVAL) { bad = 1; e = errno; }
    }
    if (fclose(f) != 0 && !bad) { bad = 1; e = errno; }
    if (bad) {
        if (e) cli_error("%s: write failed: %s", shown, strerror(e));
        return 1;
    }
    if (!cli_png_file_complete(path)) {
        cli_error("%s: write failed: the PNG did not reach the disk whole", shown);
        return 1;
    }
    return 0;
}
