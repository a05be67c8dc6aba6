/* citygen OUT.pgm OUT.txt: the city scene of the benchmarks
 * (sc_city_default, seed 1: a 400 x 350 DEM of 5 m cells, heights in
 * centimetres, and its roads) as a 16-bit PGM and a road file, for the CLI
 * benchmarks (tests/bench/tiles.sh: --cell-size 5 --z-scale 0.01). */
#include "scenes.h"

#include <stdio.h>

int main(int argc, char **argv)
{
    if (argc != 3) { fprintf(stderr, "usage: citygen OUT.pgm OUT.txt\n"); return 2; }
    sc_scene sc;
    if (sc_city_default(&sc, 1)) { fprintf(stderr, "citygen: out of memory\n"); return 1; }
    FILE *f = fopen(argv[1], "wb"), *t = fopen(argv[2], "w");
    if (!f || !t) { fprintf(stderr, "citygen: cannot write %s\n", f ? argv[2] : argv[1]); return 1; }
    fprintf(f, "P5\n%u %u\n65535\n", sc.w, sc.h);
    for (size_t i = 0, n = (size_t)sc.w * sc.h; i < n; i++) {
        float v = sc.z[i] < 0 ? 0 : sc.z[i] > 65535 ? 65535 : sc.z[i]; /* whole centimetres already */
        unsigned u = (unsigned)v;
        fputc((int)(u >> 8), f);
        fputc((int)(u & 0xFF), f);
    }
    for (size_t r = 0; r < sc.nroads; r++) {
        fprintf(t, "road r%zu width %.17g\n", r, sc.roads[r].width);
        for (size_t k = 0; k < sc.roads[r].n; k++)
            fprintf(t, "%.17g %.17g\n", sc.roads[r].xy[2 * k], sc.roads[r].xy[2 * k + 1]);
        fprintf(t, "end\n");
    }
    int bad = ferror(f) | ferror(t);
    bad |= fclose(f) != 0;
    bad |= fclose(t) != 0;
    sc_scene_free(&sc);
    if (bad) { fprintf(stderr, "citygen: write failed\n"); return 1; }
    return 0;
}
