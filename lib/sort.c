/* A stable merge sort that polls for cancel (lib/internal.h rs__sort).
 *
 * Why not qsort: one qsort of 10^5 T clips or 2 x 10^5 road ends took 45-80
 * ms on the test host with no way to stop it (issue 30: cancel within 50
 * ms), and qsort's order of equal elements is the C library's choice
 * (glibc 2.36's merge sort is stable, musl's smoothsort is not). This sort
 * is stable everywhere, so ties keep their input order on every platform;
 * on glibc 2.36 it gives qsort's exact order.
 *
 * It sorts 32-bit indices (elements are often large structs), runs of
 * RUN by insertion, then merges bottom-up, and moves each element once at
 * the end. rs__sort_keyed sorts (key, index) records by radix instead
 * (rs__sort_recs, also the edits' fingerprint sort) and then moves each
 * element once: comparing through elements of a hundred bytes over tens of
 * megabytes is two cache misses a comparison (10^5 roads' T clips sorted
 * 8x slower per element than 10^4's), and a radix pass over 16-byte
 * records is a fraction of a merge (20,000 keys: 0.42 ms against the
 * keyed merge's 1.77 ms). */
#include "internal.h"

#include <string.h>

#define RUN 16
/* a poll after about this many element steps (~0.1-0.5 ms of work) */
#define POLL_STEPS 16384

typedef struct order {
    unsigned char *b;
    size_t size;
    int (*cmp)(const void *, const void *);
} order;

/* element i goes after element j (strictly) */
static int after(const order *o, uint32_t i, uint32_t j)
{
    return o->cmp(o->b + (size_t)i * o->size, o->b + (size_t)j * o->size) > 0;
}

/* Element a[k] of b goes to place k, each moved once: the cycles of the
 * permutation, one element of scratch; t: n flags (which places are done). */
static rs_result permute(rs_ctx *ctx, unsigned char *b, size_t n, size_t size, const uint32_t *a, uint32_t *t)
{
    unsigned char *tmp = rs__malloc(ctx, size);
    if (!tmp) return RS_ERR_NOMEM;
    size_t steps = 0;
    for (size_t i = 0; i < n; i++) t[i] = 0;
    for (size_t i = 0; i < n; i++) {
        if (t[i] || a[i] == i) continue;
        /* the cycle through i: place k takes the element at a[k] */
        memcpy(tmp, b + i * size, size);
        size_t k = i;
        for (;;) {
            t[k] = 1;
            steps++;
            size_t from = a[k];
            if (from == i) {
                memcpy(b + k * size, tmp, size);
                break;
            }
            memcpy(b + k * size, b + from * size, size);
            k = from;
        }
        if (steps >= POLL_STEPS) {
            steps = 0;
            /* (a stop here is seen by the caller's next check: the
             * array is half permuted, so the cycles are finished) */
            (void)rs__poll(ctx);
        }
    }
    rs__free(ctx, tmp);
    return RS_OK;
}

static rs_result sort_by(rs_ctx *ctx, size_t n, const order *o)
{
    const size_t size = o->size;
    if (n < 2) return RS_OK;
    if (n > UINT32_MAX || size == 0) return RS_ERR_LIMIT;
    unsigned char *b = o->b;
    uint32_t *ix = rs__alloc_array(ctx, n, 2 * sizeof *ix);
    if (!ix) return RS_ERR_NOMEM;
    uint32_t *a = ix, *t = ix + n;
    for (size_t i = 0; i < n; i++) a[i] = (uint32_t)i;
    size_t steps = 0;
    rs_result r = RS_OK;
    /* runs by insertion (stable: an element moves left only past greater ones) */
    for (size_t lo = 0; lo < n && !r; lo += RUN) {
        size_t hi = lo + RUN < n ? lo + RUN : n;
        for (size_t i = lo + 1; i < hi; i++) {
            uint32_t v = a[i];
            size_t j = i;
            while (j > lo && after(o, a[j - 1], v)) {
                a[j] = a[j - 1];
                j--;
            }
            a[j] = v;
        }
        if ((steps += RUN * 4) >= POLL_STEPS) {
            steps = 0;
            if (rs__poll(ctx)) r = RS_ERR_CANCELLED;
        }
    }
    /* merges: the left run wins ties */
    for (size_t w = RUN; w < n && !r; w *= 2) {
        for (size_t lo = 0; lo < n && !r; lo += 2 * w) {
            size_t mid = lo + w < n ? lo + w : n, hi = lo + 2 * w < n ? lo + 2 * w : n;
            size_t i = lo, j = mid, k = lo;
            if (mid == hi || !after(o, a[mid - 1], a[mid])) {
                memcpy(t + lo, a + lo, (hi - lo) * sizeof *a); /* already in order */
            } else {
                while (i < mid && j < hi)
                    t[k++] = !after(o, a[i], a[j]) ? a[i++] : a[j++];
                while (i < mid) t[k++] = a[i++];
                while (j < hi) t[k++] = a[j++];
            }
            if ((steps += hi - lo) >= POLL_STEPS) {
                steps = 0;
                if (rs__poll(ctx)) r = RS_ERR_CANCELLED;
            }
        }
        uint32_t *s = a;
        a = t;
        t = s;
    }
    if (!r) r = permute(ctx, b, n, size, a, t);
    rs__free(ctx, ix);
    return r;
}

rs_result rs__sort(rs_ctx *ctx, void *base, size_t n, size_t size, int (*cmp)(const void *, const void *))
{
    order o = { base, size, cmp };
    return sort_by(ctx, n, &o);
}

rs_result rs__sort_recs(rs_ctx *ctx, rs__keyed *r, size_t n)
{
    if (n < 2) return RS_OK;
    if (n < 64) { /* (stable: a record moves left only past greater keys) */
        for (size_t i = 1; i < n; i++) {
            rs__keyed v = r[i];
            size_t j = i;
            while (j > 0 && r[j - 1].h > v.h) {
                r[j] = r[j - 1];
                j--;
            }
            r[j] = v;
        }
        return RS_OK;
    }
    rs__keyed *t = rs__alloc_array(ctx, n, sizeof *t), *a = r, *b = t;
    if (!t) return RS_ERR_NOMEM;
    rs_result res = RS_OK;
    size_t steps = 0;
    for (int shift = 0; shift < 64 && !res; shift += 8) {
        size_t cnt[257] = { 0 };
        for (size_t i = 0; i < n; i++) cnt[((a[i].h >> shift) & 255) + 1]++;
        if (cnt[((a[0].h >> shift) & 255) + 1] == n) continue; /* (one value: nothing moves) */
        for (int d = 0; d < 256; d++) cnt[d + 1] += cnt[d];
        for (size_t i = 0; i < n; i++) b[cnt[(a[i].h >> shift) & 255]++] = a[i];
        rs__keyed *x = a;
        a = b, b = x;
        if ((steps += 2 * n) >= POLL_STEPS) {
            steps = 0;
            if (rs__poll(ctx)) res = RS_ERR_CANCELLED;
        }
    }
    if (a != r) memcpy(r, a, n * sizeof *r);
    rs__free(ctx, t);
    return res;
}

rs_result rs__sort_keyed(rs_ctx *ctx, void *base, size_t n, size_t size, const uint64_t *key)
{
    if (n < 2) return RS_OK;
    if (n > UINT32_MAX || size == 0) return RS_ERR_LIMIT;
    rs__keyed *rec = rs__alloc_array(ctx, n, sizeof *rec);
    if (!rec) return RS_ERR_NOMEM;
    for (size_t i = 0; i < n; i++) rec[i].h = key[i], rec[i].i = (uint32_t)i, rec[i].pos = 0;
    rs_result r = rs__sort_recs(ctx, rec, n);
    uint32_t *a = r ? NULL : rs__alloc_array(ctx, n, 2 * sizeof *a);
    if (!r && !a) r = RS_ERR_NOMEM;
    for (size_t i = 0; !r && i < n; i++) a[i] = rec[i].i;
    rs__free(ctx, rec);
    if (!r) r = permute(ctx, base, n, size, a, a + n);
    rs__free(ctx, a);
    return r;
}

int rs__cmp_u32(const void *pa, const void *pb)
{
    uint32_t a = *(const uint32_t *)pa, b = *(const uint32_t *)pb;
    return (a > b) - (a < b);
}
