// MGF's geometry as planar faces (mgf.h): faces with seams split into an
// outline and holes, and the curved primitives and prisms. Every face of a
// curved primitive is planar by construction: a band between two parallel
// circles is cut into isosceles trapezoids, whose four corners lie in one
// plane.

#include "io/readers/mgf.h"

#include "core/degrees.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

namespace radmesh::internal::mgf {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Unit vectors u, v with u x v = w (w a unit vector).
void frame(const Vec3& w, Vec3* u, Vec3* v) {
  const Vec3 helper = std::abs(w.x) < 0.6 ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
  *u = glm::normalize(glm::cross(helper, w));
  *v = glm::cross(w, *u);
}

// cos and sin of 2 pi k / n, exact at the quarter turns (360 k / n is then
// a whole multiple of 90, exactly).
void unit_circle(int k, int n, double* c, double* s) {
  cos_sin_degrees(360.0 * k / n, c, s);
}

// Segments per full turn for a surface bent two ways (sphere, torus): each
// way's chords within sqrt(1 - tolerance) of the radius in cosine, so that
// a face's plane stays within (1 - cos a)(1 - cos b) <= tolerance of it.
int curved_segments(double tolerance) { return circle_segments(1.0 - std::sqrt(1.0 - tolerance)); }

// Whether p lies inside `loop`, in the loop's plane (seen along the axis
// nearest its normal).
bool inside(const Vec3& p, const std::vector<Vec3>& loop) {
  const Vec3 n = glm::abs(newell_normal(loop));
  const int drop = n.x >= n.y && n.x >= n.z ? 0 : (n.y >= n.z ? 1 : 2);
  const int u = (drop + 1) % 3, v = (drop + 2) % 3;
  bool in = false;
  for (size_t k = 0, j = loop.size() - 1; k < loop.size(); j = k++) {
    const Vec3 &a = loop[k], &b = loop[j];
    if ((a[v] > p[v]) != (b[v] > p[v]) && p[u] < (b[u] - a[u]) * (p[v] - a[v]) / (b[v] - a[v]) + a[u]) in = !in;
  }
  return in;
}

void emit(std::vector<Vec3> outer, bool inward, const FaceSink& sink) {
  if (inward) std::reverse(outer.begin() + 1, outer.end());
  sink({std::move(outer), {}});
}

}  // namespace

bool split_at_seams(std::vector<Vec3> loop, Seamed* out) {
  using Key = std::array<double, 3>;
  auto key = [](const Vec3& p) { return Key{p.x, p.y, p.z}; };
  std::vector<std::vector<Vec3>> done, work;
  work.push_back(std::move(loop));
  while (!work.empty()) {
    std::vector<Vec3> l = std::move(work.back());
    work.pop_back();
    const size_t n = l.size();
    // The first edge whose reverse came before it, and that one.
    std::map<std::pair<Key, Key>, size_t> edges;
    size_t first = n, second = n;
    for (size_t k = 0; k < n && first == n; ++k) {
      const Vec3 &a = l[k], &b = l[(k + 1) % n];
      if (a == b) continue;
      const auto back = edges.find({key(b), key(a)});
      if (back != edges.end()) {
        first = back->second;
        second = k;
      }
      edges.emplace(std::make_pair(key(a), key(b)), k);
    }
    if (first == n) {
      done.push_back(std::move(l));
      continue;
    }
    // Cutting edges `first` and `second` leaves the loops from just after
    // each to the other, each ending where it starts.
    std::vector<Vec3> one(l.begin() + static_cast<long>(first) + 1, l.begin() + static_cast<long>(second) + 1);
    std::vector<Vec3> two(l.begin() + static_cast<long>(second) + 1, l.end());
    two.insert(two.end(), l.begin(), l.begin() + static_cast<long>(first) + 1);
    for (auto* part : {&one, &two}) {
      part->pop_back();
      if (part->size() >= 3) work.push_back(std::move(*part));
    }
  }
  if (done.empty()) return false;
  auto area = [](const std::vector<Vec3>& p) { return glm::length(newell_normal(p)); };
  const auto largest =
      std::max_element(done.begin(), done.end(), [&](const auto& x, const auto& y) { return area(x) < area(y); });
  out->outer = std::move(*largest);
  done.erase(largest);
  for (auto& l : done) (inside(l.front(), out->outer) ? out->holes : out->islands).push_back(std::move(l));
  return true;
}

int circle_segments(double deviation) {
  // A chord of angle a lies r (1 - cos(a / 2)) from its arc at most.
  const double angle = 2.0 * std::acos(1.0 - deviation);
  return std::max(3, static_cast<int>(std::ceil(2.0 * kPi / angle)));
}

void sphere(const Vec3& center, double radius, double tolerance, const FaceSink& sink) {
  const double r = std::abs(radius);
  const int around = std::max(4, curved_segments(tolerance));
  const int bands = std::max(2, (around + 1) / 2);
  // Point of band boundary i (0: the north pole) at meridian j.
  auto at = [&](int i, int j) {
    if (i == 0) return center + Vec3(0, 0, r);
    if (i == bands) return center - Vec3(0, 0, r);
    double cz = 0.0, sz = 0.0, c = 0.0, s = 0.0;
    unit_circle(i, 2 * bands, &cz, &sz);  // polar angle pi i / bands
    unit_circle(j % around, around, &c, &s);
    return center + r * Vec3(sz * c, sz * s, cz);
  };
  for (int i = 0; i < bands; ++i)
    for (int j = 0; j < around; ++j) {
      std::vector<Vec3> face;
      if (i == 0)
        face = {at(0, 0), at(1, j), at(1, j + 1)};
      else if (i == bands - 1)
        face = {at(i, j), at(bands, 0), at(i, j + 1)};
      else
        face = {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)};
      emit(std::move(face), radius < 0.0, sink);
    }
}

void cone(const Vec3& a, double ra, const Vec3& b, double rb, double tolerance, const FaceSink& sink) {
  const bool inward = ra < 0.0 || rb < 0.0;
  ra = std::abs(ra);
  rb = std::abs(rb);
  const Vec3 w = glm::normalize(b - a);
  Vec3 u, v;
  frame(w, &u, &v);
  const int n = circle_segments(tolerance);
  auto on = [&](const Vec3& c, double r, int k) {
    double cs = 0.0, sn = 0.0;
    unit_circle(k % n, n, &cs, &sn);
    return c + r * (cs * u + sn * v);
  };
  for (int k = 0; k < n; ++k) {
    // Counter-clockwise around the outward normal: along the circle at a,
    // then towards b.
    std::vector<Vec3> face;
    if (ra == 0.0)
      face = {a, on(b, rb, k + 1), on(b, rb, k)};
    else if (rb == 0.0)
      face = {on(a, ra, k), on(a, ra, k + 1), b};
    else
      face = {on(a, ra, k), on(a, ra, k + 1), on(b, rb, k + 1), on(b, rb, k)};
    emit(std::move(face), inward, sink);
  }
}

void ring(const Vec3& center, const Vec3& normal, double rmin, double rmax, double tolerance, const FaceSink& sink) {
  Vec3 u, v;
  frame(normal, &u, &v);
  const int n = circle_segments(tolerance);
  ShapeFace face;
  std::vector<Vec3> inner;
  for (int k = 0; k < n; ++k) {
    double c = 0.0, s = 0.0;
    unit_circle(k, n, &c, &s);
    face.outer.push_back(center + rmax * (c * u + s * v));
    if (rmin > 0.0) inner.push_back(center + rmin * (c * u + s * v));
  }
  if (!inner.empty()) {
    std::reverse(inner.begin() + 1, inner.end());
    face.holes.push_back(std::move(inner));
  }
  sink(std::move(face));
}

void torus(const Vec3& center, const Vec3& normal, double rmin, double rmax, double tolerance, const FaceSink& sink) {
  const bool inward = rmin < 0.0 || rmax < 0.0;
  const double tube = (std::abs(rmax) - std::abs(rmin)) / 2.0, middle = (std::abs(rmax) + std::abs(rmin)) / 2.0;
  Vec3 u, v;
  frame(normal, &u, &v);
  const int around = curved_segments(tolerance), across = std::max(4, around);
  // Point at angle i around the axis and j around the tube (0: outside).
  auto at = [&](int i, int j) {
    double c = 0.0, s = 0.0, ct = 0.0, st = 0.0;
    unit_circle(i % around, around, &c, &s);
    unit_circle(j % across, across, &ct, &st);
    return center + (middle + tube * ct) * (c * u + s * v) + tube * st * normal;
  };
  for (int i = 0; i < around; ++i)
    for (int j = 0; j < across; ++j) {
      std::vector<Vec3> face = {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)};
      // With rmin 0 the tube's inside edge is the axis: two corners meet there.
      if (face[2] == face[3]) face.erase(face.begin() + 3);
      if (face[0] == face[1]) face.erase(face.begin());
      emit(std::move(face), inward, sink);
    }
}

void prism(const std::vector<Vec3>& base, double length, const FaceSink& sink) {
  const Vec3 offset = -length * glm::normalize(newell_normal(base));
  const size_t n = base.size();
  std::vector<Vec3> far;
  for (size_t k = 0; k < n; ++k) far.push_back(base[k] + offset);
  sink({base, {}});
  std::vector<Vec3> top = far;
  std::reverse(top.begin() + 1, top.end());
  sink({std::move(top), {}});
  for (size_t k = 0; k < n; ++k) {
    const size_t next = (k + 1) % n;
    sink({{base[next], base[k], far[k], far[next]}, {}});
  }
}

}  // namespace radmesh::internal::mgf
