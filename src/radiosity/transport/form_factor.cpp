// Form factors: Lambert's exact contour formula from a point to a polygon,
// receiver quadrature points graded toward the source, and the element
// form factors the methods share.

#include "radmesh/form_factor.h"

#include "radiosity/transport/lambert_kernel.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

namespace radmesh {

double lambert_contour_sum(const Vec3& x, const Vec3& n, const Vec3* pts, size_t count) {
  // Sutherland-Hodgman clipping to the half-space dot(n, p - x) >= 0, with
  // the clipped loop streamed into the contour sum instead of stored: no
  // limit on the vertex count and no allocation. Edges are summed in the
  // order of the clipped loop, the closing edge last.
  double sum = 0.0;
  size_t emitted = 0;
  Vec3 first{0.0}, prev{0.0};
  auto edge = [&](const Vec3& a, const Vec3& b) {
    const Vec3 r0 = a - x, r1 = b - x;
    sum += internal::lambert_edge(r0.x, r0.y, r0.z, r1.x, r1.y, r1.z, n.x, n.y, n.z);
  };
  auto emit = [&](const Vec3& p) {
    if (emitted == 0)
      first = p;
    else
      edge(prev, p);
    prev = p;
    ++emitted;
  };
  for (size_t i = 0; i < count; ++i) {
    const Vec3& a = pts[i];
    const Vec3& b = pts[i + 1 == count ? 0 : i + 1];
    const double da = glm::dot(n, a - x);
    const double db = glm::dot(n, b - x);
    if (da >= 0.0) emit(a);
    if ((da >= 0.0) != (db >= 0.0)) emit(a + (b - a) * (da / (da - db)));
  }
  if (emitted < 3) return 0.0;
  edge(prev, first);
  return sum;
}

double point_polygon_form_factor(const Vec3& x, const Vec3& n, const Vec3* pts, size_t count,
                                 const Vec3& poly_normal) {
  // The source emits from its front only.
  if (count < 3 || glm::dot(x - pts[0], poly_normal) <= 0.0) return 0.0;
  return std::abs(lambert_contour_sum(x, n, pts, count)) / (2.0 * std::numbers::pi);
}

Triangle make_triangle(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& normal) {
  Triangle t;
  t.v = {a, b, c};
  t.normal = normal;
  t.area = triangle_area(a, b, c);
  const Vec3 m = t.centroid();
  t.radius = std::max({glm::length(a - m), glm::length(b - m), glm::length(c - m)});
  return t;
}

bool facing_away(const Triangle& r, const Triangle& s) {
  auto any_in_front = [](const Triangle& plane, const Triangle& t) {
    const double scale = std::max(plane.radius, t.radius);
    // Coplanar up to the elements' size and to their coordinates' rounding:
    // far from the origin (a scene moved by 1e6) a vertex of the plane is
    // off it by units in the last place of its coordinates, more than
    // 1e-12 of a small element.
    double magnitude = 0.0;
    for (const Triangle* x : {&plane, &t})
      for (const Vec3& p : x->v) magnitude = std::max(magnitude, std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)}));
    const double eps = 1e-12 * scale + 64.0 * std::numeric_limits<double>::epsilon() * magnitude;
    for (const Vec3& p : t.v)
      if (glm::dot(p - plane.v[0], plane.normal) > eps) return true;
    return false;
  };
  return !any_in_front(r, s) || !any_in_front(s, r);
}

namespace {

// Closest point of a triangle to p (Ericson's closest-point method).
Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Vec3 cp = p - c;
  const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

}  // namespace

bool splits_piece(double size, double distance, const QuadratureOptions& options) {
  return size > options.closeness * std::max(0.0, distance - size / std::sqrt(3.0));
}

namespace {

void subdivide(const Vec3& a, const Vec3& b, const Vec3& c, int level, double total_area,
               const std::function<double(const Vec3&)>& distance, const QuadratureOptions& opt,
               ReceiverPoints& out) {
  const double size = std::max({glm::length(a - b), glm::length(b - c), glm::length(c - a)});
  if (level < opt.max_level) {
    const Vec3 centre = (a + b + c) / 3.0;
    if (splits_piece(size, distance(centre), opt)) {
      const Vec3 ab = 0.5 * (a + b), bc = 0.5 * (b + c), ca = 0.5 * (c + a);
      subdivide(a, ab, ca, level + 1, total_area, distance, opt, out);
      subdivide(ab, b, bc, level + 1, total_area, distance, opt, out);
      subdivide(ca, bc, c, level + 1, total_area, distance, opt, out);
      subdivide(ab, bc, ca, level + 1, total_area, distance, opt, out);
      return;
    }
  }
  // Degree-2 rule: the three points at barycentrics (2/3, 1/6, 1/6), equal weights.
  const double w = triangle_area(a, b, c) / total_area / 3.0;
  out.x.push_back((4.0 * a + b + c) / 6.0);
  out.x.push_back((a + 4.0 * b + c) / 6.0);
  out.x.push_back((a + b + 4.0 * c) / 6.0);
  out.w.insert(out.w.end(), 3, w);
}

}  // namespace

ReceiverPoints receiver_points(const Triangle& receiver, const std::function<double(const Vec3&)>& distance,
                               const QuadratureOptions& options) {
  ReceiverPoints r;
  r.normal = receiver.normal;
  if (receiver.area > 0.0)
    subdivide(receiver.v[0], receiver.v[1], receiver.v[2], 0, receiver.area, distance, options, r);
  return r;
}

int uniform_level(const Triangle& receiver, double distance, const QuadratureOptions& options) {
  double size = std::max({glm::length(receiver.v[0] - receiver.v[1]), glm::length(receiver.v[1] - receiver.v[2]),
                          glm::length(receiver.v[2] - receiver.v[0])});
  int level = 0;
  for (; level < options.max_level && splits_piece(size, distance, options); ++level) size *= 0.5;
  return level;
}

ReceiverPoints uniform_points(const Triangle& receiver, int level) {
  // A distance of 0 splits every piece of positive size.
  return receiver_points(receiver, [](const Vec3&) { return 0.0; }, QuadratureOptions{1.0, level});
}

double form_factor(const ReceiverPoints& r, const Triangle& source) {
  const Triangle* one = &source;
  double f = 0.0;
  form_factors(r, &one, 1, &f);
  return f;
}

namespace {

// The part of triangle (e[0], e[1], e[2]) (corners relative to a point)
// on or in front of the point's tangent plane, h[k] the corners' heights
// over it (Sutherland-Hodgman, h >= 0 kept): 0, 3 or 4 corners.
int clip_to_tangent_plane(const Vec3 (&e)[3], const double (&h)[3], std::array<Vec3, 4>& loop) {
  int corners = 0;
  for (size_t k = 0; k < 3; ++k) {
    const size_t k1 = k == 2 ? 0 : k + 1;
    if (h[k] >= 0.0) loop[static_cast<size_t>(corners++)] = e[k];
    if ((h[k] >= 0.0) != (h[k1] >= 0.0)) loop[static_cast<size_t>(corners++)] = e[k] + (e[k1] - e[k]) * (h[k] / (h[k] - h[k1]));
  }
  return corners < 3 ? 0 : corners;
}

// Lambert's sums of triangles given by their corners relative to the
// point, through the vectorized kernel: `put` them, then `sum` them all.
// A clipped quad is two triangles (a fan from its first corner) whose sums
// are added, since the contour sum of a polygon is the sum of its fan's
// (their shared edge cancels): its second triangle goes after every first
// one.
struct LambertBatch {
  std::array<std::vector<double>, 9> d;
  std::vector<double> sum;
  std::vector<std::array<Vec3, 4>> quad_loops;
  std::vector<int> quad_items;
  size_t n = 0;
  // Room for `items` first triangles (and as many seconds) without
  // reallocating: filled by index (no push_back per coordinate: that
  // bookkeeping costs more than the kernel itself).
  void start(size_t items) {
    if (sum.size() < 2 * items) {
      for (auto& v : d) v.resize(2 * items);
      sum.resize(2 * items);
    }
    quad_loops.clear();
    quad_items.clear();
    n = 0;
  }
  void put(size_t i, const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3* corner[3] = {&a, &b, &c};
    for (size_t k = 0; k < 3; ++k) {
      d[3 * k][i] = corner[k]->x;
      d[3 * k + 1][i] = corner[k]->y;
      d[3 * k + 2][i] = corner[k]->z;
    }
  }
  // Appends a clipped loop of 3 or 4 corners; returns its item.
  size_t add_loop(const std::array<Vec3, 4>& loop, int corners) {
    put(n, loop[0], loop[1], loop[2]);
    if (corners == 4) {
      quad_loops.push_back(loop);
      quad_items.push_back(static_cast<int>(n));
    }
    return n++;
  }
  void sum_all(const Vec3& normal) {
    const size_t quads = quad_items.size();
    for (size_t k = 0; k < quads; ++k) put(n + k, quad_loops[k][0], quad_loops[k][2], quad_loops[k][3]);
    internal::lambert_triangle_sums(n + quads, {d[0].data(), d[1].data(), d[2].data(), d[3].data(), d[4].data(),
                                              d[5].data(), d[6].data(), d[7].data(), d[8].data()},
                                  normal.x, normal.y, normal.z, sum.data());
    for (size_t k = 0; k < quads; ++k) sum[static_cast<size_t>(quad_items[k])] += sum[n + k];
  }
};

// Sources at least this many: point_source_pairs takes them point by point
// (lambert_point_sums, the sources packed once) instead of packing every
// (point, source) pair.
constexpr size_t kPointMajorSources = 4;

// Calls visit(j, q, F(x_q -> *sources[j])) for every pair whose point lies
// in front of the source (the others are 0), in source order, then point
// order. A triangle crossing the point's tangent plane is clipped to it
// first: the part in front is a triangle or a quad (LambertBatch). Many
// sources go through lambert_point_sums, one call per point over all of
// them, with only the crossing pairs clipped and batched; few go pair by
// pair through the batch. Both give the same sums.
template <class Visit>
void point_source_pairs(const ReceiverPoints& r, const Triangle* const* sources, size_t count, Visit&& visit) {
  thread_local LambertBatch batch;
  const size_t points = r.x.size();
  if (count >= kPointMajorSources) {
    struct Scratch {
      std::array<std::vector<double>, 12> s;  // the sources' corners and normals
      std::vector<double> sum, kind;          // per (point, source), point-major
      std::vector<int> clipped;               // per (point, source): its batch item, -1 none
    };
    thread_local Scratch m;
    if (m.s[0].size() < count)
      for (auto& v : m.s) v.resize(count);
    if (m.sum.size() < count * points) {
      m.sum.resize(count * points);
      m.kind.resize(count * points);
      m.clipped.resize(count * points);
    }
    for (size_t j = 0; j < count; ++j) {
      const Triangle& t = *sources[j];
      for (size_t k = 0; k < 3; ++k) {
        m.s[3 * k][j] = t.v[k].x;
        m.s[3 * k + 1][j] = t.v[k].y;
        m.s[3 * k + 2][j] = t.v[k].z;
      }
      m.s[9][j] = t.normal.x;
      m.s[10][j] = t.normal.y;
      m.s[11][j] = t.normal.z;
    }
    const internal::LambertSources src{{m.s[0].data(), m.s[1].data(), m.s[2].data(), m.s[3].data(), m.s[4].data(),
                                      m.s[5].data(), m.s[6].data(), m.s[7].data(), m.s[8].data()},
                                     m.s[9].data(),
                                     m.s[10].data(),
                                     m.s[11].data()};
    size_t crossing = 0;
    for (size_t q = 0; q < points; ++q) {
      const Vec3& x = r.x[q];
      double* kind = m.kind.data() + q * count;
      internal::lambert_point_sums(count, src, x.x, x.y, x.z, r.normal.x, r.normal.y, r.normal.z,
                                 m.sum.data() + q * count, kind);
      for (size_t j = 0; j < count; ++j) crossing += kind[j] == internal::kSourceCrosses;
    }
    if (crossing > 0) {
      batch.start(crossing);
      for (size_t q = 0; q < points; ++q)
        for (size_t j = 0; j < count; ++j) {
          const size_t i = q * count + j;
          m.clipped[i] = -1;
          if (m.kind[i] != internal::kSourceCrosses) continue;
          const Triangle& t = *sources[j];
          Vec3 e[3];
          double h[3];
          for (size_t k = 0; k < 3; ++k) {
            e[k] = t.v[k] - r.x[q];
            h[k] = glm::dot(r.normal, e[k]);
          }
          std::array<Vec3, 4> loop;
          const int corners = clip_to_tangent_plane(e, h, loop);
          if (corners > 0) m.clipped[i] = static_cast<int>(batch.add_loop(loop, corners));
        }
      batch.sum_all(r.normal);
    }
    for (size_t j = 0; j < count; ++j)
      for (size_t q = 0; q < points; ++q) {
        const size_t i = q * count + j;
        double sum;
        if (m.kind[i] == internal::kSourceInFront)
          sum = m.sum[i];
        else if (m.kind[i] == internal::kSourceCrosses && m.clipped[i] >= 0)
          sum = batch.sum[static_cast<size_t>(m.clipped[i])];
        else
          continue;
        visit(j, q, std::abs(sum) / (2.0 * std::numbers::pi));
      }
    return;
  }
  thread_local std::vector<int> source, point;  // per batch item
  const size_t most = count * points;
  if (source.size() < most) {
    source.resize(most);
    point.resize(most);
  }
  batch.start(most);
  for (size_t j = 0; j < count; ++j) {
    const Triangle& t = *sources[j];
    for (size_t q = 0; q < points; ++q) {
      const Vec3& x = r.x[q];
      if (glm::dot(x - t.v[0], t.normal) <= 0.0) continue;  // behind the source: it emits from its front only
      Vec3 e[3];
      double h[3];  // heights over the point's tangent plane
      bool in_front = true;
      for (size_t k = 0; k < 3; ++k) {
        e[k] = t.v[k] - x;
        h[k] = glm::dot(r.normal, e[k]);
        in_front = in_front && h[k] >= 0.0;
      }
      size_t item;
      if (in_front) {
        batch.put(batch.n, e[0], e[1], e[2]);
        item = batch.n++;
      } else {
        std::array<Vec3, 4> loop;
        const int corners = clip_to_tangent_plane(e, h, loop);
        if (corners == 0) continue;  // nothing in front: F = 0
        item = batch.add_loop(loop, corners);
      }
      source[item] = static_cast<int>(j);
      point[item] = static_cast<int>(q);
    }
  }
  batch.sum_all(r.normal);
  for (size_t i = 0; i < batch.n; ++i)
    visit(static_cast<size_t>(source[i]), static_cast<size_t>(point[i]), std::abs(batch.sum[i]) / (2.0 * std::numbers::pi));
}

}  // namespace

void form_factors(const ReceiverPoints& r, const Triangle* const* sources, size_t count, double* out) {
  std::fill(out, out + count, 0.0);
  point_source_pairs(r, sources, count, [&](size_t j, size_t q, double f) { out[j] += r.w[q] * f; });
}

void point_form_factors(const ReceiverPoints& r, const Triangle& source, double* out) {
  const Triangle* one = &source;
  std::fill(out, out + r.x.size(), 0.0);
  point_source_pairs(r, &one, 1, [&](size_t, size_t q, double f) { out[q] = f; });
}

double element_form_factor(const Triangle& receiver, const Triangle& source, const QuadratureOptions& options) {
  const ReceiverPoints r = receiver_points(
      receiver, [&](const Vec3& p) { return distance_to_triangle(p, source); }, options);
  return form_factor(r, source);
}

double distance_to_triangle(const Vec3& p, const Triangle& t) {
  return glm::length(p - closest_on_triangle(p, t.v[0], t.v[1], t.v[2]));
}

double distance_to_polygon(const Vec3& p, const std::vector<Vec3>& poly, const Vec3& normal) {
  // Inside the outline (winding number in the plane): the distance to the plane.
  const double h = glm::dot(p - poly[0], normal);
  const Vec3 q = p - h * normal;
  const Vec3 u = glm::normalize(poly[1] - poly[0]);
  const Vec3 v = glm::cross(normal, u);
  int winding = 0;
  double edge_dist = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < poly.size(); ++i) {
    const Vec3& a3 = poly[i];
    const Vec3& b3 = poly[(i + 1) % poly.size()];
    edge_dist = std::min(edge_dist, point_segment_distance(p, a3, b3));
    const double ay = glm::dot(a3 - q, v), by = glm::dot(b3 - q, v);
    const double ax = glm::dot(a3 - q, u), bx = glm::dot(b3 - q, u);
    const double cross = ax * by - bx * ay;
    if (ay <= 0.0) {
      if (by > 0.0 && cross > 0.0) ++winding;
    } else if (by <= 0.0 && cross < 0.0) {
      --winding;
    }
  }
  return winding != 0 ? std::abs(h) : edge_dist;
}

}  // namespace radmesh
