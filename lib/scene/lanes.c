/* Lanes per direction (issue 27; lib/scene/lanes.h, docs/road-format.md "Lanes").
 *
 * A road's lanes are laid out in the frame of its main direction of
 * travel (u: + left of travel; the points' direction unless the road is
 * one-way against them), strips, then lanes from the travel-left edge, as
 * the default styles always did, then turned into the points' frame (t). */
#include "lanes.h"
#include "network.h"

#include <math.h>
#include <string.h>

#define DIR_MAX 16 /* lanes per direction (as `lanes=`) */

int rs__lanes_oneway(rs_road_class c, rs_oneway o)
{
    if (o == RS_ONEWAY_NONE) return c == RS_CLASS_MOTORWAY ? 1 : 0;
    return o == RS_ONEWAY_YES ? 1 : o == RS_ONEWAY_REVERSE ? -1 : 0;
}

rs_driving_side rs__driving_side(const rs_roads *roads, size_t i, rs_driving_side side_default)
{
    const char *v = rs_roads_get_attr(roads, i, "driving_side");
    if (v && !strcmp(v, "left")) return RS_DRIVING_LEFT;
    if (v && !strcmp(v, "right")) return RS_DRIVING_RIGHT;
    return side_default == RS_DRIVING_LEFT ? RS_DRIVING_LEFT : RS_DRIVING_RIGHT;
}

/* A lane count 1..16 written as digits, else 0. */
static uint32_t count_attr(const char *v)
{
    if (!v || !*v || strlen(v) > 2) return 0;
    uint32_t n = 0;
    for (; *v; v++) {
        if (*v < '0' || *v > '9') return 0;
        n = 10 * n + (uint32_t)(*v - '0');
    }
    return n >= 1 && n <= DIR_MAX ? n : 0;
}

/* Entries of a `|` list (0 for NULL). */
static uint32_t entries(const char *v)
{
    if (!v) return 0;
    uint32_t n = 1;
    for (; *v; v++) n += *v == '|';
    return n;
}

/* One `turn:lanes` entry ([v, v + n)) to RS_TURN_* flags. */
static uint32_t turn_flags(const char *v, size_t n)
{
    uint32_t f = 0;
    for (size_t i = 0; i < n;) {
        size_t j = i;
        while (j < n && v[j] != ';') j++;
        size_t k = j - i;
        const char *w = v + i;
        if ((k == 4 && !memcmp(w, "left", 4)) || (k == 11 && !memcmp(w, "slight_left", 11)) ||
            (k == 10 && !memcmp(w, "sharp_left", 10)))
            f |= RS_TURN_LEFT;
        else if ((k == 5 && !memcmp(w, "right", 5)) || (k == 12 && !memcmp(w, "slight_right", 12)) ||
                 (k == 11 && !memcmp(w, "sharp_right", 11)))
            f |= RS_TURN_RIGHT;
        else if (k == 7 && !memcmp(w, "through", 7)) f |= RS_TURN_THROUGH;
        else if (k == 7 && !memcmp(w, "reverse", 7)) f |= RS_TURN_REVERSE;
        i = j + 1;
    }
    return f;
}

/* The flags of a turn list's entries into f[0 .. n-1]; 0 if the list does
 * not have n entries. */
static int turn_list(const char *v, uint32_t n, uint32_t *f)
{
    if (!v || entries(v) != n) return 0;
    for (uint32_t k = 0; k < n; k++) {
        const char *bar = strchr(v, '|');
        size_t len = bar ? (size_t)(bar - v) : strlen(v);
        f[k] = turn_flags(v, len);
        if (bar) v = bar + 1;
    }
    return 1;
}

/* `width:lanes`: n positive widths (metres, at most 100 each), else 0. */
static int width_list(const char *v, uint32_t n, double *w)
{
    if (!v || entries(v) != n) return 0;
    for (uint32_t k = 0; k < n; k++) {
        const char *bar = strchr(v, '|'), *e = bar ? bar : v + strlen(v), *stop;
        double x;
        /* locale-independent, the whole entry */
        if (!rs__parse_double(v, e, &x, &stop) || stop != e || !(x > 0 && x <= 100)) return 0;
        w[k] = x;
        v = bar ? bar + 1 : e;
    }
    return 1;
}

void rs__lanes_input(const rs_roads *roads, size_t i, rs_profile profile, rs_driving_side side_default,
                     rs__lanes_in *in)
{
    rs_road_info info;
    memset(in, 0, sizeof *in);
    if (rs_roads_get_info(roads, i, &info) != RS_OK) return;
    rs_roads_get(roads, i, NULL, &in->width, NULL, NULL);
    in->road_class = info.road_class;
    in->profile = profile;
    in->oneway = rs__road_oneway(roads, i, &info);
    in->side = rs__driving_side(roads, i, side_default);
    in->lanes = info.lanes;
    in->forward = count_attr(rs_roads_get_attr(roads, i, "lanes:forward"));
    in->backward = count_attr(rs_roads_get_attr(roads, i, "lanes:backward"));
    in->turn = rs_roads_get_attr(roads, i, "turn:lanes");
    in->turn_forward = rs_roads_get_attr(roads, i, "turn:lanes:forward");
    in->turn_backward = rs_roads_get_attr(roads, i, "turn:lanes:backward");
    in->width_lanes = rs_roads_get_attr(roads, i, "width:lanes");
}

void rs__lanes_layout(const rs__lanes_in *in, rs_road_lanes *out, double strip[2])
{
    memset(out, 0, sizeof *out);
    rs_profile prof = in->profile == RS_PROFILE_MUTCD ? RS_PROFILE_MUTCD : RS_PROFILE_RMS;
    rs_road_class c = (unsigned)in->road_class < RS_CLASS_COUNT ? in->road_class : RS_CLASS_NONE;
    int ow = rs__lanes_oneway(c, in->oneway), left = in->side == RS_DRIVING_LEFT;
    uint32_t deflanes;
    double lane, sl, sr;
    rs__section(prof, c, &deflanes, &lane, &sl, &sr);
    if (!deflanes) deflanes = 1;
    /* strips left and right of travel: one-way roads as the table (mirrored
     * for left-hand traffic: the hard shoulder on the left), two-way roads
     * the outer strip on both sides */
    if (!ow) sl = sr;
    else if (left) {
        double x = sl;
        sl = sr;
        sr = x;
    }
    const char *tlist_f = ow < 0 ? NULL : in->turn_forward ? in->turn_forward : in->turn;
    const char *tlist_b = ow < 0 ? (in->turn_backward ? in->turn_backward : in->turn) : in->turn_backward;
    uint32_t tf = entries(tlist_f), tb = entries(tlist_b);
    if (tf > DIR_MAX) tf = 0;
    if (tb > DIR_MAX) tb = 0;
    uint32_t nf = 0, nb = 0, both = 0, N = in->lanes && in->lanes <= DIR_MAX ? in->lanes : 0;
    if (ow > 0) nf = N ? N : in->forward ? in->forward : tf ? tf : deflanes;
    else if (ow < 0) nb = N ? N : in->backward ? in->backward : tb ? tb : deflanes;
    else {
        if (!N) N = deflanes;
        nf = in->forward ? in->forward : tf;
        nb = in->backward ? in->backward : tb;
        if (nf && !nb) nb = N > nf ? N - nf : 1;
        else if (nb && !nf) nf = N > nb ? N - nb : 1;
        else if (!nf && !nb) {
            if (N == 1) both = 1;
            else {
                nb = N / 2; /* as the default styles always split them */
                nf = N - nb;
            }
        }
    }
    uint32_t n = nf + nb + both;
    /* lanes in the travel frame, from the travel-left edge */
    int8_t dir[RS_LANES_MAX];
    for (uint32_t k = 0; k < n; k++) {
        if (both) dir[k] = 0;
        else if (ow > 0) dir[k] = 1;
        else if (ow < 0) dir[k] = -1;
        else if (left) dir[k] = k < nf ? 1 : -1;
        else dir[k] = k < nb ? -1 : 1;
    }
    double lw[RS_LANES_MAX], given[RS_LANES_MAX];
    double nominal = sl + n * lane + sr;
    double W = in->width > 0 ? in->width : nominal;
    double u[RS_LANES_MAX + 1], st_l, st_r; /* strips left and right of travel */
    int have_w = width_list(in->width_lanes, n, given);
    double sum = 0;
    if (have_w) {
        /* written left to right along the points (one-way: along travel) */
        for (uint32_t k = 0; k < n; k++) lw[k] = given[k], sum += given[k];
    }
    if (have_w && sum <= W) {
        double extra = W - sum, ls = sl + sr > 0 ? extra * sl / (sl + sr) : extra / 2;
        st_l = ls;
        st_r = extra - ls;
        u[0] = W / 2 - ls;
        for (uint32_t k = 0; k < n; k++) u[k + 1] = u[k] - lw[k];
    } else if (have_w) {
        double k = W / sum;
        st_l = st_r = 0;
        u[0] = W / 2;
        for (uint32_t j = 0; j < n; j++) u[j + 1] = u[j] - lw[j] * k;
    } else {
        /* the default styles' layout, to the bit: top - b * lane */
        double k = W / nominal;
        st_l = sl * k;
        st_r = sr * k;
        double top = W / 2 - st_l;
        lane *= k;
        for (uint32_t b = 0; b <= n; b++) u[b] = top - b * lane;
    }
    /* to the points' frame: t = dsign * u, lanes listed from +t */
    double dsign = ow < 0 ? -1.0 : 1.0;
    if (strip) {
        strip[0] = ow < 0 ? st_r : st_l;
        strip[1] = ow < 0 ? st_l : st_r;
    }
    out->count = n;
    out->width = W;
    out->side = left ? RS_DRIVING_LEFT : RS_DRIVING_RIGHT;
    for (uint32_t k = 0; k < n; k++) {
        uint32_t j = ow < 0 ? n - 1 - k : k; /* travel-frame index of point-frame lane k */
        rs_lane *L = &out->lane[k];
        L->t_left = dsign * (ow < 0 ? u[j + 1] : u[j]);
        L->t_right = dsign * (ow < 0 ? u[j] : u[j + 1]);
        L->direction = dir[j];
        out->forward += dir[j] > 0;
        out->backward += dir[j] < 0;
    }
    if (nf && nb) out->centre = u[left ? nf : nb];
    /* turn arrows: forward lanes from their driver's left (+t), backward
     * lanes from theirs (-t) */
    uint32_t f[DIR_MAX];
    if (turn_list(tlist_f, out->forward, f))
        for (uint32_t k = 0, m = 0; k < n; k++)
            if (out->lane[k].direction > 0) out->lane[k].turn = f[m++];
    if (turn_list(tlist_b, out->backward, f))
        for (uint32_t k = n, m = 0; k-- > 0;)
            if (out->lane[k].direction < 0) out->lane[k].turn = f[m++];
}

rs_result rs_road_lanes_get(const rs_roads *roads, size_t i, const rs_style_options *opts, rs_road_lanes *out)
{
    if (!roads || !out || i >= rs_roads_count(roads)) return RS_ERR_INVALID_ARG;
    rs_style_options so;
    rs_result r = RS__OPTS_IN(NULL, opts, &so, rs_style_options);
    if (r) return r;
    rs__lanes_in in;
    rs__lanes_input(roads, i, so.profile, so.driving_side, &in);
    rs__lanes_layout(&in, out, NULL);
    return RS_OK;
}

rs_result rs_network_lanes_at(const rs_network *net, const rs_roads *roads, size_t k, double s,
                              const rs_style_options *opts, size_t *road, rs_road_lanes *out)
{
    if (!net || !roads || !out || k >= net->nstrokes || rs_roads_count(roads) != net->nroads)
        return RS_ERR_INVALID_ARG;
    /* the record holding s: the last whose stroke range starts at or before it */
    uint32_t a = net->stroke_start[k], b = net->stroke_start[k + 1], pick = net->stroke_roads[a];
    for (uint32_t j = a; j < b; j++) {
        uint32_t r = net->stroke_roads[j];
        double s0 = net->rev[r] ? net->s_off[r] - net->length[r] : net->s_off[r];
        if (j == a || s >= s0) pick = r;
        else break;
    }
    if (road) *road = pick;
    rs_result rc = rs_road_lanes_get(roads, pick, opts, out);
    if (rc || !net->rev[pick]) return rc;
    /* seen along the stroke: the record's left is the stroke's right */
    rs_road_lanes m = *out;
    for (uint32_t j = 0; j < m.count; j++) {
        rs_lane *L = &out->lane[j];
        const rs_lane *R = &m.lane[m.count - 1 - j];
        L->t_left = -R->t_right;
        L->t_right = -R->t_left;
        L->direction = -R->direction;
        L->turn = R->turn;
    }
    out->forward = m.backward;
    out->backward = m.forward;
    out->centre = m.centre != 0 ? -m.centre : 0;
    return RS_OK;
}
