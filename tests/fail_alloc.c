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
