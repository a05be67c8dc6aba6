/* Binary glTF 2.0 (.glb) output of `roadsplat mesh` (issue 32,
 * docs/gltf.md). The writer lives in the module roadsplat-gltf.so
 * (cli/gltf.c, linked with meshoptimizer); cli/module.c holds the stand-in
 * the executable calls. */
#ifndef RS_CLI_GLTF_H
#define RS_CLI_GLTF_H
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

typedef struct cli_gltf_mesh {
    size_t nv, ni;          /* vertices; indices (3 per triangle) */
    const float *pos;       /* 3 per vertex: glTF axes (x east, y up, z south), metres */
    const float *uv;        /* 2 per vertex: texture coordinates, v down the image */
    const float *nrm;       /* 3 per vertex, unit, glTF axes; NULL: none */
    const uint32_t *idx;    /* ni, counter-clockwise seen from above */
    const unsigned char *image; /* the texture file's bytes (PNG or JPEG), NULL: none */
    size_t image_len;
    const char *image_mime; /* "image/png" or "image/jpeg" */
    const char *extras;     /* a JSON object for the scene's extras (the world frame), or NULL */
} cli_gltf_mesh;

typedef struct cli_gltf_stats {
    size_t vertices, triangles;
    double acmr_before, acmr_after; /* vertex-cache misses per triangle (cache of 16) */
    size_t bytes;                   /* the file */
} cli_gltf_stats;

/* Writes m to f as one .glb: vertex cache and fetch order optimised
 * (meshoptimizer), normals as normalised bytes and texture coordinates as
 * normalised shorts (KHR_mesh_quantization), positions float32 (the mesh's
 * exact heights). Returns 0, or 1 after a message naming `shown`. */
int cli_gltf_write(FILE *f, const char *shown, const cli_gltf_mesh *m, cli_gltf_stats *st);
#endif
