// Texel-coordinate geometry (see texel_geometry.h): polygon clipping and
// area, the owner of a cut texel's pieces and points, a texel's square and
// the most covered texel around one. The hemicube's pixel loop reaches
// these only in rare cases (a cut texel, a pixel centre just outside the
// covered part), so they stay out of line.

#include "radiosity/pixmap/texel_geometry.h"

#include <tuple>

namespace radmesh::internal {

int clip_line(const St* in, int n, St* out, int axis, double c, double dir) {
  auto coord = [axis](const St& p) { return axis == 0 ? p.s : p.t; };
  int m = 0;
  for (int i = 0; i < n; ++i) {
    const St& p = in[i];
    const St& q = in[(i + 1) % n];
    const double dp = dir * (coord(p) - c), dq = dir * (coord(q) - c);
    if (dp >= 0.0) out[m++] = p;
    if ((dp >= 0.0) != (dq >= 0.0) && dp != 0.0 && dq != 0.0) {
      const bool swap = std::tie(q.s, q.t) < std::tie(p.s, p.t);
      const St& a = swap ? q : p;
      const St& b = swap ? p : q;
      const double ca = coord(a), cb = coord(b);
      const double t = (c - ca) / (cb - ca);
      St x{a.s + t * (b.s - a.s), a.t + t * (b.t - a.t)};
      if (axis == 0) x.s = c; else x.t = c;
      out[m++] = x;
    }
  }
  return m;
}

void area_centroid(const St* p, int n, double& area, St& centroid) {
  double a = 0.0, cs = 0.0, ct = 0.0;
  for (int i = 0; i < n; ++i) {
    const St& u = p[i];
    const St& w = p[(i + 1) % n];
    const double cross = u.s * w.t - w.s * u.t;
    a += cross;
    cs += (u.s + w.s) * cross;
    ct += (u.t + w.t) * cross;
  }
  area = 0.5 * a;
  centroid = area != 0.0 ? St{cs / (6.0 * area), ct / (6.0 * area)} : p[0];
}

const Pixmap::Cut* cut_of(const Pixmap& pm, int idx) {
  if (pm.cuts.empty()) return nullptr;
  const auto it = std::lower_bound(pm.cuts.begin(), pm.cuts.end(), idx,
                                   [](const Pixmap::Cut& c, int texel) { return c.texel < texel; });
  return it != pm.cuts.end() && it->texel == idx ? &*it : nullptr;
}

int owner_of_piece(const Pixmap& pm, int idx, int t) {
  if (const Pixmap::Cut* cut = cut_of(pm, idx))
    for (size_t q = 0; q < cut->triangles.size(); ++q)
      if (std::find(cut->triangles[q].begin(), cut->triangles[q].end(), t) != cut->triangles[q].end())
        return cut->owners[q];
  return pm.owner[idx];
}

int owner_of_cut_point(const Pixmap& pm, const Mesh& coarse, int idx, double s, double t) {
  const Pixmap::Cut* cut = cut_of(pm, idx);
  if (!cut) return pm.owner[idx];
  auto to_segment = [&](const St& a, const St& b) {
    const double ds = b.s - a.s, dt = b.t - a.t, len2 = ds * ds + dt * dt;
    const double h = len2 > 0.0 ? std::clamp(((s - a.s) * ds + (t - a.t) * dt) / len2, 0.0, 1.0) : 0.0;
    return std::hypot(s - a.s - h * ds, t - a.t - h * dt);
  };
  double nearest = INFINITY;
  int owner = pm.owner[idx];
  for (size_t q = 0; q < cut->triangles.size(); ++q)
    for (int tri : cut->triangles[q]) {
      St v[3];
      for (int c = 0; c < 3; ++c) v[c] = st_of(pm, coarse.positions[coarse.triangles[tri][c]]);
      if ((v[1].s - v[0].s) * (v[2].t - v[0].t) == (v[1].t - v[0].t) * (v[2].s - v[0].s)) continue;  // no area
      double e[3];
      for (int c = 0; c < 3; ++c)
        e[c] = (v[(c + 1) % 3].s - v[c].s) * (t - v[c].t) - (v[(c + 1) % 3].t - v[c].t) * (s - v[c].s);
      const bool inside = (e[0] >= 0.0 && e[1] >= 0.0 && e[2] >= 0.0) || (e[0] <= 0.0 && e[1] <= 0.0 && e[2] <= 0.0);
      const double d = inside ? 0.0 : std::min({to_segment(v[0], v[1]), to_segment(v[1], v[2]), to_segment(v[2], v[0])});
      if (d < nearest) {
        nearest = d;
        owner = cut->owners[q];
      }
    }
  return owner;
}

std::array<Vec3, 4> texel_square(const Pixmap& pm, int idx) {
  const int i = idx % pm.width, j = idx / pm.width;
  return {point_of(pm, i, j), point_of(pm, i + 1, j), point_of(pm, i + 1, j + 1), point_of(pm, i, j + 1)};
}

int most_covered_around(const Pixmap& pm, int i, int j, double min_coverage) {
  int best = -1;
  double most = 0.0;
  for (int dj = -1; dj <= 1; ++dj)
    for (int di = -1; di <= 1; ++di) {
      const int x = i + di, y = j + dj;
      if (x < 0 || y < 0 || x >= pm.width || y >= pm.height) continue;
      const size_t n = static_cast<size_t>(y) * pm.width + x;
      if (pm.coverage[n] >= min_coverage && pm.coverage[n] > most) {
        most = pm.coverage[n];
        best = static_cast<int>(n);
      }
    }
  return best;
}

}  // namespace radmesh::internal
