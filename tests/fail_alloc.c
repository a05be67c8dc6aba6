#include "fail_alloc.h"

#include <stdlib.h>

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
