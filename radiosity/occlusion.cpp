#include "radiosity/occlusion.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>

namespace radmesh {

namespace {

struct Box {
  Vec3 lo{std::numeric_limits<double>::infinity()}, hi{-std::numeric_limits<double>::infinity()};
  void add(const Vec3& p) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  bool overlaps(const Vec3& olo, const Vec3& ohi, double eps) const {
    return !(glm::any(glm::lessThan(hi + eps, olo)) || glm::any(glm::lessThan(ohi + eps, lo)));
  }
};

// True when every point of `k` lies strictly outside some supporting plane
// of the convex hull of a and b: then k cannot meet any segment from a to b.
// Planes tried: the two polygons' own planes and the planes through an edge
// of one polygon and a vertex of the other that have both polygons on one side.
template <class A, class B, class C>
bool separated(const A& a, const B& b, const C& k, const Vec3& na, const Vec3& nb, double eps) {
  auto behind_all = [&](const Vec3& origin, const Vec3& n) {
    for (const Vec3& p : k)
      if (glm::dot(p - origin, n) > eps) return false;
    return true;
  };
  if (behind_all(a[0], na) || behind_all(b[0], nb)) return true;
  auto try_planes = [&](const auto& e, const auto& o) {
    const size_t ne = std::size(e);
    for (size_t i = 0; i < ne; ++i) {
      const Vec3& p0 = e[i];
      const Vec3& p1 = e[(i + 1) % ne];
      for (const Vec3& c : o) {
        Vec3 m = glm::cross(p1 - p0, c - p0);
        const double len = glm::length(m);
        if (len <= 0.0) continue;
        m /= len;
        // Orientation such that both polygons are on the non-positive side.
        int pos = 0, neg = 0;
        for (const Vec3& q : e) {
          const double d = glm::dot(q - p0, m);
          pos += d > eps;
          neg += d < -eps;
        }
        for (const Vec3& q : o) {
          const double d = glm::dot(q - p0, m);
          pos += d > eps;
          neg += d < -eps;
        }
        if (pos > 0 && neg > 0) continue;  // not a supporting plane
        if (pos > 0) m = -m;
        bool out = true;
        for (const Vec3& q : k)
          if (glm::dot(q - p0, m) <= eps) {
            out = false;
            break;
          }
        if (out) return true;
      }
    }
    return false;
  };
  return try_planes(a, b) || try_planes(b, a);
}

}  // namespace

Occlusion::Occlusion(const Scene& scene) {
  const size_t np = scene.patches.size();
  eps_ = 1e-9 * scene.diagonal();
  polys_.resize(np);
  for (size_t p = 0; p < np; ++p) {
    Poly& poly = polys_[p];
    poly.v = scene.loop_points(scene.patches[p].outer);
    poly.normal = scene.patches[p].normal;
    Box b;
    for (const Vec3& v : poly.v) b.add(v);
    poly.lo = b.lo;
    poly.hi = b.hi;
  }
  convex_ = true;
  for (size_t p = 0; p < np && convex_; ++p)
    for (const Vec3& v : scene.vertices)
      if (glm::dot(v - polys_[p].v[0], polys_[p].normal) < -eps_) {
        convex_ = false;
        break;
      }
  cand_.resize(np * np);
  if (convex_) return;
  tbb::parallel_for(size_t(0), np, [&](size_t p) {
    for (size_t q = p + 1; q < np; ++q) {
      Box pq;
      for (const Vec3& v : polys_[p].v) pq.add(v);
      for (const Vec3& v : polys_[q].v) pq.add(v);
      std::vector<int>& out = cand_[p * np + q];
      for (size_t k = 0; k < np; ++k) {
        if (k == p || k == q) continue;
        if (!pq.overlaps(polys_[k].lo, polys_[k].hi, eps_)) continue;
        if (separated(polys_[p].v, polys_[q].v, polys_[k].v, polys_[p].normal, polys_[q].normal, eps_))
          continue;
        out.push_back(static_cast<int>(k));
      }
    }
  });
}

const std::vector<int>& Occlusion::candidates(int p, int q) const {
  const size_t np = polys_.size();
  const size_t a = static_cast<size_t>(std::min(p, q)), b = static_cast<size_t>(std::max(p, q));
  return cand_[a * np + b];
}

bool Occlusion::facing(int p, int q) const {
  auto in_front = [&](const Poly& plane, const Poly& other) {
    for (const Vec3& v : other.v)
      if (glm::dot(v - plane.v[0], plane.normal) > eps_) return true;
    return false;
  };
  const Poly& a = polys_[static_cast<size_t>(p)];
  const Poly& b = polys_[static_cast<size_t>(q)];
  return in_front(a, b) && in_front(b, a);
}

double Occlusion::distance(int p, const Vec3& x) const {
  const Poly& poly = polys_[static_cast<size_t>(p)];
  return distance_to_polygon(x, poly.v, poly.normal);
}

bool Occlusion::may_occlude(int pa, int pb, const Triangle& a, const Triangle& b) const {
  if (convex_) return false;
  if (pa == pb) return false;  // a planar patch: a segment between its points stays in its plane
  const auto& cands = candidates(pa, pb);
  if (cands.empty()) return false;
  Box ab;
  for (const Vec3& v : a.v) ab.add(v);
  for (const Vec3& v : b.v) ab.add(v);
  for (int k : cands) {
    const Poly& poly = polys_[static_cast<size_t>(k)];
    if (!ab.overlaps(poly.lo, poly.hi, eps_)) continue;
    if (separated(a.v, b.v, poly.v, a.normal, b.normal, eps_)) continue;
    return true;
  }
  return false;
}

}  // namespace radmesh
