/* GLSL 3.30 core sources of the shader render (rs_gpu_glsl; cli/render_shader.c
 * is their host, docs/render.md "Shader mode", docs/embedding.md "The GPU
 * side"). The fragment shader evaluates the roads per screen pixel from the
 * buffer textures of rs_gpu_scene (include/roadsplat.h "GPU export"), in the
 * CPU's layer order (lib/splat/overlays.c, lib/splat/composite.c): casings
 * onto the terrain colour T, fill / gradient surfaces, lines, markings and a
 * bridge's casing over the roads below onto the road colour S, then
 * C = (1 - R) T + R S. Coverage is the box filter of
 * the pixel's footprint (the parallelogram of dFdx, dFdy of the map
 * position) across each edge: exact for a straight edge, as the CPU's
 * analytic mode. Constant data only. */
#include "internal.h"

static const char rsh_vs_src[] =
    "#version 330 core\n"
    "layout(location = 0) in vec3 a_pos;\n" /* map frame: x east, y down the map, z up */
    "layout(location = 1) in vec3 a_nrm;\n"
    "uniform mat4 u_mvp;\n"
    "uniform vec3 u_eye;\n"
    "out vec2 v_xy;\n"
    "out vec3 v_nrm;\n"
    "out float v_dist;\n"
    "void main() {\n"
    "    v_xy = a_pos.xy;\n"
    "    v_nrm = a_nrm;\n"
    "    v_dist = length(a_pos - u_eye);\n"
    "    gl_Position = u_mvp * vec4(a_pos, 1.0);\n"
    "}\n";

/* in parts: C99 compilers need support string literals of 4095 bytes only */
static const char *const rsh_fs_src[] = {
    "#version 330 core\n"
    "in vec2 v_xy;\n"
    "in vec3 v_nrm;\n"
    "in float v_dist;\n"
    "out vec4 o_col;\n"
    "uniform sampler2D u_terrain;\n"   /* T, RGBA8 */
    "uniform sampler2D u_road;\n"      /* S (unstyled road surface), RGBA8 */
    "uniform vec2 u_map;\n"            /* map extent, metres */
    "uniform int u_roads;\n"           /* 0: terrain only */
    "uniform samplerBuffer u_seg;\n"   /* 2 texels per segment */
    "uniform usamplerBuffer u_cstart;\n"
    "uniform usamplerBuffer u_cseg;\n"
    "uniform samplerBuffer u_roadt;\n" /* 10 texels per road */
    "uniform samplerBuffer u_band;\n"  /* 5 texels per band */
    "uniform samplerBuffer u_mark;\n"  /* 3 texels per marking */
    "uniform usamplerBuffer u_mstart;\n"
    "uniform usamplerBuffer u_mids;\n"
    "uniform usamplerBuffer u_types;\n" /* 2 per type */
    "uniform usamplerBuffer u_levels;\n" /* RGBA32UI per level; level 0: .w = the type's first u_atlas entry */
    "uniform isamplerBuffer u_atlas;\n" /* per type (h + 1) x (w + 1) summed-area corners: 255 x premultiplied r g b a */
    "uniform samplerBuffer u_cut;\n"   /* per road: first cut, count; then 2 texels per cut (lines stop) */
    "uniform vec4 u_grid;\n"           /* x0, y0, 1 / cell, reach */
    "uniform ivec2 u_gdim;\n"
    "uniform int u_lighting;\n"
    "uniform sampler2D u_normal;\n"   /* rs_normal_window: R east, G north, B up */
    "uniform int u_nmap;\n"
    "uniform vec3 u_sun;\n"            /* map frame, unit, towards the sun */
    "uniform vec3 u_amb;\n"
    "uniform vec3 u_dif;\n"
    "uniform int u_fog;\n"
    "uniform vec2 u_fogr;\n"           /* start, end */
    "uniform vec3 u_fogc;\n"
    /* llvmpipe runs every branch, and every loop body at least once,
     * under a lane mask: the cost is the whole code per pixel group, so
     * it is kept short and the loops few (measured with callgrind) */
    "vec2 dpx, dpy;\n"
    "float foot;\n"
    /* P(X <= x) for X the pixel footprint's offset along unit direction n:
     * the sum of two uniform variables of widths |n.dpx| and |n.dpy|. */

    /* the same for many x along one direction n: fp(n) once, cdfp(x, F) per x */
    "vec4 fp(vec2 n) {\n"
    "    float e1 = abs(dot(n, dpx)), e2 = abs(dot(n, dpy));\n"
    "    float a = max(max(e1, e2), 1e-9), b = min(e1, e2);\n"
    "    return vec4(0.5 * (a + b), 0.5 * (a - b), 1.0 / a, b > 1e-12 ? 0.5 / (a * b) : 0.0);\n"
    "}\n"
    "float cdfp(float x, vec4 F) {\n"
    "    float ax = abs(x), d = max(F.x - ax, 0.0);\n"
    "    float v = ax <= F.y ? min(0.5 + ax * F.z, 1.0) : 1.0 - d * d * F.w;\n"
    "    return x >= 0.0 ? v : 1.0 - v;\n"
    "}\n"
    "float cdf(float x, vec2 n) { return cdfp(x, fp(n)); }\n"
    /* nearest point of segment k: d, u (along, unclamped), side (+ left) */
    "struct Seg { vec2 a; vec2 dir; float len; float r; float s0; int road; int flags; float cw; };\n"
    "Seg seg_load(int k) {\n"
    "    vec4 p = texelFetch(u_seg, 3 * k), q = texelFetch(u_seg, 3 * k + 1), c = texelFetch(u_seg, 3 * k + 2);\n"
    "    Seg s; s.a = p.xy; s.len = c.y; s.dir = c.zw; s.cw = c.x;\n"
    "    s.r = q.x; s.s0 = q.y; s.road = int(q.z); s.flags = int(q.w);\n"
    "    return s;\n"
    "}\n"
    /* road coordinates of p at segment k: s, t, t's direction, the tangent
     * and the box filter at a flat road end */
    "void road_coords(vec2 p, int k, out float rs, out float rt, out vec2 nt, out vec2 tg, out float ef) {\n",
    "    Seg s = seg_load(k);\n"
    "    vec2 w = p - s.a;\n"
    "    float u = dot(w, s.dir), side = w.x * s.dir.y - w.y * s.dir.x;\n"
    "    bool lo = u < 0.0, hi = u > s.len;\n"
    "    bool endlo = lo && (s.flags & 9) == 1, endhi = hi && (s.flags & 18) == 2;\n"
    "    tg = s.dir; rs = s.s0 + u; rt = side; nt = vec2(s.dir.y, -s.dir.x);\n"
    "    if ((lo || hi) && !endlo && !endhi) {\n"
    "        vec2 q = lo ? s.a : s.a + s.len * s.dir; vec2 pq = p - q; float d = length(pq);\n"
    "        rs = s.s0 + (lo ? 0.0 : s.len);\n"
    "        rt = side >= 0.0 ? d : -d;\n"
    "        if (d > 0.0) nt = pq / d;\n"
    "    }\n"
    "    ef = 1.0;\n"
    "    if ((s.flags & 9) == 1) ef *= cdf(u, s.dir);\n"
    "    if ((s.flags & 18) == 2) ef *= cdf(s.len - u, s.dir);\n"
    /* a joint with the record continuing this one (RS_GPU_SEG_JOIN_*):
     * its lines run on as through a vertex of one road, each record
     * painting its side of the bisector (the sum of the two directions:
     * the same floats on both sides, so every pixel is painted by one) */
    "    if ((s.flags & 24) != 0) {\n"
    "        vec4 r1 = texelFetch(u_roadt, 10 * s.road + 1);\n"
    "        int nr = textureSize(u_roadt) / 10;\n"
    "        if ((s.flags & 8) != 0) {\n"
    "            int b = int(r1.y), kb = (b + 1 < nr ? int(texelFetch(u_roadt, 10 * b + 19).w) : textureSize(u_seg) / 3) - 1;\n"
    "            if (dot(texelFetch(u_seg, 3 * kb + 2).zw + s.dir, p - s.a) < 0.0) ef = 0.0;\n"
    "        }\n"
    "        if ((s.flags & 16) != 0) {\n"
    "            int kb = int(texelFetch(u_roadt, 10 * int(r1.z) + 9).w);\n"
    "            if (dot(s.dir + texelFetch(u_seg, 3 * kb + 2).zw, p - texelFetch(u_seg, 3 * k).zw) >= 0.0) ef = 0.0;\n"
    "        }\n"
    "    }\n"
    "}\n"
    /* a road end at a T (lib/scene/roadfield.c, docs/network.md "Ends at a T"):
     * the segment's strip, grown by `grow`, runs on flat to the clip line
     * n.p = c of a trimmed first or last end and stops there; an untrimmed
     * end keeps its normal and disc. Signed distance (the largest of the
     * sides' inside, exact at straight edges) and its normal; dflt when
     * neither end of the segment is trimmed */
    "float tee_trim(Seg s, vec2 p, float u, float side, float grow, inout vec2 n, float dflt) {\n"
    "    vec4 c0 = texelFetch(u_roadt, 10 * s.road + 8), c1 = texelFetch(u_roadt, 10 * s.road + 9);\n"
    "    vec2 n0 = c0.xy, n1 = vec2(c0.w, c1.x);\n"
    "    bool h0 = dot(n0, n0) > 0.0, h1 = dot(n1, n1) > 0.0, cl = (s.flags & 4) != 0;\n"
    "    bool cut0 = (s.flags & 1) != 0 && h0, cut1 = (s.flags & 2) != 0 && h1;\n"
    "    if (!cut0 && !cut1 && !cl) return dflt;\n"
    "    float r = s.r + grow, best = abs(side) - r, hmax = -1e30, disc = 1e30;\n"
    "    vec2 bn = (side >= 0.0 ? 1.0 : -1.0) * vec2(s.dir.y, -s.dir.x), hn = n0, dn = n0;\n"
    "    if (cut0 || (cl && h0)) { hmax = dot(n0, p) - c0.z; hn = n0; }\n"
    "    if (!cut0) { if (-u > best) { best = -u; bn = -s.dir; } vec2 w = p - s.a; float l = length(w); disc = l - r; dn = l > 0.0 ? w / l : -s.dir; }\n"
    "    if (cut1 || (cl && h1)) { float h = dot(n1, p) - c1.y; if (h > hmax) { hmax = h; hn = n1; } }\n"
    "    if (!cut1) { if (u - s.len > best) { best = u - s.len; bn = s.dir; } vec2 w = p - s.a - s.len * s.dir; float l = length(w); if (l - r < disc) { disc = l - r; dn = l > 0.0 ? w / l : s.dir; } }\n"
    "    if (hmax > best) { best = hmax; bn = hn; }\n"
    "    if (hmax > disc) { disc = hmax; dn = hn; }\n"
    "    if (disc < best) { best = disc; bn = dn; }\n"
    "    n = bn;\n"
    "    return best;\n"
    "}\n",
    /* segment k at p: distance d, signed distance to its surface sd (a
     * capsule; a trimmed T end: tee_trim), the normal n there, u along
     * and side (+ left) */
    "Seg seg_at(vec2 p, int k, out float d, out float sd, out vec2 n, out float u, out float side) {\n"
    "    Seg s = seg_load(k);\n"
    "    vec2 w = p - s.a;\n"
    "    u = dot(w, s.dir); side = w.x * s.dir.y - w.y * s.dir.x;\n"
    "    vec2 pq = w - clamp(u, 0.0, s.len) * s.dir; d = length(pq);\n"
    "    n = d > 0.0 ? pq / d : vec2(s.dir.y, -s.dir.x);\n"
    "    sd = d - s.r;\n"
    "    if ((s.flags & 7) != 0) sd = tee_trim(s, p, u, side, 0.0, n, sd);\n"
    "    return s;\n"
    "}\n"
    /* 1 - the coverage of road `road`'s surface from its segments in list
     * [e0, e1), the same arithmetic as the first pass of main (1: absent) */
    "float road_free(vec2 p, int road, int e0, int e1) {\n"
    "    float best = 1e30, d, sd, u, side; vec2 bn = vec2(1.0, 0.0), n;\n"
    "    for (int e = e0; e < e1; e++) {\n"
    "        Seg s = seg_at(p, int(texelFetch(u_cseg, e).r), d, sd, n, u, side);\n"
    "        if (s.road == road && sd < best) { best = sd; bn = n; }\n"
    "    }\n"
    "    return best < 1e29 ? 1.0 - cdf(-best, bn) : 1.0;\n"
    "}\n"
    /* road_free for the lines of the through stroke st at a T
     * (lib/scene/linesym.c, docs/network.md): an end segment of `road` that meets
     * st (b6: the road's stroke, the strokes its start and end meet, the
     * start's depth; keepE the end's) is its rectangle on the side road's
     * side of the line `depth` from st's centre line, parallel to st there
     * (tg), without its round end (as lib/scene/linesym.c: until 3 December
     * 2026 it stopped depth / sine back, square to the side road, and at an
     * oblique T its acute corner cut st's centre line) */
    "float road_free_tee(vec2 p, int road, int e0, int e1, float st, vec4 b6, float keepE, vec2 tg) {\n",
    "    float best = 1e30, d, sd, u, side; vec2 bn = vec2(1.0, 0.0), n;\n"
    "    for (int e = e0; e < e1; e++) {\n"
    "        Seg s = seg_at(p, int(texelFetch(u_cseg, e).r), d, sd, n, u, side);\n"
    "        if (s.road != road) continue;\n"
    "        bool ts = (s.flags & 1) != 0 && b6.y == st, te = (s.flags & 2) != 0 && b6.z == st;\n"
    "        float sn = abs(s.dir.x * tg.y - s.dir.y * tg.x);\n"
    "        if ((ts || te) && sn > 0.2) {\n"
    "            float u0 = -s.r, u1 = s.len + s.r;\n"
    "            float qx = max(u0 - u, u - u1), qy = abs(side) - s.r;\n"
    "            vec2 q = max(vec2(qx, qy), 0.0), pr = vec2(s.dir.y, -s.dir.x);\n"
    "            sd = q.x > 0.0 || q.y > 0.0 ? length(q) : max(qx, qy);\n"
    "            n = qy >= qx ? (side >= 0.0 ? 1.0 : -1.0) * pr : (u - u1 > u0 - u ? 1.0 : -1.0) * s.dir;\n"
    "            vec2 nc = vec2(-tg.y, tg.x);\n"
    "            if (te) {\n" /* the keep line at the end: nc towards the side road */
    "                vec2 m = dot(nc, s.dir) > 0.0 ? -nc : nc;\n"
    "                float h = keepE - ((u - s.len) * dot(m, s.dir) + side * dot(m, pr));\n"
    "                if (h > sd) { sd = h; n = -m; }\n"
    "            }\n"
    "            if (ts) {\n"
    "                vec2 m = dot(nc, s.dir) < 0.0 ? -nc : nc;\n"
    "                float h = b6.w - (u * dot(m, s.dir) + side * dot(m, pr));\n"
    "                if (h > sd) { sd = h; n = -m; }\n"
    "            }\n"
    "        }\n"
    "        if (sd < best) { best = sd; bn = n; }\n"
    "    }\n"
    "    return best < 1e29 ? 1.0 - cdf(-best, bn) : 1.0;\n"
    "}\n"
    /* road `road`'s nearest segment in list [e0, e1) (-1: absent) */
    "int road_nearest(vec2 p, int road, int e0, int e1) {\n"
    "    float best = 1e30, d, sd, u, side; vec2 n; int kb = -1;\n"
    "    for (int e = e0; e < e1; e++) {\n"
    "        int k = int(texelFetch(u_cseg, e).r);\n"
    "        Seg s = seg_at(p, k, d, sd, n, u, side);\n"
    "        if (s.road == road && d < best) { best = d; kb = k; }\n"
    "    }\n"
    "    return kb;\n"
    "}\n"
    /* the nearest segment in list [e0, e1) of the roads of stroke st
     * (-1: absent): a marking past its record's end follows the records
     * going on there (lib/scene/markings.c) */
    "int stroke_nearest(vec2 p, float st, int e0, int e1) {\n"
    "    float best = 1e30, d, sd, u, side; vec2 n; int kb = -1;\n"
    "    for (int e = e0; e < e1; e++) {\n"
    "        int k = int(texelFetch(u_cseg, e).r);\n"
    "        Seg s = seg_at(p, k, d, sd, n, u, side);\n"
    "        if (texelFetch(u_roadt, 10 * s.road + 6).x == st && d < best) { best = d; kb = k; }\n"
    "    }\n"
    "    return kb;\n"
    "}\n"
    /* the union of coverage U (its dominant edge's outward normal N) and
     * one more road's c (normal n) within the pixel: the larger where the
     * edges face the same way, the sum where they face each other (a gap
     * narrower than the pixel between two roads), 1 - (1 - U)(1 - c) where
     * they cross at right angles (exact for a square footprint), blended
     * by the angle between the edges */
    "void union_add(inout float U, inout vec2 N, float c, vec2 n) {\n"
    "    if (!(c > 0.0)) return;\n"
    "    float w = dot(N, n), ind = U + c - U * c;\n"
    "    float v = w >= 0.0 ? mix(ind, max(U, c), w) : mix(ind, min(U + c, 1.0), -w);\n"
    "    if (c > U) N = n;\n"
    "    U = U > 0.0 ? v : c;\n"
    "}\n"
    /* a road's level from its fill rank (.z of its row 7): the rank's
     * multiple of 64, 0 for the ranks all alike at -1e9 (bridges, layer=) */
    "float rank_level(float rk) { return rk < -1e8 ? 0.0 : floor(rk / 64.0); }\n"
    /* a factor of the junction cut: zero-ish ones are counted, not multiplied */
    "void cut_add(float f, inout float prod, inout int zeros, float sgn) {\n"
    "    if (f < 1e-6) zeros += int(sgn); else prod = sgn > 0.0 ? prod * f : prod / f;\n"
    "}\n",
    /* road `road`'s lines onto S at p, from its nearest segment k (distance
     * d) and its surface's free share fo; every other road of the list
     * cuts them (its surface's coverage, product `prod` with `zeros` zero
     * factors over the whole list) except the roads continuing this one */
    "void paint_lines(vec2 p, int road, int k, float d, float fo, float prod, int zeros, int e0, int e1, inout vec3 S) {\n"
    "    vec4 r0 = texelFetch(u_roadt, 10 * road), r1 = texelFetch(u_roadt, 10 * road + 1);\n"
    "    int b0 = int(r0.w), nb = int(r1.x);\n"
    /* a road whose lines cannot reach the pixel is skipped */
    "    if (nb == 0 || d > r1.w + foot) return;\n"
    "    cut_add(fo, prod, zeros, -1.0);\n"
    "    if (r1.y >= 0.0) cut_add(road_free(p, int(r1.y), e0, e1), prod, zeros, -1.0);\n"
    "    if (r1.z >= 0.0 && r1.z != r1.y) cut_add(road_free(p, int(r1.z), e0, e1), prod, zeros, -1.0);\n"
    "    float s, t, ef; vec2 nt, tg;\n"
    "    road_coords(p, k, s, t, nt, tg, ef);\n"
    /* a path, footway or cycleway cuts no car road's lines; a car road of
     * lower rank crossing this one (not a side road of this stroke at a T)
     * cuts only its lines more than keep from its centre line: its factors
     * are kept apart (prodL, zerosL) and left out for the inner lines
     * (lib/scene/linesym.c; the list is grouped by road) */
    "    vec4 r7 = texelFetch(u_roadt, 10 * road + 7);\n"
    "    bool car = r7.w > 0.0;\n"
    "    float prodL = 1.0, keep = max(r0.y - 2.0, 0.0); int zerosL = 0;\n"
    /* roads on other levels (bridges, layer=; the level is the fill
     * priority's multiple of 64, all alike at -1e9): a lower one cuts none
     * of this road's lines, a higher one all of them */
    "    float lv = rank_level(r7.z);\n"
    "    {\n"
    "        int lr = -1; float st = texelFetch(u_roadt, 10 * road + 6).x;\n"
    "        for (int e = e0; e < e1; e++) {\n"
    "            int b = int(texelFetch(u_seg, 3 * int(texelFetch(u_cseg, e).r) + 1).z);\n"
    "            if (b == lr || b == road) continue;\n"
    "            lr = b;\n"
    "            if (float(b) == r1.y || float(b) == r1.z) continue;\n"
    "            vec4 b7 = texelFetch(u_roadt, 10 * b + 7);\n"
    "            float lb = rank_level(b7.z);\n"
    "            if (lb < lv) { cut_add(road_free(p, b, e0, e1), prod, zeros, -1.0); continue; }\n"
    "            if (lb > lv || !car) continue;\n"
    "            if (!(b7.w > 0.0)) { cut_add(road_free(p, b, e0, e1), prod, zeros, -1.0); continue; }\n"
    "            if (!(b7.z < r7.z)) continue;\n"
    "            if (r7.y > 0.0) { vec4 b6 = texelFetch(u_roadt, 10 * b + 6); if (b6.y == st || b6.z == st) continue; }\n"
    "            cut_add(road_free(p, b, e0, e1), prodL, zerosL, 1.0);\n"
    "        }\n"
    "    }\n",
    /* side roads ending on this road's stroke at a T cut its lines only
     * with their cut-back ends (the list is grouped by road) */
    "    if (texelFetch(u_roadt, 10 * road + 7).y > 0.0) {\n"
    "        float st = texelFetch(u_roadt, 10 * road + 6).x; int lr = -1;\n"
    "        for (int e = e0; e < e1; e++) {\n"
    "            int b = int(texelFetch(u_seg, 3 * int(texelFetch(u_cseg, e).r) + 1).z);\n"
    "            if (b == lr || b == road) continue;\n"
    "            lr = b;\n"
    "            if (car && !(texelFetch(u_roadt, 10 * b + 7).w > 0.0)) continue;\n"
    "            vec4 b6 = texelFetch(u_roadt, 10 * b + 6);\n"
    "            if (b6.y != st && b6.z != st) continue;\n"
    "            cut_add(road_free(p, b, e0, e1), prod, zeros, -1.0);\n"
    "            cut_add(road_free_tee(p, b, e0, e1, st, b6, texelFetch(u_roadt, 10 * b + 7).x, tg), prod, zeros, 1.0);\n"
    "        }\n"
    "    }\n"
    "    float cut = zeros > 0 ? 0.0 : min(prod, 1.0), cutI = zeros - zerosL > 0 ? 0.0 : min(prod / prodL, 1.0);\n"
    "    vec4 Ft = fp(nt), Fs = fp(tg);\n"
    "    if (!(ef * max(cut, cutI) > 0.0)) return;\n"
    /* the road's line cuts (stop lines, zebras; lib/scene/markings_auto.c) */
    "    int nr = textureSize(u_roadt) / 10;\n" /* 10 texels per road */
    "    vec4 cr = texelFetch(u_cut, road); int c0 = nr + 2 * int(cr.x), nc = int(cr.y);\n"
    "    for (int j = 0; j < nb; j++) {\n"
    "        int bi = 5 * (b0 + j);\n"
    "        vec4 B0 = texelFetch(u_band, bi), col = texelFetch(u_band, bi + 1);\n"
    "        float lo = B0.x - 0.5 * B0.y, hi = B0.x + 0.5 * B0.y;\n"
    "        float cov = cdfp(hi - t, Ft) - cdfp(lo - t, Ft);\n"
    "        for (int c = 0; c < nc && cov > 0.0; c++) {\n"
    "            vec4 C0 = texelFetch(u_cut, c0 + 2 * c), C1 = texelFetch(u_cut, c0 + 2 * c + 1);\n"
    "            float l2 = max(lo, -C1.z), h2 = min(hi, C1.z);\n"
    "            if (!(h2 > l2)) continue;\n"
    "            float u = dot(p - C0.xy, C0.zw);\n"
    "            float al = cdfp(C1.y - u, Fs) - cdfp(C1.x - u, Fs);\n"
    "            if (al > 0.0) cov = max(cov - al * (cdfp(h2 - t, Ft) - cdfp(l2 - t, Ft)), 0.0);\n"
    "        }\n"
    "        if (!(cov > 0.0)) continue;\n"
    "        int nd = int(texelFetch(u_band, bi + 2).x);\n"
    "        if (nd > 0 && B0.w > 0.0) {\n"
    "            vec4 D0 = texelFetch(u_band, bi + 3), D1 = texelFetch(u_band, bi + 4);\n"
    "            float dash[8] = float[8](D0.x, D0.y, D0.z, D0.w, D1.x, D1.y, D1.z, D1.w);\n"
    "            float P = B0.w, x = s - B0.z;\n"
    "            float ext = Fs.x;\n"
    "            float k0 = floor((x - ext) / P), k1 = floor((x + ext) / P);\n"
    "            float along = 0.0;\n"
    "            if (k1 - k0 > 3.0) {\n"
    "                float on = 0.0; for (int m = 0; m < nd; m += 2) on += dash[m];\n"
    "                along = on / P;\n"
    "            } else {\n"
    "                for (float kk = k0; kk <= k1; kk += 1.0) {\n"
    "                    float o = kk * P;\n"
    "                    for (int m = 0; m < nd; m += 2) {\n"
    "                        along += cdfp(o + dash[m] - x, Fs) - cdfp(o - x, Fs);\n"
    "                        o += dash[m] + dash[m + 1];\n"
    "                    }\n"
    "                }\n"
    "            }\n"
    "            cov *= along;\n"
    "        }\n"
    "        float a = clamp(cov * ef * (abs(B0.x) <= keep ? cutI : cut), 0.0, 1.0) * col.a;\n"
    "        S = S * (1.0 - a) + col.rgb * a;\n"
    "    }\n"
    "}\n",
    /* markings (issue 25, docs/markings.md): the sprite's exact mean over
     * the pixel's footprint (e1, e2: the pixel's steps in level-0 texels),
     * its slanted sides as staircases, from the summed-area table; the
     * same footprint and steps as lib/scene/markings.c */
    "ivec4 sat_at(int off, int w1, int j, int i) { return texelFetch(u_atlas, off + j * w1 + i); }\n"
    "vec4 sat_step(int off, int w, int h, float u, float v0, float v1) {\n"
    "    u = min(u, float(w)); if (!(u > 0.0)) return vec4(0.0);\n"
    "    v0 = clamp(v0, 0.0, float(h)); v1 = clamp(v1, 0.0, float(h));\n"
    "    int i = int(u), j0 = int(v0), j1 = int(v1), w1 = w + 1;\n"
    "    int i1 = min(i + 1, w), a1 = min(j0 + 1, h), b1 = min(j1 + 1, h);\n"
    "    float fu = u - float(i), f0 = v0 - float(j0), f1 = v1 - float(j1);\n"
    "    ivec4 a00 = sat_at(off, w1, j0, i), a01 = sat_at(off, w1, j0, i1), a10 = sat_at(off, w1, a1, i), a11 = sat_at(off, w1, a1, i1);\n"
    "    ivec4 b00 = sat_at(off, w1, j1, i), b01 = sat_at(off, w1, j1, i1), b10 = sat_at(off, w1, b1, i), b11 = sat_at(off, w1, b1, i1);\n"
    "    vec4 p = vec4(b00 - a00), r = vec4((b01 - b00) - (a01 - a00));\n"
    "    vec4 db = vec4(b10 - b00), da = vec4(a10 - a00), xb = vec4((b11 - b10) - (b01 - b00)), xa = vec4((a11 - a10) - (a01 - a00));\n"
    "    return p + fu * r + (f1 * db - f0 * da) + fu * (f1 * xb - f0 * xa);\n"
    "}\n",
    "vec4 atlas_box(int type, vec2 c, vec2 e1, vec2 e2) {\n"
    "    uvec4 L = texelFetch(u_levels, int(texelFetch(u_types, 2 * type).r));\n"
    "    int off = int(L.w), w = int(L.y), h = int(L.z);\n"
    "    float A = abs(e1.x * e2.y - e1.y * e2.x);\n"
    "    if (!(A > 0.0)) return vec4(0.0);\n"
    "    if (e1.y < 0.0) e1 = -e1;\n"
    "    if (e2.y < 0.0) e2 = -e2;\n"
    "    bool e1f = e1.y == 0.0 || (e2.y != 0.0 && e1.x * e2.y < e2.x * e1.y);\n"
    "    vec2 a = e1f ? e1 : e2, b = e1f ? e2 : e1;\n"
    "    if (a.y == 0.0) a.x = -abs(a.x);\n"
    "    vec2 o = -0.5 * (a + b);\n"
    "    vec4 acc = vec4(0.0); float area = 0.0, vprev = o.y;\n"
    "    for (int e = 0; e < 2; e++) {\n"
    "        vec2 ed = e == 0 ? a : b;\n"
    "        if (ed.y > 0.0) {\n"
    "            float need = sqrt(ed.y * abs(ed.x) / (8.0 * 0.0125 * A));\n"
    "            int n = need < 1.0 ? 1 : need >= 3.0 ? 3 : int(ceil(need));\n"
    "            for (int k = 0; k < n; k++) {\n"
    "                float du = o.x + (float(k) + 0.5) / float(n) * ed.x;\n"
    "                float v1 = k + 1 == n ? o.y + ed.y : o.y + float(k + 1) / float(n) * ed.y;\n"
    "                area += -2.0 * du * (v1 - vprev);\n"
    "                acc -= sat_step(off, w, h, c.x + du, c.y + vprev, c.y + v1);\n"
    "                acc -= sat_step(off, w, h, c.x - du, c.y - vprev, c.y - v1);\n"
    "                vprev = v1;\n"
    "            }\n"
    "        }\n"
    "        o += ed;\n"
    "    }\n"
    "    if (!(area > 0.0)) return vec4(0.0);\n"
    "    acc /= 255.0 * area;\n"
    "    return clamp(acc, vec4(0.0), vec4(255.0, 255.0, 255.0, 1.0));\n"
    "}\n",
    "void main() {\n"
    "    vec2 p = v_xy;\n"
    "    dpx = dFdx(p); dpy = dFdy(p);\n"
    "    vec2 uv = p / u_map;\n"
    "    vec3 T = texture(u_terrain, uv).rgb * 255.0;\n"
    "    vec2 duvx = dpx / u_map, duvy = dpy / u_map;\n"
    "    vec3 S = vec3(0.0);\n"
    "    float R = 0.0;\n"
    "    foot = max(length(dpx), length(dpy));\n"
    "    float near_reach = 0.70710678 * foot;\n"
    "    vec2 cf = floor((p - u_grid.xy) * u_grid.z);\n"
    "    bool inside = u_roads != 0 && cf.x >= 0.0 && cf.y >= 0.0 && cf.x < float(u_gdim.x) && cf.y < float(u_gdim.y);\n"
    "    int cell = inside ? int(cf.y) * u_gdim.x + int(cf.x) : 0;\n"
    "    int e0 = int(texelFetch(u_cstart, cell).r), e1 = inside ? int(texelFetch(u_cstart, cell + 1).r) : e0;\n"
    "    if (e1 > e0) {\n"
    "        float sdR = 1e30, sdC = 1e30, dS = 1e30, dC = 1e30;\n"
    "        vec2 nR = vec2(1.0, 0.0), nC = vec2(1.0, 0.0);\n"
    "        int roadS = -1, roadC = -1; float tS = 0.0, pS = -3e9;\n"
    /* levels (a bridge over a road): the highest level among the surfaces
     * holding p and its stroke, and the highest among those of the other
     * strokes; a lower road's markings are left out under a deck
     * (lib/scene/markings.c rs__markings_set_levels) */
    "        float lv1 = -3e9, lv2 = -3e9, st1 = -9.0;\n"
    /* the cell's list (ascending: grouped by road): R, casings, the
     * nearest surface, and each road's surface coverage as a factor of the
     * junction cuts (a product and a count of zero factors, so any number
     * of roads per cell takes part) */
    "        float prod = 1.0; int zeros = 0, cr = -1;\n"
    "        float csd = 1e30, ccd = 1e30, UR = 0.0, UC = 0.0; vec2 cn = vec2(1.0, 0.0), ccn = cn, NR = cn, NC = cn;\n"
    /* bridges' casings over the roads below (the pass after the
     * markings): the highest level among the cased roads whose casing
     * reaches p and its stroke, the lowest among the surfaces there */
    "        float lvlo = 3e9, lvc = -3e9, stc = -9.0, ccw = 0.0;\n"
    "        for (int e = e0; e <= e1; e++) {\n"
    "            float d = 0.0, sd = 1e30, u = 0.0, side = 0.0; vec2 n = vec2(1.0, 0.0);\n"
    "            Seg s; s.road = -2; s.cw = 0.0; s.len = 0.0;\n"
    "            if (e < e1) s = seg_at(p, int(texelFetch(u_cseg, e).r), d, sd, n, u, side);\n"
    "            float sdc = sd - s.cw; vec2 nc = n;\n" /* the casing: a T end's too stops at the clip line */
    "            if (e < e1 && (s.flags & 7) != 0) sdc = tee_trim(s, p, u, side, s.cw, nc, d - s.r - s.cw);\n"
    "            if (s.road != cr) {\n"
    "                if (cr >= 0) {\n"
    "                    float c = cdf(-csd, cn);\n"
    "                    cut_add(1.0 - c, prod, zeros, 1.0);\n"
    "                    union_add(UR, NR, c, cn);\n"
    "                    union_add(UC, NC, cdf(-ccd, ccn), ccn);\n"
    "                    float rl = rank_level(texelFetch(u_roadt, 10 * cr + 7).z);\n"
    "                    if (c > 0.0) lvlo = min(lvlo, rl);\n"
    "                    if (ccw > 0.0 && rl > lvc && cdf(-ccd, ccn) > 0.0) { lvc = rl; stc = texelFetch(u_roadt, 10 * cr + 6).x; }\n"
    "                }\n"
    "                cr = s.road; csd = sd; cn = n; ccd = sdc; ccn = nc; ccw = s.cw;\n"
    "            } else {\n"
    "                if (sd < csd) { csd = sd; cn = n; }\n"
    "                if (sdc < ccd) { ccd = sdc; ccn = nc; }\n"
    "            }\n"
    "            if (e == e1) break;\n"
    "            float cw = s.cw;\n"
    "            if (sd < sdR) { sdR = sd; nR = n; }\n"
    "            if (sdc < sdC) { sdC = sdc; nC = nc; }\n"
    /* the fill: among the surfaces holding p the highest priority, then
     * the nearest (lib/scene/roadfield.c rs__roadfield_nearest_ranked; all -1e9
     * when equal) */
    "            if (sd <= near_reach) {\n"
    "                float kp = sd <= 0.0 ? texelFetch(u_roadt, 10 * s.road + 7).z : -2e9;\n"
    "                if (sd <= 0.0) {\n"
    "                    float lv = rank_level(kp), sq = texelFetch(u_roadt, 10 * s.road + 6).x;\n"
    "                    if (sq == st1) lv1 = max(lv1, lv);\n"
    "                    else if (lv > lv1) { lv2 = lv1; lv1 = lv; st1 = sq; }\n"
    "                    else lv2 = max(lv2, lv);\n"
    "                }\n"
    "                if (kp < -1e8) kp = -2e9;\n"
    "                if (kp > pS || (kp == pS && d < dS)) { pS = kp; dS = d; roadS = s.road; tS = u >= 0.0 && u <= s.len ? side : sign(side) * d; }\n"
    "            }\n"
    "            if (cw > 0.0 && sdc <= near_reach && d < dC) { dC = d; roadC = s.road; }\n"
    "        }\n",
    "        R = min(UR, 1.0);\n"
    "        R = floor(R * 65535.0 + 0.5) / 65535.0;\n"
    "        if (R > 0.0) S = textureGrad(u_road, uv, duvx, duvy).rgb * 255.0;\n"
    /* casings onto T */
    "        float C = max(min(UC, 1.0), R);\n"
    "        if (C > R && R < 1.0 && roadC >= 0) {\n"
    "            vec4 cc = texelFetch(u_roadt, 10 * roadC + 5);\n"
    "            float a = clamp((min(C, 1.0) - R) / (1.0 - R), 0.0, 1.0) * cc.a;\n"
    "            T = T * (1.0 - a) + cc.rgb * a;\n"
    "        }\n"
    /* fill and gradient surfaces onto S */
    "        if (R > 0.0 && roadS >= 0) {\n"
    "            vec4 r0 = texelFetch(u_roadt, 10 * roadS);\n"
    "            int kind = int(r0.x);\n"
    "            if (kind != 0) {\n"
    "                vec4 c = texelFetch(u_roadt, 10 * roadS + 2);\n"
    "                if (kind == 2) {\n"
    "                    float g = r0.y > 0.0 ? min(abs(tS) / r0.y, 1.0) : 1.0;\n"
    "                    vec4 c0 = texelFetch(u_roadt, 10 * roadS + 3), c1 = texelFetch(u_roadt, 10 * roadS + 4);\n"
    "                    c = c0 + (c1 - c0) * g;\n"
    "                }\n"
    "                S = S * (1.0 - c.a) + c.rgb * c.a;\n"
    "            }\n"
    "        }\n",
    /* lines onto S, road by road (a second pass over the list, each
     * road's nearest segment), band by band; markings onto S; both show
     * only where R > 0 */
    "        if (R > 0.0) {\n"
    "        int gr = -1, gk = 0; float gd = 1e30, gsd = 1e30; vec2 gn = vec2(1.0, 0.0);\n"
    "        for (int e = e0; e <= e1; e++) {\n"
    "            float d = 0.0, sd = 1e30, u = 0.0, side = 0.0; vec2 n = vec2(1.0, 0.0);\n"
    "            int k = e < e1 ? int(texelFetch(u_cseg, e).r) : -1, road = -2;\n"
    "            if (k >= 0) road = seg_at(p, k, d, sd, n, u, side).road;\n"
    "            if (road != gr) {\n"
    "                if (gr >= 0) paint_lines(p, gr, gk, gd, 1.0 - cdf(-gsd, gn), prod, zeros, e0, e1, S);\n"
    "                gr = road; gk = k; gd = d; gsd = sd; gn = n;\n"
    "            } else {\n"
    "                if (d < gd) { gd = d; gk = k; }\n"
    "                if (sd < gsd) { gsd = sd; gn = n; }\n"
    "            }\n"
    "        }\n",
    /* markings onto S (road pixels), in record order */
    "        {\n"
    "            int m0 = int(texelFetch(u_mstart, cell).r), m1 = int(texelFetch(u_mstart, cell + 1).r);\n"
    "            for (int e = m0; e < m1; e++) {\n"
    "                int mi = int(texelFetch(u_mids, e).r);\n"
    "                vec4 M0 = texelFetch(u_mark, 3 * mi), M1 = texelFetch(u_mark, 3 * mi + 1), M2 = texelFetch(u_mark, 3 * mi + 2);\n",
    "                float mlv = rank_level(texelFetch(u_roadt, 10 * int(M0.x) + 7).z);\n"
    "                float mst = texelFetch(u_roadt, 10 * int(M0.x) + 6).x;\n"
    "                if ((st1 != mst && lv1 > mlv) || lv2 > mlv) continue;\n"
    "                int mk = M2.y >= 0.0 ? stroke_nearest(p, M2.y, e0, e1) : road_nearest(p, int(M0.x), e0, e1);\n"
    "                if (mk < 0) continue;\n"
    "                float sgn = M1.z != 0.0 ? -1.0 : 1.0;\n"
    "                float ms, mt, mef; vec2 mnt, mtg;\n"
    "                road_coords(p, mk, ms, mt, mnt, mtg, mef);\n"
    "                float ds = ms - M0.z, dt = mt - M0.w;\n"
    "                vec2 xy = vec2((M1.y - sgn * dt) * M1.w, (M1.x - sgn * ds) * M2.x);\n"
    "                vec2 mn = vec2(mtg.y, -mtg.x), kk = -sgn * vec2(M1.w, M2.x);\n"
    "                vec2 e1 = kk * vec2(dot(dpx, mn), dot(dpx, mtg)), e2 = kk * vec2(dot(dpy, mn), dot(dpy, mtg));\n"
    "                vec2 reach = 0.5 * (abs(e1) + abs(e2)) + 1.0;\n"
    "                if (xy.x < -reach.x || xy.y < -reach.y || xy.x > 2.0 * M1.y * M1.w + reach.x || xy.y > 2.0 * M1.x * M2.x + reach.y) continue;\n"
    "                vec4 c = atlas_box(int(M0.y), xy, e1, e2);\n"
    "                if (c.a > 0.0) S = S * (1.0 - c.a) + c.rgb;\n"
    "            }\n"
    "        }\n",
    /* a bridge's casing over the roads below it (lib/splat/overlays.c
     * decks): the casing band of the cased roads of level lvc, less the
     * surfaces that hide it (level lvc or higher, or its stroke), over the
     * part of R the roads below hold; onto S after the lines and markings */
    "        if (lvc > lvlo) {\n"
    "            float UD = 0.0, UH = 0.0, dX = 1e30, dsd = 1e30, dcd = 1e30, dw = 0.0;\n"
    "            vec2 ND = vec2(1.0, 0.0), NH = ND, dn = ND, dcn = ND; int roadX = -1, dr = -1;\n"
    "            for (int e = e0; e <= e1; e++) {\n"
    "                float d = 0.0, sd = 1e30, u = 0.0, side = 0.0; vec2 n = vec2(1.0, 0.0);\n"
    "                Seg s; s.road = -2; s.cw = 0.0; s.len = 0.0;\n"
    "                if (e < e1) s = seg_at(p, int(texelFetch(u_cseg, e).r), d, sd, n, u, side);\n"
    "                float sdc = sd - s.cw; vec2 nc = n;\n"
    "                if (e < e1 && (s.flags & 7) != 0) sdc = tee_trim(s, p, u, side, s.cw, nc, d - s.r - s.cw);\n"
    "                if (s.road != dr) {\n"
    "                    if (dr >= 0) {\n"
    "                        float rl = rank_level(texelFetch(u_roadt, 10 * dr + 7).z);\n"
    "                        if (dw > 0.0 && rl == lvc) union_add(UD, ND, cdf(-dcd, dcn), dcn);\n"
    "                        if (rl >= lvc || texelFetch(u_roadt, 10 * dr + 6).x == stc) union_add(UH, NH, cdf(-dsd, dn), dn);\n"
    "                    }\n"
    "                    dr = s.road; dsd = sd; dn = n; dcd = sdc; dcn = nc; dw = s.cw;\n"
    "                } else {\n"
    "                    if (sd < dsd) { dsd = sd; dn = n; }\n"
    "                    if (sdc < dcd) { dcd = sdc; dcn = nc; }\n"
    "                }\n"
    "                if (e == e1) break;\n"
    "                if (s.cw > 0.0 && sdc <= near_reach && d < dX) {\n"
    "                    if (rank_level(texelFetch(u_roadt, 10 * s.road + 7).z) == lvc) { dX = d; roadX = s.road; }\n"
    "                }\n"
    "            }\n"
    "            float H = min(UH, 1.0), over = min(min(UD, 1.0) - H, R - H);\n"
    "            if (over > 0.0 && roadX >= 0) {\n"
    "                vec4 cc = texelFetch(u_roadt, 10 * roadX + 5);\n"
    "                float a = clamp(over / R, 0.0, 1.0) * cc.a;\n"
    "                S = S * (1.0 - a) + cc.rgb * a;\n"
    "            }\n"
    "        }\n"
    "        }\n"
    "    }\n"
    "    vec3 col = (R <= 0.0 ? T : (R >= 1.0 ? S : (1.0 - R) * T + R * S)) / 255.0;\n"
    "    col = min(col, vec3(1.0));\n"
    "    if (u_lighting != 0) {\n"
    "        vec3 n = normalize(v_nrm);\n"
    "        if (u_nmap != 0) { vec3 m = textureGrad(u_normal, uv, duvx, duvy).rgb * 2.0 - 1.0; n = normalize(vec3(m.x, -m.y, m.z)); }\n"
    "        col *= u_amb + u_dif * max(dot(n, u_sun), 0.0);\n"
    "    }\n"
    "    if (u_fog != 0) {\n"
    "        float f = clamp((u_fogr.y - v_dist) / (u_fogr.y - u_fogr.x), 0.0, 1.0);\n"
    "        col = mix(u_fogc, col, f);\n"
    "    }\n"
    "    o_col = vec4(col, 1.0);\n"
    "}\n"
};

/* The sky: a full-screen triangle pair, coloured by the elevation of the
 * ray through each pixel (the texture mode's 64 bands, per pixel). */
static const char rsh_sky_vs_src[] =
    "#version 330 core\n"
    "layout(location = 0) in vec2 a_ndc;\n"
    "out vec2 v_ndc;\n"
    "void main() { v_ndc = a_ndc; gl_Position = vec4(a_ndc, 0.999, 1.0); }\n";

static const char rsh_sky_fs_src[] =
    "#version 330 core\n"
    "in vec2 v_ndc;\n"
    "out vec4 o_col;\n"
    "uniform vec3 u_f, u_s, u_u;\n" /* camera basis, GL frame (y up) */
    "uniform vec2 u_tan;\n"         /* tan of the half fields of view, x and y */
    "const vec3 zenith = vec3(0.22, 0.42, 0.78), horizon = vec3(0.78, 0.85, 0.93), haze = vec3(0.62, 0.66, 0.70);\n"
    "void main() {\n"
    "    vec3 d = normalize(u_f + u_s * v_ndc.x * u_tan.x + u_u * v_ndc.y * u_tan.y);\n"
    "    vec3 c;\n"
    "    if (d.y <= 0.0) c = mix(horizon, haze, min(1.0, -d.y / 0.15));\n"
    "    else c = mix(horizon, zenith, sqrt(min(1.0, d.y / 0.7)));\n"
    "    o_col = vec4(c, 1.0);\n"
    "}\n";

static const char *const rsh_vs[] = { rsh_vs_src };
static const char *const rsh_sky_vs[] = { rsh_sky_vs_src };
static const char *const rsh_sky_fs[] = { rsh_sky_fs_src };

const char *const *rs_gpu_glsl(uint32_t version, rs_gpu_shader which, size_t *count)
{
    size_t n = 0;
    const char *const *src = NULL;
    if (version == 330) {
        switch (which) {
        case RS_GPU_SHADER_TERRAIN_VERTEX: src = rsh_vs, n = 1; break;
        case RS_GPU_SHADER_TERRAIN_FRAGMENT: src = rsh_fs_src, n = sizeof rsh_fs_src / sizeof rsh_fs_src[0]; break;
        case RS_GPU_SHADER_SKY_VERTEX: src = rsh_sky_vs, n = 1; break;
        case RS_GPU_SHADER_SKY_FRAGMENT: src = rsh_sky_fs, n = 1; break;
        default: break;
        }
    }
    if (count) *count = n;
    return src;
}
