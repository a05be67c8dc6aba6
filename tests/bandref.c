/* The band reference (tests/bandref.h). */
#include "bandref.h"

#include <math.h>

void bandref_init(bandref_line *L, const double *x, const double *y, size_t n)
{
    L->x = x;
    L->y = y;
    L->n = n;
    L->s[0] = 0;
    for (size_t k = 1; k < n; k++) L->s[k] = L->s[k - 1] + hypot(x[k] - x[k - 1], y[k] - y[k - 1]);
}

static int dash_on(const rs__band *b, double s)
{
    if (!b->ndash) return 1;
    double per = 0;
    for (uint32_t j = 0; j < b->ndash; j++) per += b->dash[j];
    double m = fmod(s - b->phase, per);
    if (m < 0) m += per;
    double acc = 0;
    for (uint32_t j = 0; j < b->ndash; j++) {
        acc += b->dash[j];
        if (m < acc) return (j & 1) == 0;
    }
    return 0;
}

int bandref_in(const bandref_line *L, const rs__band *b, double x, double y)
{
    double best = INFINITY, bu = 0, blen = 0, bt = 0;
    size_t bk = 0;
    for (size_t k = 0; k + 1 < L->n; k++) {
        double ax = L->x[k], ay = L->y[k], dx = L->x[k + 1] - ax, dy = L->y[k + 1] - ay, len = hypot(dx, dy);
        double u = ((x - ax) * dx + (y - ay) * dy) / len;
        if (u < 0) u = 0;
        if (u > len) u = len;
        double qx = ax + u * dx / len, qy = ay + u * dy / len, d = hypot(x - qx, y - qy);
        if (d < best) {
            best = d;
            bk = k;
            bu = u;
            blen = len;
            bt = ((x - ax) * dy - (y - ay) * dx) / len;
        }
    }
    double s, t;
    if (bu > 0 && bu < blen) {
        s = L->s[bk] + bu;
        t = bt;
    } else {
        size_t j = bu <= 0 ? bk : bk + 1; /* the vertex */
        if (j == 0 || j == L->n - 1) return 0;
        double px = L->x[j] - L->x[j - 1], py = L->y[j] - L->y[j - 1], nx = L->x[j + 1] - L->x[j],
               ny = L->y[j + 1] - L->y[j];
        double lp = hypot(px, py), ln = hypot(nx, ny);
        /* left normals (dy, -dx) of both segments, summed */
        double sx = py / lp + ny / ln, sy = -px / lp - nx / ln;
        double side = (x - L->x[j]) * sx + (y - L->y[j]) * sy;
        s = L->s[j];
        t = side >= 0 ? best : -best;
    }
    return t >= b->t - 0.5 * b->w && t <= b->t + 0.5 * b->w && dash_on(b, s);
}

double bandref_cover(const bandref_line *L, const rs__band *b, double pix, uint32_t px, uint32_t py, int n)
{
    int in = 0;
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++)
            in += bandref_in(L, b, ((double)px + (i + 0.5) / n) * pix, ((double)py + (j + 0.5) / n) * pix);
    return (double)in / ((double)n * n);
}

double bandref_dist(const bandref_line *L, double x, double y)
{
    double best = INFINITY;
    for (size_t k = 0; k + 1 < L->n; k++) {
        double ax = L->x[k], ay = L->y[k], dx = L->x[k + 1] - ax, dy = L->y[k + 1] - ay, l2 = dx * dx + dy * dy;
        double u = ((x - ax) * dx + (y - ay) * dy) / l2;
        u = u < 0 ? 0 : (u > 1 ? 1 : u);
        best = fmin(best, hypot(x - ax - u * dx, y - ay - u * dy));
    }
    return best;
}
