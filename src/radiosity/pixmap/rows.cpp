// A shooter's row: the form factors from its block to every texel it
// reaches. The hemicube at the block's centre gives the far texels theirs,
// each pixel's delta form factor spread over the texels under its
// footprint; the texels near the block take Lambert's exact factor from
// each source texel instead (a hemicube sees from one point, which is not
// where the block's texels are), and the pixmaps too narrow for the pixels
// take theirs from narrow.cpp. The receiving pixmaps are independent, so
// they are done in parallel, each into its own part; the parts are joined
// in pixmap order, so that the row does not depend on the threads.

#include "radiosity/pixmap/solver.h"

#include "radmesh/errors.h"
#include "radmesh/form_factor.h"
#include "radiosity/transport/transport.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <sstream>

namespace radmesh {

using internal::kNearField;
using internal::Row;
using internal::RowEntry;
using internal::St;

namespace {

// What one receiving pixmap takes of a shooter's row.
struct RowPart {
  std::vector<RowEntry> far;       // increasing texel
  std::vector<uint32_t> near;      // increasing global texel
  std::vector<float> near_f;       // near.size() x source texels
  // The hemicube's factor to the near texels, and per source texel the
  // exact one (sum over the near texels).
  double near_hemicube = 0.0;
  std::vector<double> near_exact;
  long long over = 0;  // pixels spread over more than one texel
  // For a pixmap narrow for this shooter (narrow_receiver): the delta form
  // factors of the pixels that saw it, the factors from the block's centre
  // put in their place (its near texels' go to near_exact), and
  // NarrowPart::behind.
  double pixels_dropped = 0.0, exact_put = 0.0;
  double behind = 1.0;
};

// Screen point (x, y) of a face to texel coordinates (s, t) of the
// point its ray hits on this plane: a ratio of affine functions (the
// ray w = forward + x right + y up meets the plane at c + h / (w.n) w).
struct Homography {
  double d0, dx, dy, a0, ax, ay, b0, bx, by, cu, cv;
};

// The pixel rectangle of face f that the quad `corners` (world points) may
// cover, as seen by the hemicube: [x0, x1] x [y0, y1]; false when none.
bool projected_rect(const Hemicube& cube, int f, const std::array<Vec3, 4>& corners, int& x0, int& x1, int& y0,
                    int& y1) {
  const Hemicube::Face& F = cube.faces()[f];
  double xmin = INFINITY, xmax = -INFINITY, ymin = INFINITY, ymax = -INFINITY;
  bool any = false;
  // Project the quad clipped to z >= near (a corner behind the eye clips the
  // quad; the clipped polygon's points on the near plane count).
  struct P {
    double x, y, z;
  };
  P a[8];
  int n = 0;
  double scale = 0.0;
  for (const Vec3& c : corners) {
    const Vec3 d = c - cube.centre();
    a[n++] = {glm::dot(d, F.right), glm::dot(d, F.up), glm::dot(d, F.forward)};
    scale = std::max(scale, glm::length(d));
  }
  const double near = 1e-12 * scale;
  for (int i = 0; i < 4; ++i) {
    const P& p = a[i];
    const P& q = a[(i + 1) % 4];
    auto add = [&](double x, double y, double z) {
      xmin = std::min(xmin, x / z);
      xmax = std::max(xmax, x / z);
      ymin = std::min(ymin, y / z);
      ymax = std::max(ymax, y / z);
      any = true;
    };
    if (p.z >= near) add(p.x, p.y, p.z);
    if ((p.z >= near) != (q.z >= near)) {
      const double t = (near - p.z) / (q.z - p.z);
      add(p.x + t * (q.x - p.x), p.y + t * (q.y - p.y), near);
    }
  }
  if (!any) return false;
  const double px = cube.pixel_size();
  x0 = std::max(0, static_cast<int>(std::floor((std::max(xmin, -2.0) + 1.0) / px - 0.5)));
  x1 = std::min(F.width - 1, static_cast<int>(std::ceil((std::min(xmax, 2.0) + 1.0) / px - 0.5)));
  y0 = std::max(0, static_cast<int>(std::floor((std::max(ymin, F.y0 - 1.0) - F.y0) / px - 0.5)));
  y1 = std::min(F.height - 1, static_cast<int>(std::ceil((std::min(ymax, 2.0) - F.y0) / px - 0.5)));
  return x0 <= x1 && y0 <= y1;
}

// How far the near field reaches from the shooter's centre: kNearField
// times its farthest texel's distance plus a texel's diagonal.
double near_reach(const Shooter& sh, const Pixmap& own) {
  double reach = 0.0;
  for (size_t i = 0; i < sh.texels.size(); ++i) {
    const int t = sh.texels[i];
    reach = std::max(reach, glm::length(own.centroid[t] - sh.centre) + std::hypot(own.texel_u, own.texel_v));
  }
  reach *= kNearField;
  return reach;
}

// Whether the hemicube sees open sky anywhere: if not, whatever lies
// behind a narrow pixmap is the scene.
bool sees_sky(const Hemicube& cube) {
  bool sky = false;
  for (const Hemicube::Face& F : cube.faces())
    sky = sky || std::find(F.id.begin(), F.id.end(), Hemicube::kEmpty) != F.id.end();
  return sky;
}

// Each source texel's far entries give or take what the near field
// changed, so that its row keeps the hemicube's sum (1 in a closed scene).
Row join_parts(const std::vector<RowPart>& parts, size_t nsrc, long long& spread_pixels) {
  double far = 0.0, hemicube = 0.0;
  std::vector<double> exact(nsrc, 0.0), open_gain(nsrc, 0.0);
  Row row;
  for (const RowPart& part : parts) {
    for (const RowEntry& e : part.far) far += e.f;
    // What the hemicube gave a narrow pixmap counts, so that the row keeps
    // the hemicube's sum (1 in a closed scene): the pixels that saw it would
    // have seen what lies behind it, and those that missed it saw what it
    // hides. Where open sky lies behind it, its own factors count instead.
    hemicube += part.near_hemicube + part.pixels_dropped - part.exact_put;
    for (size_t q = 0; q < nsrc; ++q)
      open_gain[q] += (1.0 - part.behind) * (part.exact_put + part.near_exact[q] - part.pixels_dropped);
    for (size_t q = 0; q < nsrc; ++q) exact[q] += part.near_exact[q];
    row.far.insert(row.far.end(), part.far.begin(), part.far.end());
    row.near.insert(row.near.end(), part.near.begin(), part.near.end());
    row.near_f.insert(row.near_f.end(), part.near_f.begin(), part.near_f.end());
    spread_pixels += part.over;
  }
  hemicube += far;
  row.far_scale.resize(nsrc);
  for (size_t q = 0; q < nsrc; ++q)
    row.far_scale[q] = static_cast<float>(far > 0.0 ? std::max(0.0, (hemicube + open_gain[q] - exact[q]) / far) : 1.0);
  return row;
}

}  // namespace

// What the hemicube of shooter sh shows of receiving pixmap k, spread over
// its texels (acc), and then the near field's and a narrow pixmap's exact
// factors, into `out`.
struct PixmapSolver::Impl::RowReceiver {
  const Impl& m;
  const Shooter& sh;
  const Hemicube& cube;
  const int k;
  const Pixmap& pm;
  const double h;  // the plane's offset from the shooter's centre along its normal
  RowPart& out;
  const Vec3 co;  // the shooter's centre from the pixmap's origin
  Homography H{};
  std::vector<double> acc;   // per texel of pm, once one is touched
  std::vector<int> touched;  // the texels acc holds
  std::vector<double> ws, wt, kept_w;
  std::vector<int> near_feet;
  std::vector<double> cs, ct;  // the points of the pixel corners of a face
  std::vector<char> cok;

  RowReceiver(const Impl& m, const Shooter& sh, const Hemicube& cube, int k, double h, RowPart& out)
      : m(m), sh(sh), cube(cube), k(k), pm(m.layout.pixmaps[k]), h(h), out(out), co(sh.centre - pm.origin) {}

  void set_face(const Hemicube::Face& F) {
    H = {glm::dot(F.forward, pm.normal), glm::dot(F.right, pm.normal), glm::dot(F.up, pm.normal),
         h * glm::dot(F.forward, pm.u),  h * glm::dot(F.right, pm.u),  h * glm::dot(F.up, pm.u),
         h * glm::dot(F.forward, pm.v),  h * glm::dot(F.right, pm.v),  h * glm::dot(F.up, pm.v),
         glm::dot(co, pm.u),             glm::dot(co, pm.v)};
  }
  bool hit(double x, double y, double& s, double& t) const {
    const double d = H.d0 + H.dx * x + H.dy * y;
    if (!(d < 0.0)) return false;
    s = (H.cu + (H.a0 + H.ax * x + H.ay * y) / d) / pm.texel_u;
    t = (H.cv + (H.b0 + H.bx * x + H.by * y) / d) / pm.texel_v;
    return std::isfinite(s) && std::isfinite(t);
  }
  // The owner of the texel at (s, t), or -1 when it is not covered.
  int owner_at(double s, double t) const {
    const int i = std::clamp(static_cast<int>(std::floor(s)), 0, pm.width - 1);
    const int j = std::clamp(static_cast<int>(std::floor(t)), 0, pm.height - 1);
    return internal::owner_of_point(pm, m.coarse, j * pm.width + i, s, t);
  }
  void add(int texel, double f) {
    if (!(f > 0.0)) return;  // a zero weight would list the texel twice below
    if (acc.empty()) acc.assign(static_cast<size_t>(pm.texels()), 0.0);
    if (acc[texel] == 0.0) touched.push_back(texel);
    acc[texel] += f;
  }
  bool cut_by_wall(double s0, double s1, double t0, double t1, int i0, int i1, int j0, int j1, double f,
                   int fallback, double sc, double tc);
  void spread(double s0, double s1, double t0, double t1, double f, int fallback, double sc, double tc);
  void see_face(int f, const std::array<Vec3, 4>& corners, bool narrow);
  void see_pixel(int f, int x, int y, int x0, int y0, int cw);
  void take_narrow(double reach, bool sky, const std::vector<SourcePolygon>& polygons);
  std::vector<char> near_texels(double reach);
  void near_points(int texel, std::vector<std::pair<Vec3, double>>& points) const;
  void collect(const std::vector<char>& near_texel, const std::vector<SourcePolygon>& polygons);
};

// A footprint a wall's foot crosses reaches the wall's other side,
// which the pixel does not see (the wall hides it): its texels whose
// part of the footprint lies beyond a foot, seen from the pixel's
// centre, get nothing, and the others share the pixel. Spread over both
// sides, the pixels seen just before a thin wall would light the room it
// seals. False when no foot touches the footprint.
bool PixmapSolver::Impl::RowReceiver::cut_by_wall(double s0, double s1, double t0, double t1, int i0, int i1, int j0,
                                                  int j1, double f, int fallback, double sc, double tc) {
  near_feet.clear();
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      const int idx = j * pm.width + i;
      if (!pm.wall_foot[static_cast<size_t>(idx)]) continue;
      const auto range = std::equal_range(pm.foot_at.begin(), pm.foot_at.end(), std::pair{idx, 0},
                                          [](const auto& x, const auto& y) { return x.first < y.first; });
      for (auto it = range.first; it != range.second; ++it) near_feet.push_back(it->second);
    }
  if (near_feet.empty()) return false;
  const int ci = std::clamp(static_cast<int>(std::floor(sc)), i0, i1),
            cj = std::clamp(static_cast<int>(std::floor(tc)), j0, j1);
  kept_w.assign(ws.size() * wt.size(), 0.0);
  double kept = 0.0;
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      const double w = ws[i - i0] * wt[j - j0];
      if (!(w > 0.0)) continue;
      // The centre of the texel's part of the footprint.
      const St q{0.5 * (std::max(s0, static_cast<double>(i)) + std::min(s1, i + 1.0)),
                 0.5 * (std::max(t0, static_cast<double>(j)) + std::min(t1, j + 1.0))};
      bool beyond = false;
      if (i != ci || j != cj)
        for (const int n : near_feet) {
          const Pixmap::Foot& e = pm.feet[static_cast<size_t>(n)];
          if (internal::segments_cross({sc, tc}, q, {e.s0, e.t0}, {e.s1, e.t1})) {
            beyond = true;
            break;
          }
        }
      if (beyond) continue;
      kept_w[static_cast<size_t>(j - j0) * ws.size() + (i - i0)] = w;
      kept += w;
    }
  if (!(kept > 0.0)) {
    add(fallback, f);
    return true;
  }
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      const double w = kept_w[static_cast<size_t>(j - j0) * ws.size() + (i - i0)];
      if (!(w > 0.0)) continue;
      const int o = internal::owner_of_point(pm, m.coarse, j * pm.width + i, sc, tc);
      add(o >= 0 ? o : fallback, f * w / kept);
    }
  ++out.over;
  return true;
}

// A pixel's delta form factor is spread over the texels under its
// footprint (the box around its four corners' points on this plane), in
// proportion to their overlap: the limit of virtual oversampling, with
// no samples to alias against the texel grid. Footprints of neighbouring
// pixels share corners, so where the texel axes follow the screen's they
// tile the plane exactly; otherwise their boxes overlap a little, which
// blurs by at most one footprint and keeps each pixel's sum. A texel
// that is not covered, or covered too little to be an element, passes
// its share to its owner; with no owner the share goes to `fallback`
// (the owner under the pixel's centre).
void PixmapSolver::Impl::RowReceiver::spread(double s0, double s1, double t0, double t1, double f, int fallback,
                                             double sc, double tc) {
  s0 = std::clamp(s0, 0.0, static_cast<double>(pm.width));
  s1 = std::clamp(s1, 0.0, static_cast<double>(pm.width));
  t0 = std::clamp(t0, 0.0, static_cast<double>(pm.height));
  t1 = std::clamp(t1, 0.0, static_cast<double>(pm.height));
  const int i0 = std::min(pm.width - 1, static_cast<int>(s0)), i1 = std::min(pm.width - 1, static_cast<int>(s1));
  const int j0 = std::min(pm.height - 1, static_cast<int>(t0)), j1 = std::min(pm.height - 1, static_cast<int>(t1));
  if (i0 == i1 && j0 == j1) {
    const int o = internal::owner_of_point(pm, m.coarse, j0 * pm.width + i0, sc, tc);
    add(o >= 0 ? o : fallback, f);
    return;
  }
  // Overlap of [a, b] with each unit interval from i0 to i1; a footprint
  // of zero width (a pixel seen edge on) counts as one point.
  auto overlaps = [](double a, double b, int i0, int i1, std::vector<double>& w) {
    w.assign(static_cast<size_t>(i1 - i0 + 1), 0.0);
    if (i0 == i1 || !(b > a)) {
      w[0] = 1.0;
      return 1.0;
    }
    for (int i = i0; i <= i1; ++i) w[i - i0] = std::min(b, i + 1.0) - std::max(a, static_cast<double>(i));
    return b - a;
  };
  const double norm = f / (overlaps(s0, s1, i0, i1, ws) * overlaps(t0, t1, j0, j1, wt));
  if (!pm.wall_foot.empty() && cut_by_wall(s0, s1, t0, t1, i0, i1, j0, j1, f, fallback, sc, tc)) return;
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      const int o = internal::owner_of_point(pm, m.coarse, j * pm.width + i, sc, tc);
      add(o >= 0 ? o : fallback, norm * ws[i - i0] * wt[j - j0]);
    }
  ++out.over;
}

// The pixels of face f that see this pixmap: on a narrow pixmap only
// their delta form factors' sum (pixels_dropped), else each spread.
void PixmapSolver::Impl::RowReceiver::see_face(int f, const std::array<Vec3, 4>& corners, bool narrow) {
  int x0, x1, y0, y1;
  if (!projected_rect(cube, f, corners, x0, x1, y0, y1)) return;
  const Hemicube::Face& F = cube.faces()[f];
  set_face(F);
  const double px = cube.pixel_size();
  // The points of the pixel corners (x - 1/2, y - 1/2), for x in
  // [x0, x1 + 1] and y in [y0, y1 + 1].
  const int cw = x1 - x0 + 2, ch = y1 - y0 + 2;
  cs.resize(static_cast<size_t>(cw) * ch);
  ct.resize(cs.size());
  cok.resize(cs.size());
  for (int b = 0; b < ch; ++b)
    for (int a = 0; a < cw; ++a) {
      const size_t c = static_cast<size_t>(b) * cw + a;
      cok[c] = hit(cube.pixel_x(x0 + a) - 0.5 * px, cube.pixel_y(f, y0 + b) - 0.5 * px, cs[c], ct[c]);
    }
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const int id = F.id[static_cast<size_t>(y) * F.width + x];
      if (id < 0 || m.layout.pixmap_of_patch[id] != k) continue;
      if (narrow) {
        out.pixels_dropped += cube.delta(f, x, y);
        continue;
      }
      see_pixel(f, x, y, x0, y0, cw);
    }
}

// Pixel (x, y) of face f, which sees this pixmap: its delta form factor
// spread over its footprint.
void PixmapSolver::Impl::RowReceiver::see_pixel(int f, int x, int y, int x0, int y0, int cw) {
  double s, t;
  if (!hit(cube.pixel_x(x), cube.pixel_y(f, y), s, t)) return;
  int centre_owner = owner_at(s, t);
  if (centre_owner < 0) {
    // Rounding put the centre's point just outside the covered
    // part: the most covered texel around it.
    const int n = internal::most_covered_around(pm, std::clamp(static_cast<int>(std::floor(s)), 0, pm.width - 1),
                                                std::clamp(static_cast<int>(std::floor(t)), 0, pm.height - 1), 0.0);
    if (n < 0) return;
    centre_owner = pm.owner[n];
  }
  const double delta = cube.delta(f, x, y);
  const size_t c = static_cast<size_t>(y - y0) * cw + (x - x0);
  const size_t q[4] = {c, c + 1, c + cw, c + cw + 1};
  if (!(cok[q[0]] && cok[q[1]] && cok[q[2]] && cok[q[3]])) {
    // A corner beyond this plane's horizon: the centre's texel.
    add(centre_owner, delta);
    return;
  }
  double s0 = cs[q[0]], s1 = s0, t0 = ct[q[0]], t1 = t0;
  for (int e = 1; e < 4; ++e) {
    s0 = std::min(s0, cs[q[e]]);
    s1 = std::max(s1, cs[q[e]]);
    t0 = std::min(t0, ct[q[e]]);
    t1 = std::max(t1, ct[q[e]]);
  }
  spread(s0, s1, t0, t1, delta, centre_owner, s, t);
}

// A narrow pixmap's own factors (receive_narrow) in place of the pixels'.
void PixmapSolver::Impl::RowReceiver::take_narrow(double reach, bool sky, const std::vector<SourcePolygon>& polygons) {
  NarrowPart part;
  m.receive_narrow(k, sh, reach, sky, polygons, [this](int texel, double f) { add(texel, f); }, part);
  out.exact_put = part.far_sum;
  out.behind = part.behind;
  out.near = std::move(part.near);
  out.near_f = std::move(part.near_f);
  out.near_exact = std::move(part.exact);
}

// The near field: every whole texel within reach that the hemicube saw,
// or that the pixel toward its centre shows (a texel a hair away from
// the shooter fills no pixel centre of its own).
std::vector<char> PixmapSolver::Impl::RowReceiver::near_texels(double reach) {
  std::vector<char> near_texel;
  const double cs = pm.s_of(sh.centre), ct = pm.t_of(sh.centre);
  const int i0 = std::max(0, static_cast<int>(std::floor(cs - reach / pm.texel_u)));
  const int i1 = std::min(pm.width - 1, static_cast<int>(std::ceil(cs + reach / pm.texel_u)));
  const int j0 = std::max(0, static_cast<int>(std::floor(ct - reach / pm.texel_v)));
  const int j1 = std::min(pm.height - 1, static_cast<int>(std::ceil(ct + reach / pm.texel_v)));
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      const int texel = j * pm.width + i;
      if (!pm.whole[texel] || glm::length(pm.centroid[texel] - sh.centre) >= reach) continue;
      const bool seen = !acc.empty() && acc[texel] > 0.0;
      if (!seen) {
        const int id = cube.id_toward(pm.centroid[texel] - sh.centre);
        if (id < 0 || m.layout.pixmap_of_patch[id] != k) continue;
        if (acc.empty()) acc.assign(static_cast<size_t>(pm.texels()), 0.0);
        touched.push_back(texel);
      }
      if (near_texel.empty()) near_texel.assign(static_cast<size_t>(pm.texels()), 0);
      near_texel[texel] = 1;
    }
  return near_texel;
}

// The points (and their weights, areas) a near texel's factor is
// integrated over: a plain square no line cuts is one fan of two
// triangles, 2 x 2 points; otherwise 3 points of each piece it owns.
void PixmapSolver::Impl::RowReceiver::near_points(int texel, std::vector<std::pair<Vec3, double>>& points) const {
  if (internal::plain_square(pm, texel) && m.pieces_of(pm.first + texel).size() <= 2) {
    const double a = 0.25 * pm.texel_u * pm.texel_v;
    for (int q = 0; q < 4; ++q)
      points.emplace_back(pm.centroid[texel] + ((q % 2 ? 0.25 : -0.25) * pm.texel_u) * pm.u +
                              ((q / 2 ? 0.25 : -0.25) * pm.texel_v) * pm.v,
                          a);
  } else {
    for (const int d : m.pieces_of(pm.first + texel)) {
      const std::array<Vec3, 3> p = m.piece_corners(d);
      const double a = triangle_area(p[0], p[1], p[2]) / 3.0;
      for (int c = 0; c < 3; ++c) points.emplace_back(internal::rule_point(p, c), a);
    }
  }
}

// The touched texels in increasing order: the far ones with what the
// pixels gave them, the near ones with the exact factor from each source
// texel.
void PixmapSolver::Impl::RowReceiver::collect(const std::vector<char>& near_texel,
                                              const std::vector<SourcePolygon>& polygons) {
  const Pixmap& own = m.layout.pixmaps[sh.pixmap];
  const size_t nsrc = sh.texels.size();
  std::sort(touched.begin(), touched.end());
  std::vector<double> per(nsrc);
  std::vector<std::pair<Vec3, double>> points;
  for (int texel : touched) {
    const double f = acc[texel];
    if (near_texel.empty() || !near_texel[texel]) {
      if (f > 0.0) out.far.push_back({static_cast<uint32_t>(pm.first + texel), static_cast<float>(f)});
      continue;
    }
    std::fill(per.begin(), per.end(), 0.0);
    points.clear();
    near_points(texel, points);
    // F(q -> texel) = sum over the points of w F(x -> q's polygons) / A_q.
    for (const SourcePolygon& poly : polygons) {
      double f = 0.0;
      for (const auto& [x, w] : points) f += w * point_polygon_form_factor(x, pm.normal, poly.v.data(), poly.count, own.normal);
      per[poly.q] += f / own.area[sh.texels[poly.q]];
    }
    out.near_hemicube += f;
    out.near.push_back(static_cast<uint32_t>(pm.first + texel));
    for (size_t q = 0; q < nsrc; ++q) {
      out.near_f.push_back(static_cast<float>(per[q]));
      out.near_exact[q] += per[q];
    }
  }
}

// The near field. A hemicube sees from one point, and the shooter's
// exchange with texels closer than a few times its size (across an edge
// it shares with them) is not that of its centre: there F is integrated
// exactly instead, per source texel, by reciprocity: Lambert's factor to
// each source texel's polygons (exact) from points of the receiving texel
// (2 x 2 of a plain texel, 3 of each piece of another), for the texels
// the hemicube saw. The points are on the receiving texel, not on the
// source texels: the faces of a box that a lamp crosses receive, along the
// lamp, from the lamp's texels that the box's outline cuts, where F varies
// fastest, and a few points on those would give them too little light.
void PixmapSolver::Impl::refuse_row(int s) const {
  const Shooter& sh = layout.shooters[s];
  std::ostringstream m;
  m.precision(3);
  m << scene.source << ": the near field of a block of " << sh.texels.size() << " texels needs more than the "
    << row_budget / (1u << 30) << " GiB of the " << memory_limit / (1u << 30)
    << " GiB allowed that the texels and the hemicube leave; use a smaller block or a larger texel_size, or raise "
       "max_memory";
  throw NumericalError(m.str(), {"block", "texel_size", "max_memory"});
}

Row PixmapSolver::Impl::compute_row(int s, Hemicube& cube, long long& spread_pixels) const {
  const Shooter& sh = layout.shooters[s];
  const Pixmap& own = layout.pixmaps[sh.pixmap];
  cube.render(sh.centre, own.u, own.v, polygons);
  const int npm = static_cast<int>(layout.pixmaps.size());
  const size_t nsrc = sh.texels.size();
  std::vector<RowPart> parts(static_cast<size_t>(npm));
  for (RowPart& part : parts) part.near_exact.assign(nsrc, 0.0);
  const std::vector<SourcePolygon> sources = source_polygons(sh);
  const double reach = near_reach(sh, own);
  const bool sky = sees_sky(cube);
  // The near field's factors, one per (near texel, source texel), grow with
  // the block's area and the texels in reach: counted before they are
  // made, against what the texels and the hemicube leave of the memory.
  std::atomic<double> near_bytes{0.0};
  tbb::parallel_for(0, npm, [&](int k) {
    if (k == sh.pixmap) return;
    const Pixmap& pm = layout.pixmaps[k];
    const double h = glm::dot(pm.origin - sh.centre, pm.normal);
    const bool narrow = narrow_receiver(k, sh, cube.pixel_size(), reach);
    // A shooter whose centre is not in front of this pixmap sends it nothing,
    // unless the pixmap is narrow: then each source texel near it is taken
    // on its own (a block around a picture's corner, its centre a few
    // millimetres above the picture's underside, has texels right under it).
    if (!(h < 0.0) && !narrow) return;
    const std::array<Vec3, 4> corners = {internal::point_of(pm, 0, 0), internal::point_of(pm, pm.width, 0),
                                         internal::point_of(pm, pm.width, pm.height),
                                         internal::point_of(pm, 0, pm.height)};
    RowReceiver receiver(*this, sh, cube, k, h, parts[static_cast<size_t>(k)]);
    for (int f = 0; f < 5; ++f) receiver.see_face(f, corners, narrow);
    if (narrow) receiver.take_narrow(reach, sky, sources);
    std::vector<char> near_texel;
    if (reach > 0.0 && !narrow) near_texel = receiver.near_texels(reach);
    const double count = static_cast<double>(std::count(near_texel.begin(), near_texel.end(), 1));
    if (near_bytes.fetch_add(count * static_cast<double>(nsrc) * sizeof(float)) > row_budget) refuse_row(s);
    receiver.collect(near_texel, sources);
  });
  return join_parts(parts, nsrc, spread_pixels);
}

std::vector<std::vector<std::pair<long long, double>>> PixmapSolver::form_factors(int s) const {
  if (s < 0 || s >= static_cast<int>(impl_->layout.shooters.size()))
    throw InputError("shooter " + std::to_string(s) + " does not exist");
  Hemicube cube(impl_->options.hemicube_res);
  long long over = 0;
  Row row;
  run_in_arena(impl_->solve.threads, [&] { row = impl_->compute_row(s, cube, over); });
  const size_t nsrc = row.far_scale.size();
  std::vector<std::vector<std::pair<long long, double>>> out(nsrc);
  for (size_t q = 0; q < nsrc; ++q) {
    for (const RowEntry& e : row.far) out[q].emplace_back(e.texel, static_cast<double>(e.f) * row.far_scale[q]);
    for (size_t n = 0; n < row.near.size(); ++n) out[q].emplace_back(row.near[n], row.near_f[n * nsrc + q]);
    std::sort(out[q].begin(), out[q].end());
  }
  return out;
}

}  // namespace radmesh
