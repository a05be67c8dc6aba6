/* A caller allocator (rs_allocator) for the CLI that serves large blocks
 * from their own anonymous mappings, mostly in transparent huge pages. On
 * the benchmark VMs the first touch of a 4 KiB page costs ~10 us (PVM), of
 * a 2 MiB huge page 0.13 to 3.2 ms (cli/bigalloc.c has the layout and why).
 * Small blocks go to malloc. Thread-safe (a mutex guards the list of
 * mapped blocks), so every context of a run may share one. */
#ifndef RS_CLI_BIGALLOC_H
#define RS_CLI_BIGALLOC_H
#include <stddef.h>
#include "roadsplat.h"

typedef struct cli_bigalloc cli_bigalloc;

/* Blocks of at least `threshold` bytes are mapped (0: the default, 1
 * MiB); NULL when out of memory. */
cli_bigalloc *cli_bigalloc_create(size_t threshold);
/* Unmaps what is still mapped. */
void cli_bigalloc_destroy(cli_bigalloc *b);
/* The hook to pass to rs_ctx_create. */
rs_allocator cli_bigalloc_hook(cli_bigalloc *b);
/* For the CLI's own buffers: as malloc / free (NULL when out of memory). */
void *cli_big_malloc(cli_bigalloc *b, size_t size);
void cli_big_free(cli_bigalloc *b, void *p);

/* Faults in the whole pages of [p, p + n) in one call (Linux 5.14+
 * MADV_POPULATE_WRITE; elsewhere, or when refused, nothing): a fresh buffer
 * that read() is about to fill then takes no fault per 4 KiB page. */
void cli_prefault(void *p, size_t n);

/* What it did (for --stats): blocks and bytes mapped in all. */
typedef struct cli_bigalloc_stats {
    size_t mapped_blocks, mapped_bytes, fallback_blocks;
} cli_bigalloc_stats;
void cli_bigalloc_get_stats(cli_bigalloc *b, cli_bigalloc_stats *s);
#endif
