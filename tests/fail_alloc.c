#include "fail_alloc.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static void *fa_malloc(void *u, size_t n)
{
    fail_alloc *f = u;
    if (f->countdown == 0) return NULL;
    if (f->countdown > 0) f->countdown--;
    void *p = malloc(n);
    if (p) f->live++;
    return p;
}

static void *fa_realloc(void *u, void *p, size_t n)
{
    fail_alloc *f = u;
    if (f->countdown == 0) return NULL;
    if (f->countdown > 0) f->countdown--;
    void *q = realloc(p, n);
    if (q && !p) f->live++;
    return q;
}

static void fa_free(void *u, void *p)
{
    fail_alloc *f = u;
    f->live--;
    free(p);
}

rs_allocator fail_alloc_hook(fail_alloc *f)
{
    rs_allocator a = { fa_malloc, fa_realloc, fa_free, f };
    return a;
}

static void *ca_malloc(void *u, size_t n)
{
    ++*(size_t *)u;
    return malloc(n);
}

static void *ca_realloc(void *u, void *p, size_t n)
{
    ++*(size_t *)u;
    return realloc(p, n);
}

static void ca_free(void *u, void *p)
{
    (void)u;
    free(p);
}

rs_allocator count_alloc_hook(size_t *calls)
{
    rs_allocator a = { ca_malloc, ca_realloc, ca_free, calls };
    return a;
}

#define SIZE_HEAD 16 /* (the block's size; keeps malloc's alignment) */

static void *sa_malloc(void *u, size_t n)
{
    size_alloc *s = u;
    if (n > SIZE_MAX - SIZE_HEAD) return NULL;
    unsigned char *h = malloc(SIZE_HEAD + n);
    if (!h) return NULL;
    memcpy(h, &n, sizeof n);
    s->live += n;
    if (s->live > s->peak) s->peak = s->live;
    s->blocks++;
    return h + SIZE_HEAD;
}

static void *sa_realloc(void *u, void *p, size_t n)
{
    size_alloc *s = u;
    if (s->no_realloc) return NULL;
    if (!p) return sa_malloc(u, n);
    if (n > SIZE_MAX - SIZE_HEAD) return NULL;
    unsigned char *h = (unsigned char *)p - SIZE_HEAD;
    size_t old;
    memcpy(&old, h, sizeof old);
    unsigned char *q = realloc(h, SIZE_HEAD + n);
    if (!q) return NULL;
    memcpy(q, &n, sizeof n);
    if (n > old) s->kept += old;
    s->live = s->live - old + n;
    if (s->live > s->peak) s->peak = s->live;
    return q + SIZE_HEAD;
}

static void sa_free(void *u, void *p)
{
    size_alloc *s = u;
    if (!p) return;
    unsigned char *h = (unsigned char *)p - SIZE_HEAD;
    size_t old;
    memcpy(&old, h, sizeof old);
    s->live -= old;
    s->blocks--;
    free(h);
}

rs_allocator size_alloc_hook(size_alloc *s)
{
    rs_allocator a = { sa_malloc, sa_realloc, sa_free, s };
    return a;
}

/* A guarded block: its size in a 16-byte header, the caller's bytes, then
 * GUARD_BYTES of GUARD_FILL. */
#define GUARD_HEAD 16
#define GUARD_BYTES 256
#define GUARD_FILL 0xA5

static void guard_set(unsigned char *h, size_t n)
{
    memcpy(h, &n, sizeof n);
    memset(h + GUARD_HEAD + n, GUARD_FILL, GUARD_BYTES);
}

static void guard_test(guard_alloc *g, unsigned char *h)
{
    size_t n;
    memcpy(&n, h, sizeof n);
    for (size_t i = 0; i < GUARD_BYTES; i++)
        if (h[GUARD_HEAD + n + i] != GUARD_FILL) {
            g->broken++;
            return;
        }
}

static void *ga_malloc(void *u, size_t n)
{
    guard_alloc *g = u;
    if (n > SIZE_MAX - GUARD_HEAD - GUARD_BYTES) return NULL;
    unsigned char *h = malloc(GUARD_HEAD + n + GUARD_BYTES);
    if (!h) return NULL;
    guard_set(h, n);
    g->live++;
    return h + GUARD_HEAD;
}

static void *ga_realloc(void *u, void *p, size_t n)
{
    guard_alloc *g = u;
    if (!p) return ga_malloc(u, n);
    if (n > SIZE_MAX - GUARD_HEAD - GUARD_BYTES) return NULL;
    unsigned char *h = (unsigned char *)p - GUARD_HEAD;
    guard_test(g, h);
    unsigned char *q = realloc(h, GUARD_HEAD + n + GUARD_BYTES);
    if (!q) return NULL;
    guard_set(q, n);
    return q + GUARD_HEAD;
}

static void ga_free(void *u, void *p)
{
    guard_alloc *g = u;
    if (!p) return;
    unsigned char *h = (unsigned char *)p - GUARD_HEAD;
    guard_test(g, h);
    g->live--;
    free(h);
}

rs_allocator guard_alloc_hook(guard_alloc *g)
{
    rs_allocator a = { ga_malloc, ga_realloc, ga_free, g };
    return a;
}

fail_sweep fail_alloc_sweep(long max_tries, fail_try_fn fn, void *user)
{
    fail_sweep fs = { 0, 0, 0, 0 };
    for (long n = 0; n < max_tries && !fs.succeeded; n++) {
        fail_alloc fa = { -1, 0 };
        rs_allocator al = fail_alloc_hook(&fa);
        rs_ctx *c = NULL;
        fs.tries++;
        if (rs_ctx_create(&al, NULL, &c) != RS_OK) {
            fs.wrong++;
            break;
        }
        fa.countdown = n;
        int wrong = 0;
        rs_result r = fn(c, user, &wrong);
        if (r == RS_OK) fs.succeeded = 1;
        else if (r != RS_ERR_NOMEM || wrong) fs.wrong++;
        rs_ctx_free(c);
        if (fa.live != 0) fs.leaks++;
    }
    return fs;
}
