/* The PNG writer's band encoder (cli/png.c) and the splat that writes its
 * PNG while it runs (cli/splat_run.c). docs/packaging.md has the design and
 * the measurements behind it.
 *
 * The image is cut into bands of rows at places that depend only on its
 * layout (width, channels, bits), never on the thread count. Each band is
 * filtered and compressed on its own into a run of deflate blocks that ends
 * on a byte boundary, so the bands can be compressed in any order on any
 * thread and their pieces simply follow each other in the one zlib stream
 * PNG allows: the file is the same bytes however many threads made it. */
#ifndef ROADSPLAT_CLI_PNG_H
#define ROADSPLAT_CLI_PNG_H

#include "cli.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cli_png_layout {
    uint32_t width, height;
    int channels, bits, level; /* level: 0..CLI_PNG_LEVEL_MAX */
    size_t row_bytes;          /* unfiltered bytes per row */
    uint32_t band_rows, nbands;
    int isal; /* level 1 by ISA-L's igzip at its level 0 (builds with RS_WITH_ISAL), else libdeflate */
} cli_png_layout;

/* 0, or 1 after a message naming `shown` (a layout PNG cannot hold, a bad
 * level, or an image too large for this machine). level -1: the default. */
int cli_png_layout_init(cli_png_layout *l, const char *shown, uint32_t w, uint32_t h, int channels, int bits,
                        int level);

/* One band's part of the IDAT data: the zlib header in band 0, deflate
 * blocks, the last band's blocks ending the stream (the writer appends the
 * Adler-32). `data` belongs to the coder and lives until its next band. */
typedef struct cli_png_piece {
    const uint8_t *data;
    size_t size;
    uint32_t adler; /* Adler-32 of the band's filtered bytes */
    size_t raw;     /* how many filtered bytes */
} cli_png_piece;

/* Per-thread state: the compressor and the band's buffers. */
typedef struct cli_png_coder cli_png_coder;
cli_png_coder *cli_png_coder_new(const cli_png_layout *l); /* NULL: out of memory */
void cli_png_coder_free(cli_png_coder *c);
/* Filter and compress band `band`: its rows (band_rows, fewer in the last
 * band) top first, `stride` bytes apart, 16-bit samples in native order.
 * 0, or 1 when compression failed (no message). */
int cli_png_coder_band(cli_png_coder *c, uint32_t band, const void *rows, size_t stride, cli_png_piece *out);
/* How the coder's libdeflate pieces so far were made joinable: [0] one
 * stored block, [1] one block whose end was found from its end-of-block
 * code, [2] decoded by zlib's inflate (several blocks, a fixed-code block,
 * or an ambiguous end); the last piece of an image needs none and is not
 * counted. [3]: bands compressed by ISA-L, whose full flush ends them on a
 * byte boundary itself. */
void cli_png_coder_joins(const cli_png_coder *c, uint64_t joins[4]);

/* The file: signature and IHDR, then every band's piece in band order
 * (IDAT chunks), then IEND. Each returns 0, or 1 with errno set. */
typedef struct cli_png_writer {
    FILE *f;
    const cli_png_layout *l;
    uint32_t next;  /* bands written */
    uint32_t adler; /* of the filtered bytes written so far */
    uint64_t bytes, synced; /* file size so far; offset handed to the kernel's writeback */
} cli_png_writer;
int cli_png_writer_begin(cli_png_writer *w, FILE *f, const cli_png_layout *l);
int cli_png_writer_band(cli_png_writer *w, const cli_png_piece *p);
int cli_png_writer_end(cli_png_writer *w);

/* The splat of job's window written as a PNG into f (not flushed) while it
 * runs: every worker splats a band of rows into its own buffer, filters and
 * compresses it, and whoever finishes the band next in the file writes it
 * (and the finished bands after it). No whole-image buffer exists. One
 * progress bar ("splat+write") covers both. job->rgba is not used;
 * job->weight (w*h, may be NULL) is filled as by cli_splat_run. Prints the
 * error (naming `shown` for PNG errors) and returns 1 on failure. */
typedef struct cli_png_run_stats {
    double splat_cpu_ms; /* time in rs_splat_window, summed over threads */
    double png_cpu_ms;   /* filtering and compression, summed over threads */
    double file_ms;      /* writing the chunks into f, summed */
    double splat_done_ms; /* wall time from the start until every pixel was splatted */
    double wall_ms;       /* wall time of the whole run */
    uint64_t joins[4];    /* cli_png_coder_joins summed over the threads */
} cli_png_run_stats;
int cli_splat_png_run(cli_splat_job *job, FILE *f, const char *shown, int level, cli_png_run_stats *st);

#ifdef __cplusplus
}
#endif
#endif
