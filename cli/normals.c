/* --normal-out (issue 16, docs/normals.md): the normal map of the run's
 * window, rendered by row bands on `threads` threads (rs_normal_window on
 * each band with its own context: the same bytes for any count) and encoded
 * as an RGB8 PNG into an open temporary, which the caller commits with the
 * other outputs. */
#include "cli.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

typedef struct nm_shared {
    const rs_splatter *s;
    const rs_normal_options *o;
    uint32_t x0, y0, w, h, band;
    uint8_t *rgb;
    pthread_mutex_t lock;
    uint32_t next;   /* next band to take */
    int failed;
    char msg[256];
} nm_shared;

static void *nm_worker(void *arg)
{
    nm_shared *sh = arg;
    rs_ctx *c = NULL;
    rs_result r = rs_ctx_create(NULL, NULL, &c);
    for (;;) {
        pthread_mutex_lock(&sh->lock);
        uint32_t y = sh->next;
        int stop = sh->failed || y >= sh->h || r;
        if (!stop) sh->next = sh->h - y < sh->band ? sh->h : y + sh->band;
        if (r && !sh->failed) {
            sh->failed = 1;
            snprintf(sh->msg, sizeof sh->msg, "%s", rs_strerror(r));
        }
        pthread_mutex_unlock(&sh->lock);
        if (stop) break;
        uint32_t rows = sh->h - y < sh->band ? sh->h - y : sh->band;
        rs_result e = rs_normal_window(c, sh->s, sh->x0, sh->y0 + y, sh->w, rows, sh->rgb + (size_t)y * sh->w * 3,
                                       (size_t)sh->w * 3, sh->o);
        if (e) {
            pthread_mutex_lock(&sh->lock);
            if (!sh->failed) snprintf(sh->msg, sizeof sh->msg, "%s", rs_ctx_message(c));
            sh->failed = 1;
            pthread_mutex_unlock(&sh->lock);
            break;
        }
    }
    rs_ctx_free(c);
    return NULL;
}

int cli_normal_png_check(const char *path)
{
    size_t n = strlen(path);
    if (n < 5 || strcasecmp(path + n - 4, ".png")) {
        cli_error("--normal-out: %s is not a .png (the normal map is an RGB8 PNG)", path);
        return 1;
    }
    return 0;
}

int cli_normal_rgb(const rs_splatter *s, const rs_normal_options *o, uint32_t x0, uint32_t y0, uint32_t w, uint32_t h,
                   unsigned threads, uint32_t band, uint8_t *rgb, char *msg, size_t msg_size)
{
    nm_shared sh;
    memset(&sh, 0, sizeof sh);
    sh.s = s, sh.o = o, sh.x0 = x0, sh.y0 = y0, sh.w = w, sh.h = h, sh.rgb = rgb;
    sh.band = band ? band : 1;
    pthread_mutex_init(&sh.lock, NULL);
    if (threads < 1) threads = 1;
    if (threads > 64) threads = 64;
    pthread_t t[64];
    unsigned started = 0;
    /* no more threads than bands */
    for (unsigned k = 1; k < threads && (size_t)k * sh.band < h; k++, started++)
        if (pthread_create(&t[k - 1], NULL, nm_worker, &sh)) break;
    nm_worker(&sh);
    for (unsigned k = 0; k < started; k++) pthread_join(t[k], NULL);
    pthread_mutex_destroy(&sh.lock);
    if (sh.failed) snprintf(msg, msg_size, "%s", sh.msg);
    return sh.failed;
}

int cli_normal_png(const rs_splatter *s, const rs_normal_options *o, uint32_t x0, uint32_t y0, uint32_t w,
                   uint32_t h, unsigned threads, int png_level, FILE *f, const char *path)
{
    uint8_t *rgb = malloc((size_t)w * h * 3);
    if (!rgb) {
        cli_error("%s: out of memory for a %u x %u image", path, w, h);
        return 1;
    }
    char msg[256];
    int rc = 0;
    if (cli_normal_rgb(s, o, x0, y0, w, h, threads, 64, rgb, msg, sizeof msg)) {
        cli_error("%s: %s", path, msg);
        rc = 1;
    } else {
        cli_png_image img = { w, h, 3, 8, rgb };
        cli_png_options po = { png_level, NULL, NULL, 0 };
        rc = cli_png_encode(f, path, &img, &po);
    }
    free(rgb);
    return rc;
}
