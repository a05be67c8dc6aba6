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
 * the end. rs__sort_keyed compares 64-bit keys from an array of their
 * own: with elements of a hundred bytes over tens of megabytes, each
 * comparison through the elements is two cache misses (10^5 roads' T
 * clips sorted 8x slower per element than 10^4's). */
#include "internal.h"

#include <string.h>

#define RUN 16
/* a poll after about this many element steps (~0.1-0.5 ms of work) */
#define POLL_STEPS 16384

typedef struct order {
    unsigned char *b;
    size_t size;
    int (*cmp)(const void *, const void *);
    const uint64_t *key;
} order;

/* element i goes after element j (strictly) */
static int after(const order *o, uint32_t i, uint32_t j)
{
    if (o->key) return o->key[i] > o->key[j];
    return o->cmp(o->b + (size_t)i * o->size, o->b + (size_t)j * o->size) > 0;
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
    if (!r) {
        /* move each element to its place: cycles of the permutation, one
         * element of scratch (t: which places are done) */
        unsigned char *tmp = rs__malloc(ctx, size);
        if (!tmp) r = RS_ERR_NOMEM;
        for (size_t i = 0; i < n && !r; i++) t[i] = 0;
        for (size_t i = 0; i < n && !r; i++) {
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
    }
    rs__free(ctx, ix);
    return r;
}

rs_result rs__sort(rs_ctx *ctx, void *base, size_t n, size_t size, int (*cmp)(const void *, const void *))
{
    order o = { base, size, cmp, NULL };
    return sort_by(ctx, n, &o);
}

rs_result rs__sort_keyed(rs_ctx *ctx, void *base, size_t n, size_t size, const uint64_t *key)
{
    order o = { base, size, NULL, key };
    return sort_by(ctx, n, &o);
}

int rs__cmp_u32(const void *pa, const void *pb)
{
    uint32_t a = *(const uint32_t *)pa, b = *(const uint32_t *)pb;
    return (a > b) - (a < b);
}
