/* Generates the default road-marking atlas (issue 14, docs/markings.md)
 * from vector shapes: polygons, strokes (capsules) and rings, drawn in each
 * sprite's own frame in metres and rasterised with 8x8 supersampling.
 *
 *   atlasgen lib/input/atlas_default.c [atlas.png atlas-index.txt]
 *
 * writes the atlas as C source (alpha run-length coded, white markings, and
 * the index text) and optionally as an RGBA PNG plus its index file, the
 * form `roadsplat --atlas IMG --atlas-index FILE` reads. Sprite frame:
 * x across the road, 0 at the sprite's left edge (left of the direction of
 * travel), y along it, 0 at the top (the way the road runs). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PPM 20.0      /* atlas pixels per metre */
#define PI 3.14159265358979323846
#define ATLAS_W 256
#define ATLAS_H 512
#define PAD 2         /* transparent pixels around every sprite */
#define MAXP 64
#define MAXS 64

typedef struct shape {
    int kind; /* 0 polygon, 1 capsule, 2 ring */
    int n;
    double x[MAXP], y[MAXP];
    double r, r2; /* capsule half width; ring inner/outer radius */
} shape;

typedef struct sprite {
    const char *name;
    double length, width; /* metres: along (y), across (x) */
    shape s[MAXS];
    int ns;
    int px, py, pw, ph; /* placement */
} sprite;

static sprite sp[32];
static int nsp;
static uint8_t atlas[ATLAS_H][ATLAS_W];

static sprite *begin(const char *name, double length, double width)
{
    sprite *p = &sp[nsp++];
    memset(p, 0, sizeof *p);
    p->name = name;
    p->length = length;
    p->width = width;
    return p;
}

static void poly(sprite *p, int n, const double *xy)
{
    shape *s = &p->s[p->ns++];
    s->kind = 0;
    s->n = n;
    for (int i = 0; i < n; i++) {
        s->x[i] = xy[2 * i];
        s->y[i] = xy[2 * i + 1];
    }
}

static void rect(sprite *p, double x0, double y0, double x1, double y1)
{
    double v[8] = { x0, y0, x1, y0, x1, y1, x0, y1 };
    poly(p, 4, v);
}

static void stroke(sprite *p, double x0, double y0, double x1, double y1, double hw)
{
    shape *s = &p->s[p->ns++];
    s->kind = 1;
    s->n = 2;
    s->x[0] = x0; s->y[0] = y0; s->x[1] = x1; s->y[1] = y1;
    s->r = hw;
}

static void ring(sprite *p, double cx, double cy, double r0, double r1)
{
    shape *s = &p->s[p->ns++];
    s->kind = 2;
    s->x[0] = cx; s->y[0] = cy;
    s->r = r0; s->r2 = r1;
}

static int inside(const shape *s, double x, double y)
{
    if (s->kind == 0) {
        int c = 0;
        for (int i = 0, j = s->n - 1; i < s->n; j = i++)
            if ((s->y[i] > y) != (s->y[j] > y) &&
                x < (s->x[j] - s->x[i]) * (y - s->y[i]) / (s->y[j] - s->y[i]) + s->x[i])
                c = !c;
        return c;
    }
    if (s->kind == 1) {
        double dx = s->x[1] - s->x[0], dy = s->y[1] - s->y[0], l2 = dx * dx + dy * dy;
        double t = l2 > 0 ? ((x - s->x[0]) * dx + (y - s->y[0]) * dy) / l2 : 0;
        if (t < 0) t = 0;
        if (t > 1) t = 1;
        double ex = x - s->x[0] - t * dx, ey = y - s->y[0] - t * dy;
        return ex * ex + ey * ey <= s->r * s->r;
    }
    double d = hypot(x - s->x[0], y - s->y[0]);
    return d >= s->r && d <= s->r2;
}

/* A stroke-font word across the sprite: letters on a 4 x 6 grid, drawn as
 * polylines of capsules, elongated along the road. */
static const char *glyph(char c)
{
    switch (c) {
    case 'B': return "0,0 0,6|0,0 3,0 4,1 4,2 3,3 0,3|3,3 4,4 4,5 3,6 0,6";
    case 'U': return "0,0 0,5 1,6 3,6 4,5 4,0";
    case 'S': return "4,1 3,0 1,0 0,1 0,2 1,3 3,3 4,4 4,5 3,6 1,6 0,5";
    case 'T': return "0,0 4,0|2,0 2,6";
    case 'O': return "1,0 3,0 4,1 4,5 3,6 1,6 0,5 0,1 1,0";
    case 'P': return "0,6 0,0 3,0 4,1 4,2 3,3 0,3";
    case 'L': return "0,0 0,6 4,6";
    case 'W': return "0,0 1,6 2,3 3,6 4,0";
    default: return "";
    }
}

static void word(sprite *p, const char *w)
{
    int n = (int)strlen(w);
    double margin = 0.1, cell = (p->width - 2 * margin) / n;
    double hw = 0.06, gx = (cell - 2 * hw - 0.08) / 4, gy = (p->length - 2 * margin - 2 * hw) / 6;
    for (int k = 0; k < n; k++) {
        double ox = margin + k * cell + hw + 0.04, oy = margin + hw;
        const char *g = glyph(w[k]);
        while (*g) {
            double px = 0, py = 0;
            int first = 1;
            while (*g && *g != '|') {
                int a, b, used;
                if (sscanf(g, "%d,%d%n", &a, &b, &used) != 2) break;
                g += used;
                while (*g == ' ') g++;
                double x = ox + a * gx, y = oy + b * gy;
                if (!first) stroke(p, px, py, x, y, hw);
                px = x; py = y;
                first = 0;
            }
            if (*g == '|') g++;
        }
    }
}

/* Arrow parts: shaft centre x, shaft half width 0.09 m, heads as triangles. */
#define SH 0.09
static void head_up(sprite *p, double cx, double tip, double hw, double len)
{
    double v[6] = { cx, tip, cx + hw, tip + len, cx - hw, tip + len };
    poly(p, 3, v);
}
static void head_side(sprite *p, double tipx, double cy, double dir, double hw, double len)
{
    double v[6] = { tipx, cy, tipx + dir * len, cy - hw, tipx + dir * len, cy + hw };
    poly(p, 3, v);
}

/* Left-turning arm from the shaft at x=sx to a head whose tip is at x=tipx. */
static void left_arm(sprite *p, double sx, double y, double tipx, double dir)
{
    double hl = 0.55;
    rect(p, dir < 0 ? tipx + hl - 0.01 : sx - SH, y - SH, dir < 0 ? sx + SH : tipx - hl + 0.01, y + SH);
    head_side(p, tipx, y, -dir, 0.35, hl);
}

static void build(void)
{
    sprite *p;
    p = begin("arrow_straight", 5.0, 0.8);
    head_up(p, 0.4, 0.02, 0.38, 1.4);
    rect(p, 0.4 - SH, 1.41, 0.4 + SH, 4.98);

    p = begin("arrow_left", 5.0, 1.4);
    rect(p, 1.0 - SH, 1.2 - SH, 1.0 + SH, 4.98);
    left_arm(p, 1.0, 1.2, 0.02, -1);

    p = begin("arrow_right", 5.0, 1.4);
    rect(p, 0.4 - SH, 1.2 - SH, 0.4 + SH, 4.98);
    left_arm(p, 0.4, 1.2, 1.38, 1);

    p = begin("arrow_straight_left", 5.0, 1.6);
    head_up(p, 1.2, 0.02, 0.38, 1.4);
    rect(p, 1.2 - SH, 1.41, 1.2 + SH, 4.98);
    left_arm(p, 1.2, 2.4, 0.02, -1);

    p = begin("arrow_straight_right", 5.0, 1.6);
    head_up(p, 0.4, 0.02, 0.38, 1.4);
    rect(p, 0.4 - SH, 1.41, 0.4 + SH, 4.98);
    left_arm(p, 0.4, 2.4, 1.58, 1);

    p = begin("arrow_uturn", 5.0, 1.6);
    /* up the right-hand shaft, over a half ring, down to a head on the left */
    rect(p, 1.25 - SH, 1.0, 1.25 + SH, 4.98);
    for (int k = 0; k < 12; k++) {
        double a0 = PI * k / 12, a1 = PI * (k + 1) / 12, r = 0.475, cx = 0.775, cy = 1.0;
        stroke(p, cx + r * cos(a0), cy - r * sin(a0), cx + r * cos(a1), cy - r * sin(a1), SH);
    }
    rect(p, 0.3 - SH, 1.0, 0.3 + SH, 2.4);
    {
        double v[6] = { 0.3, 3.2, 0.3 + 0.3, 2.4, 0.3 - 0.3, 2.4 };
        poly(p, 3, v);
    }

    p = begin("stop_line", 0.5, 3.5);
    rect(p, 0, 0, 3.5, 0.5);

    p = begin("give_way_line", 0.5, 3.5);
    for (double x = 0; x < 3.49; x += 0.75) rect(p, x, 0, x + 0.5 > 3.5 ? 3.5 : x + 0.5, 0.5);

    p = begin("give_way_triangles", 0.6, 3.5);
    for (int k = 0; k < 7; k++) {
        /* apexes towards the approaching driver (down the sprite) */
        double x0 = 0.5 * k, v[6] = { x0 + 0.02, 0, x0 + 0.48, 0, x0 + 0.25, 0.6 };
        poly(p, 3, v);
    }

    p = begin("give_way_triangle", 5.0, 1.5);
    {
        double ax = 0.75, ay = 4.9, lx = 0.05, ly = 0.1, rx = 1.45, ry = 0.1, hw = 0.08;
        stroke(p, lx + hw, ly + hw, rx - hw, ry + hw, hw);
        stroke(p, rx - hw, ry + hw, ax, ay - hw, hw);
        stroke(p, ax, ay - hw, lx + hw, ly + hw, hw);
    }

    p = begin("zebra", 4.0, 6.0);
    for (int k = 0; k < 6; k++) rect(p, 0.25 + k * 1.0, 0, 0.75 + k * 1.0, 4.0);

    p = begin("cycle", 1.6, 0.9);
    ring(p, 0.45, 0.4, 0.24, 0.32);
    ring(p, 0.45, 1.2, 0.24, 0.32);
    stroke(p, 0.45, 0.4, 0.3, 0.8, 0.04);
    stroke(p, 0.3, 0.8, 0.45, 1.2, 0.04);
    stroke(p, 0.45, 0.4, 0.62, 0.9, 0.04);
    stroke(p, 0.62, 0.9, 0.3, 0.8, 0.04);
    stroke(p, 0.62, 0.9, 0.45, 1.2, 0.04);
    stroke(p, 0.2, 0.55, 0.75, 0.55, 0.04);

    p = begin("word_bus", 2.5, 1.5);
    word(p, "BUS");
    p = begin("word_stop", 2.5, 2.0);
    word(p, "STOP");
    p = begin("word_slow", 2.5, 2.0);
    word(p, "SLOW");

    /* single elements that the automatic markings repeat at their standard
     * size across any road (docs/road-format.md "Marking elements") */
    p = begin("give_way_block", 0.5, 0.5); /* RMS Wartelinie block */
    rect(p, 0, 0, 0.5, 0.5);
    p = begin("zebra_bar", 4.0, 0.5); /* RMS Fussgaengerueberweg bar */
    rect(p, 0, 0, 0.5, 4.0);
    p = begin("arrow_uturn_right", 5.0, 1.6); /* arrow_uturn mirrored: left-hand traffic */
    rect(p, 1.6 - 1.25 - SH, 1.0, 1.6 - 1.25 + SH, 4.98);
    for (int k = 0; k < 12; k++) {
        double a0 = PI * k / 12, a1 = PI * (k + 1) / 12, r = 0.475, cx = 1.6 - 0.775, cy = 1.0;
        stroke(p, cx - r * cos(a0), cy - r * sin(a0), cx - r * cos(a1), cy - r * sin(a1), SH);
    }
    rect(p, 1.3 - SH, 1.0, 1.3 + SH, 2.4);
    {
        double v[6] = { 1.3, 3.2, 1.3 - 0.3, 2.4, 1.3 + 0.3, 2.4 };
        poly(p, 3, v);
    }
    p = begin("yield_tooth", 0.6858, 0.4572); /* MUTCD 3B.16: 18 in base, 27 in high */
    {
        double v[6] = { 0, 0, 0.4572, 0, 0.2286, 0.6858 };
        poly(p, 3, v);
    }
}

static void raster(sprite *p)
{
    const int SS = 8;
    for (int j = 0; j < p->ph; j++)
        for (int i = 0; i < p->pw; i++) {
            int hits = 0;
            for (int b = 0; b < SS; b++)
                for (int a = 0; a < SS; a++) {
                    double x = (i + (a + 0.5) / SS) * p->width / p->pw;
                    double y = (j + (b + 0.5) / SS) * p->length / p->ph;
                    for (int k = 0; k < p->ns; k++)
                        if (inside(&p->s[k], x, y)) { hits++; break; }
                }
            atlas[p->py + j][p->px + i] = (uint8_t)((hits * 255 + SS * SS / 2) / (SS * SS));
        }
}

/* Shelf packing in the order given. */
static int pack(void)
{
    int x = 0, y = 0, shelf = 0;
    for (int k = 0; k < nsp; k++) {
        sprite *p = &sp[k];
        p->pw = (int)lround(p->width * PPM);
        p->ph = (int)lround(p->length * PPM);
        if (x + p->pw + 2 * PAD > ATLAS_W) { x = 0; y += shelf; shelf = 0; }
        p->px = x + PAD;
        p->py = y + PAD;
        x += p->pw + 2 * PAD;
        if (p->ph + 2 * PAD > shelf) shelf = p->ph + 2 * PAD;
        if (y + p->ph + 2 * PAD > ATLAS_H) return -1;
    }
    return y + shelf;
}

static void index_text(char *out, size_t cap)
{
    size_t at = 0;
    for (int k = 0; k < nsp; k++)
        at += (size_t)snprintf(out + at, cap - at, "%s %d %d %d %d %g %g\n", sp[k].name, sp[k].px, sp[k].py, sp[k].pw,
                               sp[k].ph, sp[k].length, sp[k].width);
}

/* --- a stored (uncompressed) PNG ------------------------------------------ */
static uint32_t crc_table[256];
static uint32_t crc(uint32_t c, const uint8_t *b, size_t n)
{
    c ^= 0xFFFFFFFFu;
    for (size_t i = 0; i < n; i++) c = crc_table[(c ^ b[i]) & 0xFF] ^ (c >> 8);
    return c ^ 0xFFFFFFFFu;
}
static void be32(uint8_t *p, uint32_t v) { p[0] = (uint8_t)(v >> 24); p[1] = (uint8_t)(v >> 16); p[2] = (uint8_t)(v >> 8); p[3] = (uint8_t)v; }
static void chunk(FILE *f, const char *type, const uint8_t *d, size_t n)
{
    uint8_t h[8];
    be32(h, (uint32_t)n);
    memcpy(h + 4, type, 4);
    fwrite(h, 1, 8, f);
    if (n) fwrite(d, 1, n, f);
    uint32_t c = crc(crc(0, (const uint8_t *)type, 4), d, n);
    be32(h, c);
    fwrite(h, 1, 4, f);
}
static int write_png(const char *path, int h)
{
    for (uint32_t n = 0; n < 256; n++) {
        uint32_t c = n;
        for (int k = 0; k < 8; k++) c = c & 1 ? 0xEDB88320u ^ (c >> 1) : c >> 1;
        crc_table[n] = c;
    }
    size_t row = 1 + 4 * ATLAS_W, raw_n = row * (size_t)h;
    uint8_t *raw = malloc(raw_n);
    size_t blocks = (raw_n + 65534) / 65535, zn = 2 + raw_n + 5 * blocks + 4;
    uint8_t *z = malloc(zn);
    if (!raw || !z) return 1;
    for (int y = 0; y < h; y++) {
        uint8_t *r = raw + row * (size_t)y;
        r[0] = 0;
        for (int x = 0; x < ATLAS_W; x++) {
            r[1 + 4 * x] = r[2 + 4 * x] = r[3 + 4 * x] = 255;
            r[4 + 4 * x] = atlas[y][x];
        }
    }
    size_t at = 0;
    z[at++] = 0x78; z[at++] = 0x01;
    uint32_t a = 1, b = 0;
    for (size_t i = 0; i < raw_n; i++) { a = (a + raw[i]) % 65521; b = (b + a) % 65521; }
    for (size_t off = 0; off < raw_n; off += 65535) {
        size_t n = raw_n - off < 65535 ? raw_n - off : 65535;
        z[at++] = off + n == raw_n;
        z[at++] = (uint8_t)n; z[at++] = (uint8_t)(n >> 8);
        z[at++] = (uint8_t)~n; z[at++] = (uint8_t)(~n >> 8);
        memcpy(z + at, raw + off, n);
        at += n;
    }
    be32(z + at, (b << 16) | a);
    at += 4;
    FILE *f = fopen(path, "wb");
    if (!f) return 1;
    static const uint8_t sig[8] = { 137, 80, 78, 71, 13, 10, 26, 10 };
    fwrite(sig, 1, 8, f);
    uint8_t ihdr[13];
    be32(ihdr, ATLAS_W);
    be32(ihdr + 4, (uint32_t)h);
    ihdr[8] = 8; ihdr[9] = 6; ihdr[10] = ihdr[11] = ihdr[12] = 0;
    chunk(f, "IHDR", ihdr, 13);
    chunk(f, "IDAT", z, at);
    chunk(f, "IEND", NULL, 0);
    free(raw);
    free(z);
    return fclose(f) != 0;
}

int main(int argc, char **argv)
{
    if (argc != 2 && argc != 4) {
        fprintf(stderr, "usage: atlasgen OUT.c [ATLAS.png INDEX.txt]\n");
        return 2;
    }
    build();
    int h = pack();
    if (h < 0) { fprintf(stderr, "atlasgen: sprites do not fit\n"); return 1; }
    for (int k = 0; k < nsp; k++) raster(&sp[k]);
    static char idx[8192];
    index_text(idx, sizeof idx);
    FILE *f = fopen(argv[1], "w");
    if (!f) { perror(argv[1]); return 1; }
    fprintf(f, "/* Generated by tests/tools/atlasgen.c (make atlas): the default road-marking\n"
               " * atlas, docs/markings.md. Alpha of white markings, run-length coded as\n"
               " * (count 1..255, value) byte pairs, row by row. Do not edit. */\n"
               "#include \"atlas.h\"\n\n");
    fprintf(f, "const uint32_t rs__atlas_default_w = %d, rs__atlas_default_h = %d;\n\n", ATLAS_W, h);
    fprintf(f, "const char rs__atlas_default_index[] =\n");
    for (char *l = idx; *l;) {
        char *e = strchr(l, '\n');
        fprintf(f, "    \"%.*s\\n\"\n", (int)(e - l), l);
        l = e + 1;
    }
    fprintf(f, "    ;\n\nconst unsigned char rs__atlas_default_rle[] = {");
    size_t n = 0, total = (size_t)ATLAS_W * (size_t)h;
    const uint8_t *px = &atlas[0][0];
    for (size_t i = 0; i < total;) {
        size_t r = 1;
        while (i + r < total && r < 255 && px[i + r] == px[i]) r++;
        fprintf(f, "%s%zu,%u,", n % 10 ? "" : "\n    ", r, px[i]);
        n++;
        i += r;
    }
    fprintf(f, "\n};\nconst size_t rs__atlas_default_rle_size = sizeof rs__atlas_default_rle;\n");
    if (fclose(f)) return 1;
    if (argc == 4) {
        if (write_png(argv[2], h)) { fprintf(stderr, "atlasgen: cannot write %s\n", argv[2]); return 1; }
        FILE *g = fopen(argv[3], "w");
        if (!g) return 1;
        fprintf(g, "# roadsplat default marking atlas (tests/tools/atlasgen.c); docs/markings.md\n"
                   "# NAME X Y W H LENGTH WIDTH\n%s", idx);
        if (fclose(g)) return 1;
    }
    return 0;
}
