/* Progress bar on stderr. Quiet runs, redirected stderr and work that
 * finishes within a second print nothing; otherwise one line is redrawn
 * in place (only when the shown tenth of a percent changes) and finished
 * with a newline. */
#include "cli.h"

#include <unistd.h>

#define BAR_WIDTH 30

void cli_progress_init(cli_progress *p, const char *label, int quiet)
{
    p->label = label ? label : "";
    p->enabled = !quiet && isatty(2);
    p->start = cli_now_ms();
    p->shown = 0;
    p->last_permille = -1;
}

static void draw(cli_progress *p, int permille, double now)
{
    char bar[BAR_WIDTH + 1];
    int fill = permille * BAR_WIDTH / 1000;
    for (int i = 0; i < BAR_WIDTH; i++) bar[i] = i < fill ? '#' : '.';
    bar[BAR_WIDTH] = '\0';
    fprintf(stderr, "\r%s [%s] %5.1f%%  %.1f s ", p->label, bar, permille / 10.0, (now - p->start) / 1000.0);
    fflush(stderr);
    p->shown = 1;
    p->last_permille = permille;
}

int cli_progress_cb(void *user, uint64_t done, uint64_t total)
{
    cli_progress *p = user;
    if (!p || !p->enabled) return 0;
    double now = cli_now_ms();
    if (now - p->start < 1000.0) return 0;
    int permille = total ? (int)((double)(done >= total ? total : done) / (double)total * 1000.0) : 0;
    if (p->shown && permille == p->last_permille) return 0;
    draw(p, permille, now);
    return 0;
}

void cli_progress_done(cli_progress *p)
{
    if (!p || !p->shown) return;
    draw(p, 1000, cli_now_ms());
    fputc('\n', stderr);
    p->shown = 0;
}
