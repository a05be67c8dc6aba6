/* How the roam fuzz target (fuzz/roam/fuzz.c) reads its input, shared with
 * tests/test_roam.c, which replays the target's findings through the same
 * setup. Input: byte 0 = width-2, byte 1 = height-2 (each taken mod 33),
 * then one byte per sample (255 = nodata, samples repeat when the input is
 * short); the last 4 bytes choose the pool size (2 bytes), the error
 * threshold and the mode. With bit 3 of the last byte, six rs_roam_update
 * calls follow, their views from the body's bytes, in reverse. */
#ifndef RS_ROAM_FUZZ_INPUT_H
#define RS_ROAM_FUZZ_INPUT_H
#include "roadsplat.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef struct rf_input {
    const uint8_t *data, *tail; /* the input and its last 4 bytes */
    size_t nbody;               /* the bytes between the two size bytes and the last 4 */
    uint32_t W, H;
    double cs;                  /* cell size, metres */
    int mode;                   /* first mesh: 0 refine_error, 1 refine_count, 2 frame, 3 frame with a target */
    int updates;                /* 1: the update sequence follows */
    rs_roam_options o;
} rf_input;

/* 0 when the input is too short to read. */
static inline int rf_read(const uint8_t *data, size_t size, rf_input *in)
{
    if (size < 7) return 0;
    memset(in, 0, sizeof *in);
    in->data = data;
    in->tail = data + size - 4;
    in->nbody = size - 6;
    in->W = 2 + data[0] % 33, in->H = 2 + data[1] % 33;
    in->cs = 1.0 + (in->tail[3] >> 4);
    in->mode = in->tail[3] % 4;
    in->updates = (in->tail[3] & 8) != 0;
    in->o.pool_nodes = (uint32_t)in->tail[0] | (uint32_t)in->tail[1] << 8;
    in->o.unit_size = (in->tail[1] & 0xC0) ? 1u << (2 * (in->tail[1] >> 6)) : 0u; /* 4, 16, 64 or the default */
    return 1;
}

/* The W x H samples (malloc'd; NULL when memory runs out). */
static inline float *rf_samples(const rf_input *in)
{
    float *z = malloc((size_t)in->W * in->H * sizeof *z);
    if (!z) return NULL;
    for (size_t k = 0; k < (size_t)in->W * in->H; k++) {
        uint8_t b = in->data[2 + k % in->nbody];
        z[k] = b == 255 ? NAN : (float)b * (in->tail[3] & 4 ? 257.0f : 1.0f);
    }
    return z;
}

/* The first mesh (modes 0 to 3). */
static inline rs_result rf_first_mesh(rs_ctx *ctx, rs_roam *r, const rf_input *in)
{
    const uint8_t *tail = in->tail;
    if (in->mode == 0) return rs_roam_refine_error(ctx, r, tail[2] / 8.0);
    if (in->mode == 1) return rs_roam_refine_count(ctx, r, 2 + tail[2] * 4u);
    rs_roam_view v;
    memset(&v, 0, sizeof v);
    v.eye[0] = (double)tail[0] - 20; v.eye[1] = (double)tail[1] - 20; v.eye[2] = 30 + tail[2];
    v.dir[0] = in->W / 2.0 - v.eye[0]; v.dir[1] = in->H / 2.0 - v.eye[1]; v.dir[2] = -10;
    v.pixel_error = 0.5 + tail[2] / 16.0;
    v.target_triangles = in->mode == 3 ? 20u + tail[2] : 0u;
    return rs_roam_frame(ctx, r, &v);
}

/* Update k's view and budget (k = 0 .. 5), and the byte the target's mesh
 * check takes its extraction options from. */
static inline void rf_update_view(const rf_input *in, int k, rs_roam_view *v, uint32_t *budget, uint8_t *opt)
{
    const uint8_t *data = in->data;
    const size_t nbody = in->nbody;
    const uint8_t *q = data + 2 + (nbody - 1 - (size_t)(k * 5) % nbody); /* reading backwards */
    uint8_t q0 = q[0], q1 = data[2 + (size_t)(k * 5 + 1) % nbody], q2 = data[2 + (size_t)(k * 5 + 2) % nbody];
    memset(v, 0, sizeof *v);
    v->eye[0] = (double)q0 / 4.0 - 10; v->eye[1] = (double)q1 / 4.0 - 10; v->eye[2] = 2 + q2 / 2.0;
    v->dir[0] = in->W / 2.0 - v->eye[0] + (q2 & 15) - 7.5; v->dir[1] = in->H / 2.0 - v->eye[1];
    v->dir[2] = -(double)(q0 & 7);
    if (v->dir[0] == 0 && v->dir[1] == 0 && v->dir[2] == 0) v->dir[2] = -1;
    v->pixel_error = 0.25 + (q1 & 31) / 8.0;
    v->target_triangles = (q2 & 64) ? 4u + q0 : 0u;
    v->width = 64 + q1; v->height = 48 + q2;
    *budget = (q0 & 128) ? q1 % 9 : 0;
    *opt = (uint8_t)(in->tail[2] ^ q0);
}

#endif
