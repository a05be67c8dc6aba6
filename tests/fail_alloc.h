/* A counting allocator for the library's allocator hook that fails the
 * allocation after `countdown` successful ones (<0: never) and counts live
 * blocks, so a test can fail every allocation in turn and check for leaks. */
#ifndef RS_TESTS_FAIL_ALLOC_H
#define RS_TESTS_FAIL_ALLOC_H
#include "roadsplat.h"

typedef struct fail_alloc {
    long countdown; /* fail when it reaches 0; <0 never */
    long live;      /* blocks allocated and not freed */
} fail_alloc;

/* An rs_allocator whose user is `f`. */
rs_allocator fail_alloc_hook(fail_alloc *f);
/* An rs_allocator that never fails and adds its allocation calls (malloc
 * and realloc) to *calls: a test of allocation-free calls. */
rs_allocator count_alloc_hook(size_t *calls);

/* An allocator that keeps 256 bytes of a known pattern after every
 * block and checks them when the block is freed or moved: a write past
 * the end of a block shows in a plain build (as `broken`), not only under
 * AddressSanitizer. Blocks keep malloc's 16-byte alignment. */
typedef struct guard_alloc {
    long live;   /* blocks allocated and not freed */
    long broken; /* blocks found with their guard overwritten */
} guard_alloc;
rs_allocator guard_alloc_hook(guard_alloc *g);

/* An allocator that keeps each block's size in a 16-byte header (malloc's
 * alignment kept): the live and peak bytes, the live blocks, the bytes
 * growing reallocs had to keep (their old sizes: the most they copy),
 * and, when `no_realloc` is set, every realloc refused. */
typedef struct size_alloc {
    size_t live, peak; /* bytes */
    long blocks;       /* blocks allocated and not freed */
    size_t kept;       /* old sizes of the reallocs that grew a block */
    int no_realloc;
} size_alloc;
rs_allocator size_alloc_hook(size_alloc *s);

/* One try of a failure sweep: make what is tested on context c, free it,
 * return the result; set *wrong when a failure left an object behind. */
typedef rs_result (*fail_try_fn)(rs_ctx *c, void *user, int *wrong);
typedef struct fail_sweep {
    int succeeded; /* a try succeeded (the sweep stops there) */
    long tries;    /* tries made, the successful one included */
    long wrong;    /* tries that failed other than with RS_ERR_NOMEM, or set *wrong */
    long leaks;    /* tries that left blocks allocated */
} fail_sweep;
/* Fail the first, second, ... allocation in turn: try n runs on a fresh
 * context whose allocator fails after n successful allocations, until a
 * try succeeds or max_tries were made. */
fail_sweep fail_alloc_sweep(long max_tries, fail_try_fn fn, void *user);
/* The usual checks of a sweep (tests/harness.h's CHECK): a try succeeded
 * after more than min_tries, none failed wrongly, none leaked. */
#define CHECK_SWEEP(fs, min_tries)                                                                                \
    do {                                                                                                         \
        CHECK((fs).succeeded);                                                                                   \
        CHECK((fs).tries > (min_tries));                                                                         \
        CHECK_EQ_INT((fs).wrong, 0);                                                                             \
        CHECK_EQ_INT((fs).leaks, 0);                                                                             \
    } while (0)
#endif
