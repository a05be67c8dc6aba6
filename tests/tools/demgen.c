/* demgen W OUT.pgm: a W x W fractal DEM (tests/scenes.c, seed 5, roughness
 * 0.5, the DEM of tests/bench/sparse.c) as a 16-bit binary PGM, for the CLI
 * benchmarks (tests/bench/write.sh). */
#include "scenes.h"

#include <stdio.h>
#include <stdlib.h>

int main(int argc, char **argv)
{
    if (argc != 3) { fprintf(stderr, "usage: demgen W OUT.pgm\n"); return 2; }
    long w = strtol(argv[1], NULL, 10);
    if (w < 2 || w > 16384) { fprintf(stderr, "demgen: W must be 2..16384\n"); return 2; }
    size_t n = (size_t)w * (size_t)w;
    float *z = malloc(n * sizeof *z);
    unsigned char *row = malloc((size_t)w * 2);
    FILE *f = fopen(argv[2], "wb");
    if (!z || !row || !f) { fprintf(stderr, "demgen: cannot write %s\n", argv[2]); return 1; }
    sc_dem_fractal(z, (uint32_t)w, (uint32_t)w, 5, 0.5); /* 0..65535 */
    fprintf(f, "P5\n%ld %ld\n65535\n", w, w);
    for (long y = 0; y < w; y++) {
        for (long x = 0; x < w; x++) {
            unsigned v = (unsigned)z[(size_t)y * (size_t)w + (size_t)x];
            row[2 * x] = (unsigned char)(v >> 8);
            row[2 * x + 1] = (unsigned char)(v & 0xFF);
        }
        fwrite(row, 1, (size_t)w * 2, f);
    }
    int bad = ferror(f) | fclose(f);
    free(z);
    free(row);
    return bad ? 1 : 0;
}
