/* DEM objects and the PGM reader (P2 ASCII, P5 binary).
 *
 * Accepted: magic, width, height, maxval separated by whitespace, with '#'
 * comments (to the end of the line) wherever whitespace is allowed; maxval
 * 1..65535; P5 samples are 1 byte (maxval <= 255) or 2 bytes big-endian,
 * after exactly one whitespace byte (or a comment ending in a newline);
 * P2 samples are decimal numbers separated by whitespace and comments.
 *
 * Trailing data policy: after the last sample only ASCII whitespace (and,
 * in P2, comments) may follow. Anything else is an error, because it almost
 * always means the header's width/height do not match the data. Files with
 * several concatenated images are therefore rejected.
 *
 * Sizes are checked against ctx->limits and for overflow, and the data is
 * checked to be long enough for width*height samples, before allocating. */
#include "dem.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

typedef struct pgm_reader {
    const unsigned char *p, *end, *start;
    uint64_t line; /* 1-based line of p, for messages */
} pgm_reader;

static int pgm_space(unsigned char c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

static int pgm_digit(unsigned char c) { return c >= '0' && c <= '9'; }

/* Skip whitespace and comments. */
static void pgm_skip(pgm_reader *r)
{
    while (r->p < r->end) {
        unsigned char c = *r->p;
        if (c == '#') {
            while (r->p < r->end && *r->p != '\n' && *r->p != '\r') r->p++;
        } else if (pgm_space(c)) {
            if (c == '\n') r->line++;
            r->p++;
        } else {
            break;
        }
    }
}

/* Read an unsigned decimal number (after pgm_skip). Returns 1 ok, 0 no
 * digits, -1 too large for 64 bits (saturated in *out). */
static int pgm_number(pgm_reader *r, uint64_t *out)
{
    uint64_t v = 0;
    int big = 0;
    const unsigned char *s = r->p;
    while (r->p < r->end && pgm_digit(*r->p)) {
        unsigned d = (unsigned)(*r->p - '0');
        if (v > (UINT64_MAX - d) / 10) big = 1;
        else v = v * 10 + d;
        r->p++;
    }
    *out = big ? UINT64_MAX : v;
    if (r->p == s) return 0;
    return big ? -1 : 1;
}

/* Describe the byte at r->p for an error message. */
static const char *pgm_what(const pgm_reader *r, char *buf, size_t n)
{
    if (r->p >= r->end) return "end of data";
    unsigned char c = *r->p;
    if (c > 32 && c < 127) { buf[0] = '\''; buf[1] = (char)c; buf[2] = '\''; buf[3] = 0; }
    else {
        static const char hex[] = "0123456789abcdef";
        const char *t = "byte 0x";
        size_t i = 0;
        for (; t[i] && i + 3 < n; i++) buf[i] = t[i];
        buf[i++] = hex[c >> 4];
        buf[i++] = hex[c & 15];
        buf[i] = 0;
    }
    return buf;
}

/* Header field: skip separators, require a number, and a separator (or a
 * comment) right after it. */
static rs_result pgm_header_field(rs_ctx *ctx, pgm_reader *r, const char *name, uint64_t *out)
{
    char what[16];
    const unsigned char *before = r->p;
    pgm_skip(r);
    if (r->p == before && r->p < r->end)
        return rs__fail(ctx, RS_ERR_PARSE, "PGM line %llu: expected whitespace before the %s, got %s",
                        (unsigned long long)r->line, name, pgm_what(r, what, sizeof what));
    int k = pgm_number(r, out);
    if (k == 0) {
        if (r->p >= r->end)
            return rs__fail(ctx, RS_ERR_PARSE, "PGM line %llu: header truncated: %s missing",
                            (unsigned long long)r->line, name);
        return rs__fail(ctx, RS_ERR_PARSE, "PGM line %llu: %s must be a decimal number, got %s",
                        (unsigned long long)r->line, name, pgm_what(r, what, sizeof what));
    }
    if (k < 0)
        return rs__fail(ctx, RS_ERR_PARSE, "PGM line %llu: %s is too large (more than 64 bits)",
                        (unsigned long long)r->line, name);
    if (r->p < r->end && !pgm_space(*r->p) && *r->p != '#')
        return rs__fail(ctx, RS_ERR_PARSE, "PGM line %llu: unexpected %s after the %s",
                        (unsigned long long)r->line, pgm_what(r, what, sizeof what), name);
    return RS_OK;
}

static rs_result dem_check_size(rs_ctx *ctx, uint64_t w, uint64_t h, const char *what)
{
    if (w < 2 || h < 2)
        return rs__fail(ctx, RS_ERR_PARSE, "%s: DEM is %llux%llu; width and height must be >= 2",
                        what, (unsigned long long)w, (unsigned long long)h);
    if (w > ctx->limits.max_dem_side || h > ctx->limits.max_dem_side)
        return rs__fail(ctx, RS_ERR_LIMIT, "%s: DEM is %llux%llu; the limit is %u samples per side",
                        what, (unsigned long long)w, (unsigned long long)h, ctx->limits.max_dem_side);
    return RS_OK;
}

/* Samples between two progress polls of the sample loops. */
#define PGM_POLL 65536u

static rs_result pgm_parse(rs_ctx *ctx, const void *data, size_t size, rs_dem **out)
{

    pgm_reader r;
    r.start = r.p = data;
    r.end = r.p + size;
    r.line = 1;
    if (size < 2 || r.p[0] != 'P' || (r.p[1] != '2' && r.p[1] != '5'))
        return rs__fail(ctx, RS_ERR_PARSE, "not a PGM file (expected \"P2\" or \"P5\" at the start)");
    int binary = r.p[1] == '5';
    r.p += 2;

    uint64_t w, h, maxval;
    rs_result rc;
    if ((rc = pgm_header_field(ctx, &r, "width", &w)) != RS_OK) return rc;
    if ((rc = pgm_header_field(ctx, &r, "height", &h)) != RS_OK) return rc;
    if ((rc = pgm_header_field(ctx, &r, "maxval", &maxval)) != RS_OK) return rc;
    if (maxval < 1 || maxval > 65535)
        return rs__fail(ctx, RS_ERR_PARSE, "PGM line %llu: maxval %llu is outside 1..65535",
                        (unsigned long long)r.line, (unsigned long long)maxval);
    char where[48];
    snprintf(where, sizeof where, "PGM line %llu", (unsigned long long)r.line);
    if ((rc = dem_check_size(ctx, w, h, where)) != RS_OK) return rc;
    uint64_t count = w * h; /* both <= 2^32 - 1 after the limit check: no overflow */
    size_t n;
    if (count > SIZE_MAX || !rs__mul_size((size_t)w, (size_t)h, &n))
        return rs__fail(ctx, RS_ERR_LIMIT, "PGM header: %llux%llu samples do not fit in memory",
                        (unsigned long long)w, (unsigned long long)h);

    if (binary) {
        /* Exactly one whitespace byte ends the header; a comment there ends
         * with its newline. */
        if (r.p < r.end && *r.p == '#') {
            while (r.p < r.end && *r.p != '\n' && *r.p != '\r') r.p++;
        }
        if (r.p >= r.end)
            return rs__fail(ctx, RS_ERR_PARSE, "PGM truncated: no sample data after the header");
        r.p++; /* pgm_header_field guaranteed whitespace (or '#', skipped above) */
        size_t bps = maxval > 255 ? 2 : 1, need;
        if (!rs__mul_size(n, bps, &need))
            return rs__fail(ctx, RS_ERR_LIMIT, "PGM header: %llux%llu samples do not fit in memory",
                            (unsigned long long)w, (unsigned long long)h);
        size_t have = (size_t)(r.end - r.p);
        if (have < need)
            return rs__fail(ctx, RS_ERR_PARSE,
                            "PGM truncated: %llux%llu samples need %zu bytes, only %zu present (sample %zu is incomplete)",
                            (unsigned long long)w, (unsigned long long)h, need, have, have / bps);
        /* Validate before allocating: samples above maxval, trailing junk. */
        const unsigned char *s = r.p;
        if (maxval != 255 && maxval != 65535) {
            for (size_t i = 0; i < n; i++) {
                if ((i & (PGM_POLL - 1)) == PGM_POLL - 1 && rs__poll(ctx)) return RS_ERR_CANCELLED;
                unsigned v = bps == 2 ? ((unsigned)s[2 * i] << 8) | s[2 * i + 1] : s[i];
                if (v > maxval)
                    return rs__fail(ctx, RS_ERR_PARSE,
                                    "PGM sample %zu (row %zu, column %zu) is %u, above maxval %llu",
                                    i, i / (size_t)w, i % (size_t)w, v, (unsigned long long)maxval);
            }
        }
        for (const unsigned char *t = s + need; t < r.end; t++)
            if (!pgm_space(*t))
                return rs__fail(ctx, RS_ERR_PARSE,
                                "PGM: %zu unexpected bytes after the last sample (offset %zu); width/height wrong?",
                                (size_t)(r.end - (s + need)), (size_t)(t - r.start));
        rs_dem *dem;
        if ((rc = rs__dem_alloc(ctx, (uint32_t)w, (uint32_t)h, &dem)) != RS_OK) return rc;
        unsigned lo = UINT_MAX, hi = 0; /* (the range here: a pass of its own took 45 ms unpolled at 8193^2) */
        for (size_t i = 0; i < n; i++) {
            if ((i & (PGM_POLL - 1)) == PGM_POLL - 1 && rs__report(ctx, PGM_POLL * bps)) {
                rs_dem_free(ctx, dem);
                return RS_ERR_CANCELLED;
            }
            unsigned v = bps == 2 ? ((unsigned)s[2 * i] << 8) | s[2 * i + 1] : s[i];
            lo = v < lo ? v : lo, hi = v > hi ? v : hi;
            dem->z[i] = (float)v;
        }
        rs__dem_seal_range(dem, (float)lo, (float)hi, 0);
        *out = dem;
        rs__ok(ctx);
        return RS_OK;
    }

    /* P2: every sample but the last needs a digit and a separator. */
    size_t have = (size_t)(r.end - r.p);
    if (n > have / 2 + 1)
        return rs__fail(ctx, RS_ERR_PARSE,
                        "PGM truncated: %llux%llu samples cannot fit in the %zu bytes after the header",
                        (unsigned long long)w, (unsigned long long)h, have);
    rs_dem *dem;
    if ((rc = rs__dem_alloc(ctx, (uint32_t)w, (uint32_t)h, &dem)) != RS_OK) return rc;
    char what[16];
    const unsigned char *said = r.p;
    uint64_t vlo = UINT64_MAX, vhi = 0; /* (the range as the samples come) */
    for (size_t i = 0; i < n; i++) {
        if ((i & (PGM_POLL - 1)) == PGM_POLL - 1) {
            if (rs__report(ctx, (uint64_t)(r.p - said))) {
                rc = RS_ERR_CANCELLED;
                goto fail;
            }
            said = r.p;
        }
        pgm_skip(&r);
        uint64_t v;
        int k = pgm_number(&r, &v);
        if (k == 0) {
            if (r.p >= r.end)
                rc = rs__fail(ctx, RS_ERR_PARSE, "PGM line %llu: truncated: %zu of %zu samples present",
                              (unsigned long long)r.line, i, n);
            else
                rc = rs__fail(ctx, RS_ERR_PARSE, "PGM line %llu: sample %zu: expected a number, got %s",
                              (unsigned long long)r.line, i, pgm_what(&r, what, sizeof what));
            goto fail;
        }
        if (k < 0) { /* more digits than 64 bits hold: don't print a saturated value */
            rc = rs__fail(ctx, RS_ERR_PARSE, "PGM line %llu: sample %zu (row %zu, column %zu) is too large, above maxval %llu",
                          (unsigned long long)r.line, i, i / (size_t)w, i % (size_t)w, (unsigned long long)maxval);
            goto fail;
        }
        if (v > maxval) {
            rc = rs__fail(ctx, RS_ERR_PARSE, "PGM line %llu: sample %zu (row %zu, column %zu) is %llu, above maxval %llu",
                          (unsigned long long)r.line, i, i / (size_t)w, i % (size_t)w, (unsigned long long)v,
                          (unsigned long long)maxval);
            goto fail;
        }
        if (r.p < r.end && !pgm_space(*r.p) && *r.p != '#') {
            rc = rs__fail(ctx, RS_ERR_PARSE, "PGM line %llu: sample %zu: unexpected %s after the number",
                          (unsigned long long)r.line, i, pgm_what(&r, what, sizeof what));
            goto fail;
        }
        vlo = v < vlo ? v : vlo, vhi = v > vhi ? v : vhi;
        dem->z[i] = (float)v;
    }
    pgm_skip(&r);
    if (r.p < r.end) {
        rc = rs__fail(ctx, RS_ERR_PARSE, "PGM line %llu: unexpected %s after the last of %zu samples; width/height wrong?",
                      (unsigned long long)r.line, pgm_what(&r, what, sizeof what), n);
        goto fail;
    }
    rs__dem_seal_range(dem, (float)vlo, (float)vhi, 0);
    *out = dem;
    rs__ok(ctx);
    return RS_OK;
fail:
    rs_dem_free(ctx, dem);
    return rc;
}

/* Progress: the context's callback (rs_ctx_set_progress), bytes of samples
 * read of the file's size; a poll every PGM_POLL samples. */
rs_result rs_dem_parse_pgm(rs_ctx *ctx, const void *data, size_t size, rs_dem **out)
{
    if (!out) return ctx ? rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_dem_parse_pgm: out is NULL") : RS_ERR_INVALID_ARG;
    *out = NULL;
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!data && size) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_dem_parse_pgm: data is NULL");
    rs__progress pg;
    rs__progress_begin(ctx, &pg, NULL, NULL, size ? size : 1, PGM_POLL);
    return rs__progress_end(ctx, &pg, pgm_parse(ctx, data, size, out));
}
