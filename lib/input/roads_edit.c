/* Edits of a road set (issue 30): remove a road, replace its geometry,
 * width and name, set or remove a point attribute. The storage is
 * lib/input/roads.c's (lib/input/roads_impl.h). Strings a removed or
 * replaced road leaves in the pool stay there until the set is freed, as
 * rs_roads_set_attr's replaced values do. */
#include "roads_impl.h"
#include "style.h"

#include <math.h>
#include <string.h>

rs_result rs_roads_remove(rs_ctx *ctx, rs_roads *roads, size_t i)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!roads) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_remove: roads is NULL");
    if (i >= roads->count)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_remove: road %zu out of range (%zu roads)", i, roads->count);
    rs_road_rec gone = roads->roads[i];
    /* its points out of the shared array; later roads' slices move down */
    memmove(roads->xy + 2 * gone.first, roads->xy + 2 * (gone.first + gone.n),
            (roads->points - gone.first - gone.n) * 2 * sizeof(double));
    roads->points -= gone.n;
    memmove(roads->roads + i, roads->roads + i + 1, (roads->count - i - 1) * sizeof *roads->roads);
    roads->count--;
    for (size_t k = 0; k < roads->count; k++)
        if (roads->roads[k].first > gone.first) roads->roads[k].first -= gone.n;
    /* its markings and point attributes dropped, later roads' renumbered */
    size_t w = 0;
    for (size_t k = 0; k < roads->marks_len; k++) {
        rs_mark_rec m = roads->marks[k];
        if (m.road == i) continue;
        if (m.road > i && m.road != SIZE_MAX) m.road--;
        roads->marks[w++] = m;
    }
    roads->marks_len = w;
    w = 0;
    for (size_t k = 0; k < roads->pattrs_len; k++) {
        rs_point_attr a = roads->pattrs[k];
        if (a.road == i) continue;
        if (a.road > i) a.road--;
        roads->pattrs[w++] = a;
    }
    roads->pattrs_len = w;
    rs__ok(ctx);
    return RS_OK;
}

rs_result rs_roads_replace(rs_ctx *ctx, rs_roads *roads, size_t i, const char *name, double width, const double *xy,
                           size_t n)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!roads) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_replace: roads is NULL");
    if (i >= roads->count)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_replace: road %zu out of range (%zu roads)", i,
                        roads->count);
    rs_result g = rs__roads_check_geometry(ctx, "rs_roads_replace", width, xy, n);
    if (g) return g;
    rs_road_rec *rec = &roads->roads[i];
    size_t others = roads->points - rec->n;
    if (n > ctx->limits.max_points || others > ctx->limits.max_points - n)
        return rs__fail(ctx, RS_ERR_LIMIT, "rs_roads_replace: more than %llu road points in total",
                        (unsigned long long)ctx->limits.max_points);
    /* the new points into a buffer of their own first: xy may be one of
     * this set's roads, which the move below shifts */
    double *tmp = rs__alloc_array(ctx, n, 2 * sizeof(double));
    if (!tmp) return rs__fail(ctx, RS_ERR_NOMEM, "rs_roads_replace: out of memory for %zu points", n);
    memcpy(tmp, xy, n * 2 * sizeof(double));
    size_t name_off = rec->name, names_len = roads->names_len;
    if (name) {
        name_off = rs__roads_pool_add(ctx, roads, name, strlen(name));
        if (name_off == SIZE_MAX) {
            rs__free(ctx, tmp);
            return rs__fail(ctx, RS_ERR_NOMEM, "rs_roads_replace: out of memory");
        }
    }
    if (n > rec->n) {
        double *pts = rs__roads_grow(ctx, roads->xy, &roads->points_cap, others + n, 2 * sizeof(double));
        if (!pts) {
            rs__free(ctx, tmp);
            roads->names_len = names_len;
            return rs__fail(ctx, RS_ERR_NOMEM, "rs_roads_replace: out of memory for %zu points", n);
        }
        roads->xy = pts;
    }
    size_t first = rec->first, old_n = rec->n;
    memmove(roads->xy + 2 * (first + n), roads->xy + 2 * (first + old_n),
            (roads->points - first - old_n) * 2 * sizeof(double));
    memcpy(roads->xy + 2 * first, tmp, n * 2 * sizeof(double));
    rs__free(ctx, tmp);
    roads->points = others + n;
    for (size_t k = 0; k < roads->count; k++)
        if (roads->roads[k].first > first) roads->roads[k].first = roads->roads[k].first - old_n + n;
    rec->n = n;
    rec->width = width;
    rec->width_given = 1;
    rec->name = name_off;
    rs__roads_reprint(roads, i);
    /* point attributes past the new last point go */
    size_t w = 0;
    for (size_t k = 0; k < roads->pattrs_len; k++)
        if (roads->pattrs[k].road != i || roads->pattrs[k].point < n) roads->pattrs[w++] = roads->pattrs[k];
    roads->pattrs_len = w;
    rs__ok(ctx);
    return RS_OK;
}

rs_result rs_roads_set_point_attr(rs_ctx *ctx, rs_roads *roads, size_t i, size_t point, const char *key,
                                  const char *value)
{
    char q[64];
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!roads || !key) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_set_point_attr: roads or key is NULL");
    if (i >= roads->count)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_set_point_attr: road %zu out of range (%zu roads)", i,
                        roads->count);
    if (point >= roads->roads[i].n)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_set_point_attr: point %zu out of range (road %zu has %zu)",
                        point, i, roads->roads[i].n);
    size_t kn = strlen(key);
    if (!rs__roads_key_ok(key, kn))
        return rs__fail(ctx, RS_ERR_INVALID_ARG,
                        "rs_roads_set_point_attr: key %s must be 1..%d characters of A-Z a-z 0-9 _ : . -",
                        rs__quote(q, sizeof q, key, kn), MAX_KEY);
    size_t have = SIZE_MAX;
    for (size_t k = 0; k < roads->pattrs_len && have == SIZE_MAX; k++) {
        const rs_point_attr *a = &roads->pattrs[k];
        if (a->road == i && a->point == point && strcmp(roads->names + a->key, key) == 0) have = k;
    }
    if (!value) { /* remove */
        if (have != SIZE_MAX) {
            memmove(roads->pattrs + have, roads->pattrs + have + 1,
                    (roads->pattrs_len - have - 1) * sizeof *roads->pattrs);
            roads->pattrs_len--;
        }
        rs__ok(ctx);
        return RS_OK;
    }
    size_t vn = strlen(value);
    if (vn == 0)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_set_point_attr: point attribute %s has no value",
                        rs__quote(q, sizeof q, key, kn));
    rs_result r = rs__roads_value_check(ctx, "rs_roads_set_point_attr", value, vn);
    if (r) return r;
    size_t names_len = roads->names_len;
    size_t voff = rs__roads_pool_add(ctx, roads, value, vn);
    if (voff == SIZE_MAX) return rs__fail(ctx, RS_ERR_NOMEM, "rs_roads_set_point_attr: out of memory");
    if (have != SIZE_MAX) {
        roads->pattrs[have].value = voff;
        rs__ok(ctx);
        return RS_OK;
    }
    size_t koff = rs__roads_pool_add(ctx, roads, key, kn);
    rs_point_attr *a = koff == SIZE_MAX ? NULL
                       : rs__roads_grow(ctx, roads->pattrs, &roads->pattrs_cap, roads->pattrs_len + 1, sizeof *a);
    if (!a) {
        roads->names_len = names_len;
        return rs__fail(ctx, RS_ERR_NOMEM, "rs_roads_set_point_attr: out of memory");
    }
    roads->pattrs = a;
    a[roads->pattrs_len].road = i;
    a[roads->pattrs_len].point = point;
    a[roads->pattrs_len].key = koff;
    a[roads->pattrs_len].value = voff;
    roads->pattrs_len++;
    rs__ok(ctx);
    return RS_OK;
}

rs_result rs__roads_subset(rs_ctx *ctx, const rs_roads *roads, const uint32_t *ids, size_t n, rs_roads **out)
{
    *out = NULL;
    rs_roads *S = rs__calloc(ctx, 1, sizeof *S);
    size_t *map = rs__alloc_array(ctx, roads->count ? roads->count : 1, sizeof *map);
    size_t np = 0, na = 0;
    for (size_t i = 0; ids && i < n; i++) {
        if (ids[i] >= roads->count || (i && ids[i] <= ids[i - 1])) {
            rs__free(ctx, S);
            rs__free(ctx, map);
            return rs__fail(ctx, RS_ERR_INVALID_ARG, "road subset: road ids not ascending or out of range");
        }
    }
    for (size_t i = 0; i < n && i < roads->count; i++) {
        np += roads->roads[ids ? ids[i] : i].n;
        na += roads->roads[ids ? ids[i] : i].attr_count;
    }
    if (S) {
        /* (the string pool whole: every offset stays valid) */
        S->roads = rs__alloc_array(ctx, n ? n : 1, sizeof *S->roads);
        S->xy = rs__alloc_array(ctx, np ? np : 1, 2 * sizeof *S->xy);
        S->names = rs__alloc_array(ctx, roads->names_len ? roads->names_len : 1, 1);
        S->attrs = rs__alloc_array(ctx, na ? na : 1, sizeof *S->attrs);
        S->marks = rs__alloc_array(ctx, roads->marks_len ? roads->marks_len : 1, sizeof *S->marks);
        S->pattrs = rs__alloc_array(ctx, roads->pattrs_len ? roads->pattrs_len : 1, sizeof *S->pattrs);
    }
    if (!S || !map || !S->roads || !S->xy || !S->names || !S->attrs || !S->marks || !S->pattrs) {
        rs__free(ctx, map);
        if (S) rs_roads_free(ctx, S);
        return rs__fail(ctx, RS_ERR_NOMEM, "road subset: out of memory");
    }
    S->cap = n ? n : 1, S->points_cap = np ? np : 1, S->names_cap = roads->names_len ? roads->names_len : 1;
    S->attrs_cap = na ? na : 1, S->marks_cap = roads->marks_len ? roads->marks_len : 1;
    S->pattrs_cap = roads->pattrs_len ? roads->pattrs_len : 1;
    if (roads->names_len) memcpy(S->names, roads->names, roads->names_len);
    S->names_len = roads->names_len;
    S->frame = roads->frame;
    S->frame_crs = roads->frame_crs;
    for (size_t r = 0; r < roads->count; r++) map[r] = SIZE_MAX;
    for (size_t i = 0; i < n; i++) {
        rs_road_rec rec = roads->roads[ids ? ids[i] : i];
        map[ids ? ids[i] : i] = i;
        memcpy(S->xy + 2 * S->points, roads->xy + 2 * rec.first, rec.n * 2 * sizeof *S->xy);
        if (rec.attr_count) memcpy(S->attrs + S->attrs_len, roads->attrs + rec.attr_first, rec.attr_count * sizeof *S->attrs);
        rec.first = S->points;
        rec.attr_first = S->attrs_len;
        S->points += rec.n;
        S->attrs_len += rec.attr_count;
        S->roads[S->count++] = rec;
    }
    for (size_t k = 0; k < roads->marks_len; k++) {
        rs_mark_rec m = roads->marks[k];
        if (m.road >= roads->count || map[m.road] == SIZE_MAX) continue;
        m.road = map[m.road];
        S->marks[S->marks_len++] = m;
    }
    for (size_t k = 0; k < roads->pattrs_len; k++) {
        rs_point_attr a = roads->pattrs[k];
        if (a.road >= roads->count || map[a.road] == SIZE_MAX) continue;
        a.road = map[a.road];
        S->pattrs[S->pattrs_len++] = a;
    }
    rs__free(ctx, map);
    *out = S;
    return RS_OK;
}

rs_result rs_roads_copy(rs_ctx *ctx, const rs_roads *roads, rs_roads **out)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (out) *out = NULL;
    if (!roads || !out) return rs__fail(ctx, RS_ERR_INVALID_ARG, "NULL argument to rs_roads_copy");
    rs_result r = rs__roads_subset(ctx, roads, NULL, roads->count, out);
    if (r) return rs__fail(ctx, r, "rs_roads_copy: out of memory");
    rs__ok(ctx);
    return RS_OK;
}
