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
#endif
