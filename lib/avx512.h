/* Private: the AVX-512 paths' dispatch, shared by the splat stages
 * (lib/splat/surface.c, composite.c) and the road field's holder scan
 * (lib/scene/roadfield.c). A path is chosen per call by the CPU: F, DQ and
 * VL; where those are missing and AVX2 is there (AMD before Zen 4, most
 * Intel client CPUs), the composite, the bilinear terrain, the tints, the
 * shades and the holder scan take AVX2 paths (RS_AVX2_DISPATCH); the
 * texture sampler takes its AVX2 path on any AVX2 CPU. A file built with
 * -DRS_NO_AVX512 has only its portable paths
 * (tests/cli_surface_paths_test.sh compares the two builds). */
#ifndef RS_AVX512_H
#define RS_AVX512_H
#if defined(__GNUC__) && defined(__x86_64__) && !defined(RS_NO_AVX512)
#include <immintrin.h>
#define RS_AVX512_DISPATCH 1
#define RS_AVX512 __attribute__((target("avx512f,avx512dq,avx512vl,avx2")))
static inline int rs__avx512_ok(void)
{
    return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
           __builtin_cpu_supports("avx512vl");
}
#if defined(__SSE2__) /* (the AVX2 paths share the SSE2 paths' helpers) */
#define RS_AVX2_DISPATCH 1
#define RS_AVX2 __attribute__((target("avx2")))
static inline int rs__avx2_ok(void)
{
    return __builtin_cpu_supports("avx2");
}
#endif
#endif
#endif
