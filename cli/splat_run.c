/* The splat of `roadsplat` and `roadsplat render`: one prepared splatter,
 * the window cut into bands of rows that worker threads take in turn, each
 * with its own context. Every band is rendered by rs_splat_window, whose
 * output does not depend on how the image is cut, so any thread count gives
 * the same bytes. */
#include "cli.h"

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
    if (r) cli_error("%s: %s", roads_path, rs_ctx_message(ctx)[0] ? rs_ctx_message(ctx) : rs_strerror(r));
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

typedef struct worker {
    shared *sh;
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
        r = rs_splat_window(ctx, job->s, job->x0, job->y0 + y, job->w, rows, job->rgba + (size_t)y * job->w * 4,
                            (size_t)job->w * 4, job->weight ? job->weight + (size_t)y * job->w : NULL, job->w,
                            &wk->prof);
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
    worker *wk = calloc(n, sizeof *wk);
    pthread_t *tid = calloc(n, sizeof *tid);
    unsigned started = 0;
    if (wk && tid) {
        for (unsigned i = 0; i < n; i++) wk[i].sh = &sh;
        for (unsigned i = 1; i < n; i++) {
            if (pthread_create(&tid[i], NULL, work, &wk[i]) != 0) break;
            started = i;
        }
        work(&wk[0]); /* the calling thread works too */
        for (unsigned i = 1; i <= started; i++) pthread_join(tid[i], NULL);
        for (unsigned i = 0; i < n; i++) {
            job->profile.coverage_ms += wk[i].prof.coverage_ms;
            job->profile.surface_ms += wk[i].prof.surface_ms;
            job->profile.overlays_ms += wk[i].prof.overlays_ms;
            job->profile.composite_ms += wk[i].prof.composite_ms;
            job->profile.pixels += wk[i].prof.pixels;
            job->profile.road_pixels += wk[i].prof.road_pixels;
        }
        job->threads_used = started + 1;
    } else {
        sh.err = RS_ERR_NOMEM;
        snprintf(sh.msg, sizeof sh.msg, "out of memory for %u threads", n);
    }
    free(wk);
    free(tid);
    pthread_mutex_destroy(&sh.mu);
    cli_progress_done(&prog);
    if (sh.err) {
        cli_error("%s", sh.msg);
        return 1;
    }
    return 0;
}
