// Geometry in a pixmap's texel coordinates (s, t), shared by the layout,
// the rows and the display mesh: triangles clipped to texel cells, segments
// walked across the grid, and the texel that owns a point. The layout
// builds its coverage, cuts and wall feet with these, and the rows and the
// display mesh must find the same texels and owners for the same points,
// so each exists once. The small ones the hemicube's pixel loop calls for
// every pixel are inline.
#pragma once

#include "radmesh/pixmap.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace radmesh::internal {

struct St {
  double s, t;
};

// Sutherland-Hodgman of a convex polygon against s >= c (dir = +1) or
// s <= c (dir = -1) (axis 0), or the same for t (axis 1). The crossing of
// an edge is computed from its end points in a fixed order, so that the two
// triangles sharing an edge cut it at the same point.
int clip_line(const St* in, int n, St* out, int axis, double c, double dir);

// Area and centroid of a polygon in (s, t).
void area_centroid(const St* p, int n, double& area, St& centroid);

// Calls f(i, j, polygon, n) for each texel cell (i, j) the triangle
// overlaps with non-zero area, with the triangle clipped to the cell.
template <class F>
void for_each_piece(const Pixmap& pm, const St tri[3], F&& f) {
  const double smin = std::min({tri[0].s, tri[1].s, tri[2].s}), smax = std::max({tri[0].s, tri[1].s, tri[2].s});
  const double tmin = std::min({tri[0].t, tri[1].t, tri[2].t}), tmax = std::max({tri[0].t, tri[1].t, tri[2].t});
  const int i0 = std::clamp(static_cast<int>(std::floor(smin)), 0, pm.width - 1);
  const int i1 = std::clamp(static_cast<int>(std::ceil(smax)) - 1, i0, pm.width - 1);
  const int j0 = std::clamp(static_cast<int>(std::floor(tmin)), 0, pm.height - 1);
  const int j1 = std::clamp(static_cast<int>(std::ceil(tmax)) - 1, j0, pm.height - 1);
  St a[12], b[12];
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      int n = 3;
      std::copy(tri, tri + 3, a);
      // The grid's outer cells reach to infinity, so that rounding at the
      // pixmap's border loses no sliver.
      if (i > 0) n = clip_line(a, n, b, 0, i, 1.0); else std::copy(a, a + n, b);
      if (i < pm.width - 1) n = clip_line(b, n, a, 0, i + 1, -1.0); else std::copy(b, b + n, a);
      if (j > 0) n = clip_line(a, n, b, 1, j, 1.0); else std::copy(a, a + n, b);
      if (j < pm.height - 1) n = clip_line(b, n, a, 1, j + 1, -1.0); else std::copy(b, b + n, a);
      if (n < 3) continue;
      f(i, j, a, n);
    }
}

// Whether texel idx is its own square and nothing else: wholly covered and
// holding no sliver of a neighbour.
inline bool plain_square(const Pixmap& pm, long long idx) {
  return pm.whole[idx] && pm.area[idx] <= (1.0 + 1e-9) * pm.texel_u * pm.texel_v;
}

inline St st_of(const Pixmap& pm, const Vec3& x) { return {pm.s_of(x), pm.t_of(x)}; }

// Point a of the 3-point rule on triangle v (exact for quadratics): a
// sixth of the way from corner a toward the midpoint of the other two.
inline Vec3 rule_point(const std::array<Vec3, 3>& v, int a) {
  return (4.0 * v[a] + v[(a + 1) % 3] + v[(a + 2) % 3]) / 6.0;
}

// Whether segments pq and ab cross (touching counts).
inline bool segments_cross(const St& p, const St& q, const St& a, const St& b) {
  auto side = [](const St& o, const St& u, const St& v) { return (u.s - o.s) * (v.t - o.t) - (u.t - o.t) * (v.s - o.s); };
  const double d1 = side(a, b, p), d2 = side(a, b, q), d3 = side(p, q, a), d4 = side(p, q, b);
  return ((d1 <= 0.0 && d2 >= 0.0) || (d1 >= 0.0 && d2 <= 0.0)) && ((d3 <= 0.0 && d4 >= 0.0) || (d3 >= 0.0 && d4 <= 0.0));
}

inline Vec3 point_of(const Pixmap& pm, double s, double t) {
  return pm.origin + (s * pm.texel_u) * pm.u + (t * pm.texel_v) * pm.v;
}

// The cut (Pixmap::cuts) of texel idx, or null when no contact line cuts it.
const Pixmap::Cut* cut_of(const Pixmap& pm, int idx);

// The owner of the piece of coarse triangle t in texel idx.
int owner_of_piece(const Pixmap& pm, int idx, int t);

// Calls touch(texel) for every texel whose closed square the segment a-b
// (in texel coordinates) meets: column by column along its longer axis, the
// rows its span there reaches, a texel's edges included.
template <class Touch>
void for_each_texel_on(const Pixmap& pm, St a, St b, Touch&& touch) {
  const bool by_s = std::abs(b.s - a.s) >= std::abs(b.t - a.t);
  const int n_major = by_s ? pm.width : pm.height, n_minor = by_s ? pm.height : pm.width;
  double m0 = by_s ? a.s : a.t, m1 = by_s ? b.s : b.t, q0 = by_s ? a.t : a.s, q1 = by_s ? b.t : b.s;
  if (m0 > m1) {
    std::swap(m0, m1);
    std::swap(q0, q1);
  }
  constexpr double kEdge = 1e-9;  // on a texel line: both texels
  auto minor_at = [&](double m) { return m1 > m0 ? q0 + (q1 - q0) * (m - m0) / (m1 - m0) : q0; };
  const int i0 = std::max(0, static_cast<int>(std::floor(m0 - kEdge)));
  const int i1 = std::min(n_major - 1, static_cast<int>(std::floor(m1 + kEdge)));
  for (int i = i0; i <= i1; ++i) {
    const double lo = std::clamp(static_cast<double>(i), m0, m1), hi = std::clamp(i + 1.0, m0, m1);
    const double qa = minor_at(lo), qb = minor_at(hi);
    const int j0 = std::max(0, static_cast<int>(std::floor(std::min(qa, qb) - kEdge)));
    const int j1 = std::min(n_minor - 1, static_cast<int>(std::floor(std::max(qa, qb) + kEdge)));
    for (int j = j0; j <= j1; ++j) touch(by_s ? j * pm.width + i : i * pm.width + j);
  }
}

// The owner of point (s, t) for texel idx: where a contact line cuts the
// texel, that of the part nearest the point (the one holding it, when it
// lies in the texel), its triangles being those of `coarse`. A pixel's
// footprint may reach across the wall, but its centre lies on the side the
// pixel sees.
int owner_of_cut_point(const Pixmap& pm, const Mesh& coarse, int idx, double s, double t);

// The same, fast where no texel is cut or the texel is whole (a cut texel
// never is): the hemicube's hottest loop asks it for every pixel.
inline int owner_of_point(const Pixmap& pm, const Mesh& coarse, int idx, double s, double t) {
  return pm.cuts.empty() || pm.whole[idx] ? pm.owner[idx] : owner_of_cut_point(pm, coarse, idx, s, t);
}

// The square of texel idx (counter-clockwise around the pixmap's normal).
std::array<Vec3, 4> texel_square(const Pixmap& pm, int idx);

// The texel of the 3 x 3 around (i, j) with the most coverage, at least
// `min_coverage` and more than 0 (the first in row order on ties); -1 when none.
int most_covered_around(const Pixmap& pm, int i, int j, double min_coverage);

}  // namespace radmesh::internal
