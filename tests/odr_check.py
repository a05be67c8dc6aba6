#!/usr/bin/env python3
"""Independent check of `roadsplat convert X.xodr OUT.txt` (issue 32, docs/opendrive.md).

Reads the .xodr with Python's own XML parser and evaluates the reference
lines by numeric integration (Simpson steps of the heading for lines, arcs
and spirals, RK4 of du/ds for poly3, closed form for paramPoly3), none of
which the library uses (it evaluates Fresnel integrals and Gauss-Legendre).
Then, for the road text the CLI wrote:

  * every road-mark record (name ROAD/SECTION/laneK, attribute t_offset)
    lies within TOL of its exact curve, boundary of lane K + t_offset, and
    the exact curve over the record's s range lies within TOL of the record;
  * every surface piece (ROAD/SECTION/surface[L,R]): the exact outer
    boundaries L and R lie within TOL of the edge of the union of the
    section's pieces (signed distance of the capsules);
  * dashes of broken marks start at s_offset + k * period of the road's s
    (the phase runs on through lane sections) or at the start of their
    mark, and are `on` long or cut by the mark's end.

usage: odr_check.py FILE.xodr CONVERTED.txt   (exit 1 on a failure)
"""
import math
import sys
import xml.etree.ElementTree as ET

TOL = 0.02
OFFSET = (0.0, 0.0, 0.0)
STEP = 0.01  # integration step, metres


def fl(e, k, d=None):
    v = e.get(k)
    return float(v) if v is not None else d


class Geom:
    def __init__(self, e):
        self.s, self.x, self.y, self.hdg, self.len = (fl(e, k) for k in ("s", "x", "y", "hdg", "length"))
        k = list(e)[0]
        self.kind = k.tag
        self.a = dict((n, float(v)) for n, v in k.attrib.items() if n != "pRange")
        self.normalized = k.get("pRange", "normalized") == "normalized"
        if self.kind in ("line", "arc", "spiral"):
            self._table_heading()
        elif self.kind == "poly3":
            self._table_poly3()

    def theta(self, ds):  # heading along lines, arcs, spirals
        if self.kind == "line":
            return self.hdg
        if self.kind == "arc":
            return self.hdg + self.a["curvature"] * ds
        k0, k1 = self.a["curvStart"], self.a["curvEnd"]
        return self.hdg + k0 * ds + 0.5 * (k1 - k0) / self.len * ds * ds

    def _table_heading(self):
        n = max(1, int(math.ceil(self.len / STEP)))
        self.h = self.len / n
        xs, ys = [self.x], [self.y]
        for i in range(n):
            a, b = i * self.h, (i + 1) * self.h
            m = 0.5 * (a + b)
            ta, tm, tb = self.theta(a), self.theta(m), self.theta(b)
            xs.append(xs[-1] + self.h / 6 * (math.cos(ta) + 4 * math.cos(tm) + math.cos(tb)))
            ys.append(ys[-1] + self.h / 6 * (math.sin(ta) + 4 * math.sin(tm) + math.sin(tb)))
        self.xs, self.ys = xs, ys

    def _vp(self, u):
        a = self.a
        return a["b"] + 2 * a["c"] * u + 3 * a["d"] * u * u

    def _table_poly3(self):
        # du/ds = 1 / sqrt(1 + v'(u)^2), RK4
        n = max(1, int(math.ceil(self.len / STEP)))
        self.h = self.len / n
        f = lambda u: 1 / math.sqrt(1 + self._vp(u) ** 2)
        us = [0.0]
        for _ in range(n):
            u = us[-1]
            k1 = f(u)
            k2 = f(u + 0.5 * self.h * k1)
            k3 = f(u + 0.5 * self.h * k2)
            k4 = f(u + self.h * k3)
            us.append(u + self.h / 6 * (k1 + 2 * k2 + 2 * k3 + k4))
        self.us = us

    def eval(self, ds):
        ds = min(max(ds, 0.0), self.len)
        c, s = math.cos(self.hdg), math.sin(self.hdg)
        if self.kind in ("line", "arc", "spiral"):
            i = min(int(ds / self.h), len(self.xs) - 2)
            a, b = i * self.h, ds
            m = 0.5 * (a + b)
            ta, tm, tb = self.theta(a), self.theta(m), self.theta(b)
            x = self.xs[i] + (b - a) / 6 * (math.cos(ta) + 4 * math.cos(tm) + math.cos(tb))
            y = self.ys[i] + (b - a) / 6 * (math.sin(ta) + 4 * math.sin(tm) + math.sin(tb))
            return x, y, tb
        if self.kind == "poly3":
            i = min(int(ds / self.h), len(self.us) - 2)
            u = self.us[i]
            r = ds - i * self.h  # one RK4 step from the table
            f = lambda q: 1 / math.sqrt(1 + self._vp(q) ** 2)
            k1 = f(u); k2 = f(u + 0.5 * r * k1); k3 = f(u + 0.5 * r * k2); k4 = f(u + r * k3)
            u += r / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            a = self.a
            v = a["a"] + a["b"] * u + a["c"] * u * u + a["d"] * u ** 3
            return self.x + c * u - s * v, self.y + s * u + c * v, self.hdg + math.atan(self._vp(u))
        a = self.a  # paramPoly3
        p = ds / self.len if self.normalized else ds
        u = a["aU"] + a["bU"] * p + a["cU"] * p * p + a["dU"] * p ** 3
        v = a["aV"] + a["bV"] * p + a["cV"] * p * p + a["dV"] * p ** 3
        du = a["bU"] + 2 * a["cU"] * p + 3 * a["dU"] * p * p
        dv = a["bV"] + 2 * a["cV"] * p + 3 * a["dV"] * p * p
        return self.x + c * u - s * v, self.y + s * u + c * v, self.hdg + math.atan2(dv, du)


def poly_at(polys, s):
    """polys: [(s0, a, b, c, d)] sorted; the last with s0 <= s (the first before all)."""
    if not polys:
        return 0.0
    cur = polys[0]
    for p in polys:
        if p[0] <= s:
            cur = p
    d = s - cur[0]
    return cur[1] + cur[2] * d + cur[3] * d * d + cur[4] * d ** 3


class Road:
    def __init__(self, e):
        self.id = e.get("id")
        self.length = fl(e, "length")
        self.geoms = [Geom(g) for g in e.find("planView").findall("geometry")]
        lanes = e.find("lanes")
        self.offset = [(fl(o, "s"), fl(o, "a"), fl(o, "b"), fl(o, "c"), fl(o, "d")) for o in lanes.findall("laneOffset")]
        self.sections = []
        for sec in lanes.findall("laneSection"):
            s0 = fl(sec, "s")
            ls = {}
            for side in sec:
                for ln in side.findall("lane"):
                    lid = int(ln.get("id"))
                    w = [(s0 + fl(x, "sOffset"), fl(x, "a"), fl(x, "b"), fl(x, "c"), fl(x, "d")) for x in ln.findall("width")]
                    marks = []
                    for m in ln.findall("roadMark"):
                        t = m.find("type")
                        lines = [dict((k, float(v)) for k, v in l.attrib.items() if k in ("length", "space", "tOffset", "sOffset", "width"))
                                 for l in t.findall("line")] if t is not None else []
                        marks.append({"s": s0 + fl(m, "sOffset"), "type": m.get("type"), "lines": lines})
                    ls[lid] = {"type": ln.get("type"), "w": w, "marks": marks}
            self.sections.append({"s": s0, "lanes": ls})
        for i, sec in enumerate(self.sections):
            sec["e"] = self.sections[i + 1]["s"] if i + 1 < len(self.sections) else self.length

    def ref(self, s):
        g = self.geoms[0]
        for q in self.geoms:
            if q.s <= s:
                g = q
        return g.eval(s - g.s)

    def boundary(self, sec, lid, s):
        t = poly_at(self.offset, s)
        L = sec["lanes"]
        if lid > 0:
            for k in range(1, lid + 1):
                if k in L:
                    t += poly_at(L[k]["w"], s)
        elif lid < 0:
            for k in range(-1, lid - 1, -1):
                if k in L:
                    t -= poly_at(L[k]["w"], s)
        return t

    def point(self, s, t):
        x, y, h = self.ref(s)
        x, y = x - t * math.sin(h), y + t * math.cos(h)
        ox, oy, oh = OFFSET  # header <offset>: local to georeferenced
        return ox + math.cos(oh) * x - math.sin(oh) * y, oy + math.sin(oh) * x + math.cos(oh) * y


def seg_dist(px, py, ax, ay, bx, by):
    dx, dy = bx - ax, by - ay
    L2 = dx * dx + dy * dy
    u = 0.0 if L2 == 0 else max(0.0, min(1.0, ((px - ax) * dx + (py - ay) * dy) / L2))
    return math.hypot(px - ax - u * dx, py - ay - u * dy)


def poly_dist(p, pts):
    return min(seg_dist(p[0], p[1], *pts[i], *pts[i + 1]) for i in range(len(pts) - 1))


def read_text(path):
    recs, cur = [], None
    for line in open(path):
        line = line.strip()
        if line.startswith("road "):
            q1 = line.index('"')
            q2 = line.index('"', q1 + 1)
            name = line[q1 + 1:q2]
            rest = line[q2 + 1:].split()
            attrs = dict(w.split("=", 1) for w in rest if "=" in w)
            cur = {"name": name, "width": float(rest[1]), "attrs": attrs, "pts": []}
        elif line == "end":
            if cur is not None:
                recs.append(cur)
            cur = None
        elif cur is not None and line:
            x, y = line.split()[:2]
            cur["pts"].append((float(x), float(y)))
    return recs


def nearest_s(road, t_of, p, s0, s1):
    """s in [s0, s1] whose curve point is nearest p (coarse scan, then golden refinement)."""
    n = max(2, int((s1 - s0) / 0.05))
    best = min(range(n + 1), key=lambda i: math.dist(road.point(s0 + (s1 - s0) * i / n, t_of(s0 + (s1 - s0) * i / n)), p))
    a = max(s0, s0 + (s1 - s0) * (best - 1) / n)
    b = min(s1, s0 + (s1 - s0) * (best + 1) / n)
    f = lambda s: math.dist(road.point(s, t_of(s)), p)
    for _ in range(60):
        m1, m2 = a + (b - a) * 0.382, a + (b - a) * 0.618
        if f(m1) < f(m2):
            b = m2
        else:
            a = m1
    s = 0.5 * (a + b)
    return s, f(s)


def main():
    xodr, txt = sys.argv[1], sys.argv[2]
    global OFFSET
    root = ET.parse(xodr).getroot()
    off = root.find("header/offset")
    if off is not None:
        OFFSET = (fl(off, "x", 0.0), fl(off, "y", 0.0), fl(off, "hdg", 0.0))
    roads = {r.get("id"): Road(r) for r in root.findall("road")}
    recs = read_text(txt)
    fails, worst_mark, worst_surf, nmark, nsurf, ndash = 0, 0.0, 0.0, 0, 0, 0
    surf_groups = {}
    for rec in recs:
        rid, sec_i, kind = rec["name"].rsplit("/", 2)
        road = roads[rid]
        if sec_i == "obj":
            continue
        sec = road.sections[int(sec_i)]
        if kind.startswith("lane"):
            lid = int(kind[4:])
            dt = float(rec["attrs"].get("t_offset", 0))
            t_of = lambda s, sec=sec, lid=lid, dt=dt: road.boundary(sec, lid, s) + dt
            pts = rec["pts"]
            # each vertex on the exact curve
            sa, _ = nearest_s(road, t_of, pts[0], sec["s"], sec["e"])
            sb, _ = nearest_s(road, t_of, pts[-1], sec["s"], sec["e"])
            for p in pts:
                s, d = nearest_s(road, t_of, p, max(sec["s"], sa - 1), min(sec["e"], sb + 1))
                worst_mark = max(worst_mark, d)
                if d > TOL:
                    print(f"FAIL {rec['name']}: vertex {p} is {d:.4f} m from its boundary")
                    fails += 1
                    break
            # the exact curve near the record
            n = max(2, int((sb - sa) / 0.05))
            for i in range(n + 1):
                s = sa + (sb - sa) * i / n
                d = poly_dist(road.point(s, t_of(s)), pts)
                worst_mark = max(worst_mark, d)
                if d > TOL:
                    print(f"FAIL {rec['name']}: the boundary at s={s:.3f} is {d:.4f} m from the record")
                    fails += 1
                    break
            nmark += 1
            # dash phase: which mark of this lane holds the record
            marks = sec["lanes"][lid]["marks"]
            mk = [m for m in marks if m["s"] <= sa + 1e-6]
            if not mk:
                continue
            m = mk[-1]
            mi = marks.index(m)
            mend = min(sec["e"], marks[mi + 1]["s"] if mi + 1 < len(marks) else sec["e"])
            mstart = max(m["s"], sec["s"])
            pats = []
            if m["lines"]:
                pats = [(l["length"], l["space"], l.get("sOffset", 0)) for l in m["lines"] if l["space"] > 0 and l["length"] > 0 and abs(l.get("tOffset", 0) - dt) < 1e-9]
            elif "broken" in m["type"]:
                pats = [(3.0, 6.0, 0.0)]
            elif m["type"] == "botts dots":
                pats = [(0.1, 1.1, 0.0)]
            if not pats or ("solid" in m["type"] and "broken" in m["type"] and not m["lines"] and sb - sa > 3.0 + TOL):
                continue  # the solid line of a mixed double mark
            on, off, so = pats[0]
            P = on + off
            ph = (sa - so) % P
            ok_start = min(ph, P - ph) <= TOL or abs(sa - mstart) <= TOL
            length = sb - sa
            ok_len = abs(length - on) <= 2 * TOL or abs(sb - mend) <= TOL or abs(sa - mstart) <= TOL
            ndash += 1
            if not (ok_start and ok_len):
                print(f"FAIL {rec['name']}: dash s {sa:.4f}..{sb:.4f} is off the pattern {on}/{off} from {so}")
                fails += 1
        else:
            surf_groups.setdefault((rid, int(sec_i), kind), []).append(rec)
    for (rid, sec_i, kind), group in surf_groups.items():
        road = roads[rid]
        sec = road.sections[sec_i]
        lb, rb = (int(v) for v in kind[kind.index("[") + 1:-1].split(","))
        caps = [(g["pts"], 0.5 * g["width"]) for g in group]
        n = max(2, int((sec["e"] - sec["s"]) / 0.1))
        for b in (lb, rb):
            for i in range(n + 1):
                s = sec["s"] + (sec["e"] - sec["s"]) * i / n
                t = road.boundary(sec, b, s)
                p = road.point(s, t)
                depth = max(r - poly_dist(p, pts) for pts, r in caps)
                worst_surf = max(worst_surf, abs(depth))
                if abs(depth) > TOL:
                    print(f"FAIL road {rid} section {sec_i} {kind}: boundary {b} at s={s:.3f} is {depth:+.4f} m inside the surface edge")
                    fails += 1
                    break
        nsurf += 1
    print(f"{xodr}: {nmark} mark records ({ndash} dashes) worst {worst_mark:.4f} m; {nsurf} surfaces worst {worst_surf:.4f} m; tolerance {TOL} m")
    sys.exit(1 if fails else 0)


if __name__ == "__main__":
    main()
