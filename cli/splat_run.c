/* The splat of `roadsplat` and `roadsplat render`: one prepared splatter,
 * the window cut into bands of rows that worker threads take in turn, each
 * with its own context. Every band is rendered by rs_splat_window, whose
 * output does not depend on how the image is cut, so any thread count gives
 * the same bytes. */
#include "png.h"
#include "gis.h"

#include <errno.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static unsigned default_threads(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : (n > 256 ? 256 : (unsigned)n);
}

int cli_splatter_prepare(rs_ctx *ctx, const cli_splat_input *in, const char *roads_path, cli_splat_args *s, int quiet,
                         rs_road_grid **grid, rs_splatter **out)
{
    /* The roads bar follows the grid build only. The splatter is made from
     * the grid with no callback of its own: its windows would call it from
     * the worker threads after the bar is gone (cli_splat_run reports the
     * splat's progress itself, under its lock). */
    cli_progress prog;
    rs_splat_options o = s->o;
    cli_progress_init(&prog, "roads", quiet);
    o.progress = cli_progress_cb;
    o.progress_user = &prog;
    rs_result r = rs_road_grid_build(ctx, in->dem, in->roads, &o, grid);
    cli_progress_done(&prog);
    o.progress = NULL;
    o.progress_user = NULL;
    if (!r) r = rs_splatter_create(ctx, in->dem, NULL, *grid, &o, out);
    char m[512];
    if (r) cli_error("%s: %s", roads_path, cli_lib_message(ctx, r, m, sizeof m));
    return r != RS_OK;
}

void cli_splat_job_init(cli_splat_job *job, const rs_splatter *sp, const cli_splat_args *s, int quiet)
{
    memset(job, 0, sizeof *job);
    job->s = sp;
    rs_splatter_size(sp, &job->w, &job->h);
    job->texels = s->o.texels ? s->o.texels : 8;
    job->threads = s->threads ? s->threads : default_threads();
    job->quiet = quiet;
}

typedef struct shared {
    cli_splat_job *job;
    cli_progress *prog;
    uint32_t band_rows, nbands, next, done_rows;
    int stop;
    rs_result err;
    char msg[256];
    pthread_mutex_t mu;
} shared;

/* One thread of a splat pass: its pass's shared state (shared or
 * png_shared) and its own stage profile. */
typedef struct worker {
    void *sh;
    rs_splat_profile prof;
} worker;

static double clock_ms(void *user)
{
    (void)user;
    return cli_now_ms();
}

static void *work(void *arg)
{
    worker *wk = arg;
    shared *sh = wk->sh;
    cli_splat_job *job = sh->job;
    rs_ctx *ctx = NULL;
    rs_result r = rs_ctx_create(NULL, NULL, &ctx);
    wk->prof.clock_ms = clock_ms;
    for (;;) {
        uint32_t b;
        pthread_mutex_lock(&sh->mu);
        if (r && !sh->err) {
            sh->err = r;
            snprintf(sh->msg, sizeof sh->msg, "%s", rs_strerror(r));
        }
        if (r) sh->stop = 1;
        b = sh->stop ? sh->nbands : sh->next;
        if (b < sh->nbands) sh->next++;
        pthread_mutex_unlock(&sh->mu);
        if (b >= sh->nbands) break;
        uint32_t y = b * sh->band_rows, rows = job->h - y < sh->band_rows ? job->h - y : sh->band_rows;
        if (job->layers) {
            /* the band's rows of each plane asked for */
            rs_splat_layers L = *job->layers;
            if (L.terrain) L.terrain += (size_t)y * L.terrain_stride;
            if (L.casing) L.casing += (size_t)y * L.casing_stride;
            if (L.surface) L.surface += (size_t)y * L.surface_stride;
            if (L.coverage) L.coverage += (size_t)y * L.coverage_stride;
            if (L.paint) L.paint += (size_t)y * L.paint_stride;
            if (L.normal) L.normal += (size_t)y * L.normal_stride;
            r = rs_splat_layers_window(ctx, job->s, NULL, job->x0, job->y0 + y, job->w, rows, &L, &wk->prof);
        } else
            r = rs_splat_window(ctx, job->s, job->x0, job->y0 + y, job->w, rows, job->rgba + (size_t)y * job->w * 4,
                                (size_t)job->w * 4, job->weight ? job->weight + (size_t)y * job->w : NULL, job->w,
                                &wk->prof);
        if (!r && job->nodata)
            cli_nodata_alpha(job->nodata, job->dem_w, job->dem_h, job->texels, job->x0, job->y0 + y, job->w, rows,
                             job->rgba + (size_t)y * job->w * 4, (size_t)job->w * 4);
        pthread_mutex_lock(&sh->mu);
        if (r && !sh->err) {
            sh->err = r;
            snprintf(sh->msg, sizeof sh->msg, "%s", rs_ctx_message(ctx)[0] ? rs_ctx_message(ctx) : rs_strerror(r));
        }
        if (!r) {
            sh->done_rows += rows;
            if (cli_progress_cb(sh->prog, sh->done_rows, job->h)) {
                sh->err = RS_ERR_CANCELLED;
                snprintf(sh->msg, sizeof sh->msg, "cancelled");
            }
        }
        if (sh->err) sh->stop = 1;
        pthread_mutex_unlock(&sh->mu);
        r = RS_OK;
    }
    rs_ctx_free(ctx);
    return NULL;
}

/* Run fn on n workers sharing sh: threads for workers 1..n-1, the calling
 * thread for worker 0, then their stage profiles summed into job. Returns
 * the number of threads that ran (job->threads_used), 0 when out of memory
 * (nothing ran). */
static unsigned run_workers(cli_splat_job *job, void *sh, unsigned n, void *(*fn)(void *))
{
    worker *wk = calloc(n, sizeof *wk);
    pthread_t *tid = calloc(n, sizeof *tid);
    unsigned started = 0, ran = 0;
    if (wk && tid) {
        for (unsigned i = 0; i < n; i++) wk[i].sh = sh;
        for (unsigned i = 1; i < n; i++) {
            if (pthread_create(&tid[i], NULL, fn, &wk[i]) != 0) break;
            started = i;
        }
        fn(&wk[0]);
        for (unsigned i = 1; i <= started; i++) pthread_join(tid[i], NULL);
        for (unsigned i = 0; i < n; i++) {
            job->profile.coverage_ms += wk[i].prof.coverage_ms;
            job->profile.surface_ms += wk[i].prof.surface_ms;
            job->profile.overlays_ms += wk[i].prof.overlays_ms;
            job->profile.composite_ms += wk[i].prof.composite_ms;
            job->profile.pixels += wk[i].prof.pixels;
            job->profile.road_pixels += wk[i].prof.road_pixels;
            job->profile.mark_tests += wk[i].prof.mark_tests;
            job->profile.mark_pixels += wk[i].prof.mark_pixels;
        }
        ran = job->threads_used = started + 1;
    }
    free(wk);
    free(tid);
    return ran;
}

int cli_splat_run(cli_splat_job *job)
{
    shared sh;
    cli_progress prog;
    memset(&sh, 0, sizeof sh);
    sh.job = job;
    cli_progress_init(&prog, "splat", job->quiet);
    sh.prog = &prog;
    uint32_t T = job->texels ? job->texels : 1;
    /* whole DEM-cell rows of at least 32 pixel rows: few re-scans of a row's
     * road cells, and enough bands to keep every thread busy */
    sh.band_rows = T * ((32 + T - 1) / T);
    unsigned n = job->threads ? job->threads : 1;
    while (sh.band_rows > T && (uint64_t)sh.band_rows * n * 4 > job->h) sh.band_rows -= T;
    sh.nbands = (uint32_t)(((uint64_t)job->h + sh.band_rows - 1) / sh.band_rows);
    if (n > sh.nbands) n = sh.nbands;
    pthread_mutex_init(&sh.mu, NULL);
    if (!run_workers(job, &sh, n, work)) {
        sh.err = RS_ERR_NOMEM;
        snprintf(sh.msg, sizeof sh.msg, "out of memory for %u threads", n);
    }
    pthread_mutex_destroy(&sh.mu);
    cli_progress_done(&prog);
    if (sh.err) {
        cli_error("%s", sh.msg);
        return 1;
    }
    return 0;
}

/* ---- the splat written as a PNG while it runs (cli/png.h) ------------------- */

typedef struct band_slot { /* a finished band waiting for the ones before it */
    uint8_t *data;
    size_t size, raw;
    uint32_t adler;
    int ready;
} band_slot;

typedef struct png_shared {
    cli_splat_job *job;
    const cli_png_layout *l;
    cli_png_writer wr;
    cli_progress *prog;
    const char *shown;
    band_slot *slots;
    uint32_t next;    /* next band to splat */
    uint32_t written; /* bands in the file */
    int writing;      /* a worker is writing bands into the file */
    int stop;
    char msg[256];
    double t0, splat_done;
    cli_png_run_stats st;
    pthread_mutex_t mu;
} png_shared;

/* The first error wins; called with the lock held. */
static void png_fail(png_shared *sh, const char *fmt, const char *a, const char *b)
{
    if (!sh->stop) snprintf(sh->msg, sizeof sh->msg, fmt, a, b);
    sh->stop = 1;
}

/* Write band `b` (piece p, or the slots that follow once it is in), with
 * the lock held on entry and exit; the lock is dropped around the I/O. */
static void png_write_from(png_shared *sh, const cli_png_piece *p)
{
    sh->writing = 1;
    cli_png_piece cur = *p;
    band_slot *s = NULL;
    for (;;) {
        pthread_mutex_unlock(&sh->mu);
        double t = cli_now_ms();
        int bad = cli_png_writer_band(&sh->wr, &cur);
        int e = errno;
        t = cli_now_ms() - t;
        if (s) {
            free(s->data);
            s->data = NULL;
        }
        pthread_mutex_lock(&sh->mu);
        sh->st.file_ms += t;
        if (bad) {
            png_fail(sh, "%s: write failed: %s", sh->shown, strerror(e ? e : EIO));
            break;
        }
        sh->written++;
        if (cli_progress_cb(sh->prog, sh->written, sh->l->nbands)) png_fail(sh, "%s%s", "cancelled", "");
        if (sh->stop || sh->written == sh->l->nbands || !sh->slots[sh->written].ready) break;
        s = &sh->slots[sh->written];
        cur.data = s->data;
        cur.size = s->size;
        cur.adler = s->adler;
        cur.raw = s->raw;
    }
    sh->writing = 0;
}

/* RGBA rows to RGB in place (row r at rows + r * stride). Four pixels at a
 * time where the byte order is known: four loads, then three stores that
 * end before the next group's first byte (12 (q + 1) <= 16 (q + 1)). */
static void rgba_to_rgb(uint8_t *rows, size_t stride, uint32_t w, uint32_t n)
{
    for (uint32_t r = 0; r < n; r++) {
        uint8_t *p = rows + (size_t)r * stride;
        size_t k = 0;
#if defined(__BYTE_ORDER__) && defined(__ORDER_LITTLE_ENDIAN__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
        for (; k + 4 <= w; k += 4) {
            uint32_t a, b, c, d;
            memcpy(&a, p + 4 * k, 4);
            memcpy(&b, p + 4 * k + 4, 4);
            memcpy(&c, p + 4 * k + 8, 4);
            memcpy(&d, p + 4 * k + 12, 4);
            uint32_t o0 = (a & 0xFFFFFFu) | b << 24, o1 = (b >> 8 & 0xFFFFu) | c << 16, o2 = (c >> 16 & 0xFFu) | d << 8;
            memcpy(p + 3 * k, &o0, 4);
            memcpy(p + 3 * k + 4, &o1, 4);
            memcpy(p + 3 * k + 8, &o2, 4);
        }
#endif
        for (; k < w; k++) {
            uint8_t px[3] = { p[4 * k], p[4 * k + 1], p[4 * k + 2] };
            memcpy(p + 3 * k, px, 3);
        }
    }
}

static void *png_work(void *arg)
{
    worker *wk = arg;
    png_shared *sh = wk->sh;
    cli_splat_job *job = sh->job;
    const cli_png_layout *l = sh->l;
    rs_ctx *ctx = NULL;
    rs_result r = rs_ctx_create(NULL, NULL, &ctx);
    cli_png_coder *coder = cli_png_coder_new(l);
    uint8_t *rgba = malloc((size_t)l->band_rows * job->w * 4);
    wk->prof.clock_ms = clock_ms;
    pthread_mutex_lock(&sh->mu);
    if (r) png_fail(sh, "%s%s", rs_strerror(r), "");
    else if (!coder || !rgba) png_fail(sh, "%s: %s", sh->shown, "out of memory");
    for (;;) {
        if (sh->stop || sh->next >= l->nbands) break;
        uint32_t b = sh->next++;
        pthread_mutex_unlock(&sh->mu);

        uint32_t y = b * l->band_rows, rows = job->h - y < l->band_rows ? job->h - y : l->band_rows;
        double t0 = cli_now_ms();
        r = rs_splat_window(ctx, job->s, job->x0, job->y0 + y, job->w, rows, rgba, (size_t)job->w * 4,
                            job->weight ? job->weight + (size_t)y * job->w : NULL, job->w, &wk->prof);
        if (!r && job->nodata)
            cli_nodata_alpha(job->nodata, job->dem_w, job->dem_h, job->texels, job->x0, job->y0 + y, job->w, rows,
                             rgba, (size_t)job->w * 4);
        double t1 = cli_now_ms(); /* the packing below is the PNG's */
        if (!r && l->channels == 3) rgba_to_rgb(rgba, (size_t)job->w * 4, job->w, rows);
        cli_png_piece p;
        int bad = !r && cli_png_coder_band(coder, b, rgba, (size_t)job->w * 4, &p);
        double t2 = cli_now_ms();

        pthread_mutex_lock(&sh->mu);
        sh->st.splat_cpu_ms += t1 - t0;
        sh->st.png_cpu_ms += t2 - t1;
        if (t1 - sh->t0 > sh->splat_done) sh->splat_done = t1 - sh->t0;
        if (r) {
            const char *m = rs_ctx_message(ctx);
            png_fail(sh, "%s%s", m[0] ? m : rs_strerror(r), "");
        } else if (bad) {
            png_fail(sh, "%s: %s", sh->shown, "compression failed");
        } else if (!sh->stop && b == sh->written && !sh->writing) {
            png_write_from(sh, &p); /* straight from the coder's buffer */
        } else if (!sh->stop) {
            band_slot *s = &sh->slots[b];
            s->data = malloc(p.size ? p.size : 1);
            if (!s->data) {
                png_fail(sh, "%s: %s", sh->shown, "out of memory");
            } else {
                memcpy(s->data, p.data, p.size);
                s->size = p.size;
                s->raw = p.raw;
                s->adler = p.adler;
                s->ready = 1; /* the writer takes it once the bands before are in */
            }
        }
    }
    if (coder) {
        uint64_t j[4];
        cli_png_coder_joins(coder, j);
        for (int i = 0; i < 4; i++) sh->st.joins[i] += j[i];
    }
    pthread_mutex_unlock(&sh->mu);
    free(rgba);
    cli_png_coder_free(coder);
    rs_ctx_free(ctx);
    return NULL;
}

int cli_splat_png_run(cli_splat_job *job, FILE *f, const char *shown, int level, cli_png_run_stats *st)
{
    cli_png_layout l;
    /* every pixel is opaque unless nodata is masked: RGB, a quarter less to
     * filter, compress and store (docs/packaging.md) */
    const int channels = job->alpha || job->nodata ? 4 : 3;
    if (cli_png_layout_init(&l, shown, job->w, job->h, channels, 8, level)) return 1;
    png_shared sh;
    cli_progress prog;
    memset(&sh, 0, sizeof sh);
    sh.job = job;
    sh.l = &l;
    sh.shown = shown;
    sh.prog = &prog;
    sh.t0 = cli_now_ms();
    cli_progress_init(&prog, "splat+write", job->quiet);
    if (cli_png_writer_begin(&sh.wr, f, &l)) {
        cli_error("%s: write failed: %s", shown, strerror(errno ? errno : EIO));
        return 1;
    }
    unsigned n = job->threads ? job->threads : 1;
    if (n > l.nbands) n = l.nbands;
    pthread_mutex_init(&sh.mu, NULL);
    sh.slots = calloc(l.nbands, sizeof *sh.slots);
    if (!sh.slots || !run_workers(job, &sh, n, png_work)) png_fail(&sh, "%s: %s", shown, "out of memory");
    if (!sh.stop && (sh.written != l.nbands || cli_png_writer_end(&sh.wr)))
        png_fail(&sh, "%s: write failed: %s", shown, strerror(errno ? errno : EIO));
    if (sh.slots)
        for (uint32_t b = 0; b < l.nbands; b++) free(sh.slots[b].data);
    free(sh.slots);
    pthread_mutex_destroy(&sh.mu);
    cli_progress_done(&prog);
    sh.st.splat_done_ms = sh.splat_done;
    sh.st.wall_ms = cli_now_ms() - sh.t0;
    if (st) *st = sh.st;
    if (sh.stop) {
        cli_error("%s", sh.msg);
        return 1;
    }
    return 0;
}
