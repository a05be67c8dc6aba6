/* Huge-page allocator of the CLI (cli/bigalloc.h).
 *
 * - A block of at least the threshold (1 MiB) gets its own anonymous
 *   mapping: its first 256 KiB in ordinary pages, the rest starting on a
 *   2 MiB boundary, a whole number of 2 MiB long and advised MADV_HUGEPAGE,
 *   so the kernel backs it with transparent huge pages (THP mode
 *   "madvise", the Debian default, or "always"; with THP off it is an
 *   ordinary mapping, as glibc's malloc makes for blocks this size).
 * - Why the small-page head: on the benchmark VMs a 4 KiB first touch
 *   costs ~10 us, a 2 MiB huge page 0.13 ms when the host still backs the
 *   memory but ~3.2 ms when the host has taken it back (free page
 *   reporting hands 2 MiB free blocks to the host; which kind the kernel
 *   gives out is luck). A block used only a little (the worst-case node
 *   pool of a coarse mesh, the stack) then costs a few small pages instead
 *   of a possibly cold huge page; a block used a lot gets huge pages for
 *   all but its head. Pages never touched cost nothing, so a pool sized
 *   for the worst case is free until used.
 * - Smaller blocks come from malloc with a 16-byte header holding their
 *   size (realloc into a mapped block must know how much to copy).
 * - Mapped blocks are found by address in a short list under a mutex
 *   (a run maps a few dozen); when the list is full, blocks fall back to
 *   malloc. */
#define _DEFAULT_SOURCE 1 /* MAP_ANONYMOUS, MADV_HUGEPAGE */
#include "bigalloc.h"

#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#define HUGE_PAGE ((size_t)2 << 20)
#define DEFAULT_THRESHOLD ((size_t)1 << 20)
#define HEAD ((size_t)256 << 10)
#define MAX_BLOCKS 256
#define HDR 16 /* keeps malloc's 16-byte alignment on 64-bit targets */

typedef struct mapped {
    char *p;
    size_t size, len; /* requested, mapped */
} mapped;

struct cli_bigalloc {
    pthread_mutex_t lock;
    size_t threshold, head, page;
    size_t n;
    mapped blk[MAX_BLOCKS];
    cli_bigalloc_stats st;
};

cli_bigalloc *cli_bigalloc_create(size_t threshold)
{
    cli_bigalloc *b = malloc(sizeof *b);
    if (!b) return NULL;
    memset(b, 0, sizeof *b);
    if (pthread_mutex_init(&b->lock, NULL) != 0) { free(b); return NULL; }
    b->threshold = threshold ? threshold : DEFAULT_THRESHOLD;
    long pg = sysconf(_SC_PAGESIZE);
    b->page = pg > 0 && (pg & (pg - 1)) == 0 ? (size_t)pg : 4096;
    b->head = HEAD & ~(b->page - 1);
    return b;
}

void cli_bigalloc_destroy(cli_bigalloc *b)
{
    if (!b) return;
    for (size_t k = 0; k < b->n; k++) munmap(b->blk[k].p, b->blk[k].len);
    pthread_mutex_destroy(&b->lock);
    free(b);
}

void cli_bigalloc_get_stats(cli_bigalloc *b, cli_bigalloc_stats *s)
{
    pthread_mutex_lock(&b->lock);
    *s = b->st;
    pthread_mutex_unlock(&b->lock);
}

/* A mapping of head + tail bytes (tail a multiple of 2 MiB) whose tail
 * starts on a 2 MiB boundary and is advised into huge pages: map 2 MiB
 * more and trim both ends. */
static char *map_block_at(size_t head, size_t tail)
{
    size_t len = head + tail;
    if (len > SIZE_MAX - HUGE_PAGE) return NULL;
    char *m = mmap(NULL, len + HUGE_PAGE, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (m == MAP_FAILED) return NULL;
    uintptr_t a = ((uintptr_t)m + head + HUGE_PAGE - 1) & ~(uintptr_t)(HUGE_PAGE - 1);
    char *p = (char *)(a - head);
    size_t lead = (size_t)(p - m);
    if (lead) munmap(m, lead);
    if (HUGE_PAGE - lead) munmap(p + len, HUGE_PAGE - lead);
#ifdef MADV_HUGEPAGE
    if (tail) (void)madvise(p + head, tail, MADV_HUGEPAGE); /* a hint: refused without THP */
#endif
    return p;
}

/* A mapped block of `size` bytes, registered; NULL when mmap fails or the
 * list is full (the caller falls back to malloc). */
static void *map_block(cli_bigalloc *b, size_t size)
{
    /* the head is whole small pages (the mapping's edges must be) */
    size_t head = size > SIZE_MAX - b->page ? b->head : (size + b->page - 1) & ~(b->page - 1);
    if (head > b->head) head = b->head;
    size_t rest = size > head ? size - head : 0;
    if (rest > SIZE_MAX - HUGE_PAGE) return NULL;
    size_t tail = (rest + HUGE_PAGE - 1) & ~(HUGE_PAGE - 1), len = head + tail;
    char *p = map_block_at(head, tail);
    if (!p) return NULL;
    pthread_mutex_lock(&b->lock);
    int ok = b->n < MAX_BLOCKS;
    if (ok) {
        b->blk[b->n].p = p;
        b->blk[b->n].size = size;
        b->blk[b->n].len = len;
        b->n++;
        b->st.mapped_blocks++;
        b->st.mapped_bytes += len;
    } else b->st.fallback_blocks++;
    pthread_mutex_unlock(&b->lock);
    if (!ok) { munmap(p, len); return NULL; }
    return p;
}

/* Index of mapped block p, or -1 (a malloc'ed block). Caller holds the lock. */
static long find(const cli_bigalloc *b, const void *p)
{
    for (size_t k = 0; k < b->n; k++)
        if (b->blk[k].p == (const char *)p) return (long)k;
    return -1;
}

static void *small_malloc(size_t size)
{
    if (size > SIZE_MAX - HDR) return NULL;
    char *m = malloc(size + HDR);
    if (!m) return NULL;
    memcpy(m, &size, sizeof size);
    return m + HDR;
}

static size_t small_size(const void *p)
{
    size_t s;
    memcpy(&s, (const char *)p - HDR, sizeof s);
    return s;
}

void *cli_big_malloc(cli_bigalloc *b, size_t size)
{
    if (size >= b->threshold) {
        void *p = map_block(b, size);
        if (p) return p;
    }
    return small_malloc(size);
}

void cli_big_free(cli_bigalloc *b, void *p)
{
    if (!p) return;
    pthread_mutex_lock(&b->lock);
    long k = find(b, p);
    mapped m = { NULL, 0, 0 };
    if (k >= 0) {
        m = b->blk[k];
        b->blk[k] = b->blk[--b->n];
    }
    pthread_mutex_unlock(&b->lock);
    if (k >= 0) munmap(m.p, m.len);
    else free((char *)p - HDR);
}

static void *big_realloc(cli_bigalloc *b, void *p, size_t size)
{
    if (!p) return cli_big_malloc(b, size);
    size_t old;
    pthread_mutex_lock(&b->lock);
    long k = find(b, p);
    if (k >= 0 && size <= b->blk[k].len) { /* fits the mapping: stays */
        b->blk[k].size = size;
        pthread_mutex_unlock(&b->lock);
        return p;
    }
    old = k >= 0 ? b->blk[k].size : small_size(p);
    pthread_mutex_unlock(&b->lock);
    if (k < 0 && size < b->threshold) { /* small stays small */
        if (size > SIZE_MAX - HDR) return NULL;
        char *m = realloc((char *)p - HDR, size + HDR);
        if (!m) return NULL;
        memcpy(m, &size, sizeof size);
        return m + HDR;
    }
    void *q = cli_big_malloc(b, size);
    if (!q) return NULL;
    memcpy(q, p, old < size ? old : size);
    cli_big_free(b, p);
    return q;
}

static void *hook_malloc(void *user, size_t size) { return cli_big_malloc(user, size); }
static void *hook_realloc(void *user, void *p, size_t size) { return big_realloc(user, p, size); }
static void hook_free(void *user, void *p) { cli_big_free(user, p); }

rs_allocator cli_bigalloc_hook(cli_bigalloc *b)
{
    rs_allocator a;
    a.malloc_fn = hook_malloc;
    a.realloc_fn = hook_realloc;
    a.free_fn = hook_free;
    a.user = b;
    return a;
}

void cli_prefault(void *p, size_t n)
{
#ifdef MADV_POPULATE_WRITE
    long ps = sysconf(_SC_PAGESIZE);
    if (ps <= 0 || !p) return;
    uintptr_t a = ((uintptr_t)p + (uintptr_t)ps - 1) & ~((uintptr_t)ps - 1), e = ((uintptr_t)p + n) & ~((uintptr_t)ps - 1);
    if (e > a) (void)madvise((void *)a, e - a, MADV_POPULATE_WRITE);
#else
    (void)p;
    (void)n;
#endif
}
