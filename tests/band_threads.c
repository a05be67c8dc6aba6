/* Row bands on several threads (tests/band_threads.h). */
#include "band_threads.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>

typedef struct band_job {
    const rs_splatter *s;
    const rs_normal_options *nopt;
    uint8_t *px;
    uint32_t w, h, band, first, step;
    rs_result r;
} band_job;

static void *band_worker(void *arg)
{
    band_job *j = arg;
    rs_ctx *c = NULL;
    size_t ch = j->nopt ? 3 : 4, stride = (size_t)j->w * ch;
    j->r = rs_ctx_create(NULL, NULL, &c);
    for (uint32_t y = j->first * j->band; !j->r && y < j->h; y += j->step * j->band) {
        uint32_t hh = j->h - y < j->band ? j->h - y : j->band;
        uint8_t *out = j->px + (size_t)y * stride;
        j->r = j->nopt ? rs_normal_window(c, j->s, 0, y, j->w, hh, out, stride, j->nopt)
                       : rs_splat_window(c, j->s, 0, y, j->w, hh, out, stride, NULL, 0, NULL);
    }
    rs_ctx_free(c);
    return NULL;
}

int bt_threads_equal(const rs_splatter *s, const rs_normal_options *nopt, const uint8_t *ref, uint32_t w, uint32_t h,
                     uint32_t band, uint32_t n)
{
    enum { MAX_THREADS = 8 };
    size_t bytes = (size_t)w * h * (nopt ? 3 : 4);
    uint8_t *px = calloc(bytes ? bytes : 1, 1);
    if (!px || n == 0 || n > MAX_THREADS) {
        free(px);
        return 0;
    }
    band_job jobs[MAX_THREADS];
    pthread_t th[MAX_THREADS];
    int ok = 1;
    uint32_t started = 0;
    for (uint32_t k = 0; k < n; k++) {
        jobs[k] = (band_job){ s, nopt, px, w, h, band, k, n, RS_OK };
        if (pthread_create(&th[k], NULL, band_worker, &jobs[k]) != 0) {
            ok = 0;
            break;
        }
        started++;
    }
    for (uint32_t k = 0; k < started; k++) {
        pthread_join(th[k], NULL);
        ok &= jobs[k].r == RS_OK;
    }
    ok = ok && memcmp(px, ref, bytes) == 0;
    free(px);
    return ok;
}
