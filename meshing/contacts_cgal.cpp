// Contact lines (D0) with exact constructions.

#include "meshing/discontinuity.h"
#include "meshing/errors.h"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace radmesh {

DiscontinuityMode parse_discontinuity_mode(const std::string& text) {
  if (text == "off") return DiscontinuityMode::off;
  if (text == "contacts") return DiscontinuityMode::contacts;
  if (text == "full")
    throw InputError("--discontinuity full: shadow boundaries (D1/D2) are not implemented yet; use contacts or off");
  throw InputError("--discontinuity '" + text + "': expected off or contacts");
}

const char* to_string(DiscontinuityMode mode) { return mode == DiscontinuityMode::off ? "off" : "contacts"; }

namespace {

using EK = CGAL::Exact_predicates_exact_constructions_kernel;

Vec3 to_vec(const EK::Point_3& p) {
  return Vec3(CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z()));
}
EK::Point_3 to_exact(const Vec3& p) { return EK::Point_3(p.x, p.y, p.z); }

struct Poly {
  std::vector<std::vector<Vec3>> loops;  // outer first, then holes
  Vec3 normal, origin, lo, hi;
};

// Where polygon `o` meets the plane of `t`: segments (pairs of points).
std::vector<std::pair<Vec3, Vec3>> slice(const Poly& o, const Poly& t, double eps) {
  const EK::Plane_3 plane(to_exact(t.origin), EK::Vector_3(t.normal.x, t.normal.y, t.normal.z));
  std::vector<std::pair<Vec3, Vec3>> out;
  std::vector<Vec3> crossings;
  const Vec3 dir = glm::cross(t.normal, o.normal);  // direction of the common line
  for (const auto& loop : o.loops) {
    const size_t n = loop.size();
    std::vector<double> d(n);
    for (size_t i = 0; i < n; ++i) {
      d[i] = glm::dot(loop[i] - t.origin, t.normal);
      if (std::abs(d[i]) <= eps) d[i] = 0.0;
    }
    for (size_t i = 0; i < n; ++i) {
      const size_t j = (i + 1) % n;
      if (d[i] == 0.0 && d[j] == 0.0) {
        out.push_back({loop[i], loop[j]});  // an edge lying in the plane
      } else if ((d[i] < 0.0 && d[j] > 0.0) || (d[i] > 0.0 && d[j] < 0.0)) {
        const auto hit = CGAL::intersection(EK::Segment_3(to_exact(loop[i]), to_exact(loop[j])), plane);
        if (hit)
          if (const EK::Point_3* p = boost::get<EK::Point_3>(&*hit)) crossings.push_back(to_vec(*p));
      } else if (d[i] == 0.0) {
        // A vertex on the plane where the loop passes through it (neighbours on
        // opposite sides) is a crossing; a vertex touching it is not.
        const double prev = d[(i + n - 1) % n];
        if ((prev < 0.0 && d[j] > 0.0) || (prev > 0.0 && d[j] < 0.0)) crossings.push_back(loop[i]);
      }
    }
  }
  // Crossings pair up along the common line (even-odd).
  std::sort(crossings.begin(), crossings.end(),
            [&](const Vec3& a, const Vec3& b) { return glm::dot(a, dir) < glm::dot(b, dir); });
  for (size_t k = 0; k + 1 < crossings.size(); k += 2) out.push_back({crossings[k], crossings[k + 1]});
  return out;
}

// Point-in-polygon (even-odd over all loops) in t's plane.
bool inside(const Poly& t, const Vec3& p) {
  const Vec3 u = glm::normalize(t.loops[0][1] - t.loops[0][0]);
  const Vec3 v = glm::cross(t.normal, u);
  const double px = glm::dot(p - t.origin, u), py = glm::dot(p - t.origin, v);
  bool in = false;
  for (const auto& loop : t.loops)
    for (size_t i = 0, n = loop.size(); i < n; ++i) {
      const double ax = glm::dot(loop[i] - t.origin, u), ay = glm::dot(loop[i] - t.origin, v);
      const double bx = glm::dot(loop[(i + 1) % n] - t.origin, u), by = glm::dot(loop[(i + 1) % n] - t.origin, v);
      if ((ay > py) != (by > py) && px < ax + (py - ay) * (bx - ax) / (by - ay)) in = !in;
    }
  return in;
}

double boundary_distance(const Poly& t, const Vec3& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& loop : t.loops)
    for (size_t i = 0, n = loop.size(); i < n; ++i) {
      const Vec3 a = loop[i], ab = loop[(i + 1) % n] - a;
      const double s = std::clamp(glm::dot(p - a, ab) / glm::dot(ab, ab), 0.0, 1.0);
      best = std::min(best, glm::length(p - (a + s * ab)));
    }
  return best;
}

// The parts of segment (a, b) inside polygon t and off its boundary.
void clip(const Poly& t, const Vec3& a, const Vec3& b, double eps, int patch, int other,
          std::vector<DiscontinuitySegment>& out) {
  const Vec3 ab = b - a;
  const double len = glm::length(ab);
  if (len <= eps) return;
  std::vector<double> ts = {0.0, 1.0};
  // Parameters where the segment meets t's boundary edges (in t's plane).
  for (const auto& loop : t.loops)
    for (size_t i = 0, n = loop.size(); i < n; ++i) {
      const Vec3 c = loop[i], cd = loop[(i + 1) % n] - c;
      const Vec3 w = glm::cross(ab, cd);
      const double ww = glm::dot(w, w);
      if (ww <= 0.0) {  // parallel: collinear overlap ends count
        for (const Vec3& q : {c, c + cd}) {
          const double s = glm::dot(q - a, ab) / (len * len);
          if (s > 0.0 && s < 1.0 && glm::length(a + s * ab - q) <= eps) ts.push_back(s);
        }
        continue;
      }
      const double s = glm::dot(glm::cross(c - a, cd), w) / ww;
      const double r = glm::dot(glm::cross(c - a, ab), w) / ww;
      if (s > 0.0 && s < 1.0 && r >= -1e-12 && r <= 1.0 + 1e-12) ts.push_back(s);
    }
  std::sort(ts.begin(), ts.end());
  for (size_t k = 0; k + 1 < ts.size(); ++k) {
    if ((ts[k + 1] - ts[k]) * len <= eps) continue;
    const Vec3 mid = a + 0.5 * (ts[k] + ts[k + 1]) * ab;
    if (boundary_distance(t, mid) <= eps || !inside(t, mid)) continue;
    DiscontinuitySegment seg;
    seg.patch = patch;
    seg.other = other;
    seg.kind = 0;
    seg.a = a + ts[k] * ab;
    seg.b = a + ts[k + 1] * ab;
    out.push_back(seg);
  }
}

}  // namespace

std::vector<DiscontinuitySegment> contact_segments(const Scene& scene) {
  const double eps = 1e-9 * scene.diagonal();
  std::vector<Poly> polys(scene.patches.size());
  for (size_t p = 0; p < polys.size(); ++p) {
    const Patch& patch = scene.patches[p];
    Poly& poly = polys[p];
    poly.loops.push_back(scene.loop_points(patch.outer));
    for (const auto& h : patch.holes) poly.loops.push_back(scene.loop_points(h));
    poly.normal = patch.normal;
    poly.origin = poly.loops[0][0];
    poly.lo = poly.hi = poly.origin;
    for (const Vec3& v : poly.loops[0]) {
      poly.lo = glm::min(poly.lo, v);
      poly.hi = glm::max(poly.hi, v);
    }
  }
  std::vector<DiscontinuitySegment> out;
  for (size_t p = 0; p < polys.size(); ++p)
    for (size_t q = 0; q < polys.size(); ++q) {
      if (p == q) continue;
      const Poly& t = polys[p];
      const Poly& o = polys[q];
      if (glm::any(glm::lessThan(t.hi + eps, o.lo)) || glm::any(glm::lessThan(o.hi + eps, t.lo))) continue;
      if (glm::length(glm::cross(t.normal, o.normal)) <= 1e-12) continue;  // parallel or coplanar
      for (const auto& [a, b] : slice(o, t, eps))
        clip(t, a, b, eps, static_cast<int>(p), static_cast<int>(q), out);
    }
  return out;
}

}  // namespace radmesh
