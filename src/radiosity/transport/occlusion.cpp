// Occlusion without rays: which patches may lie between two elements or a
// point and an element (their shaft), so that rays are cast only where
// something can occlude, and the scene's convex-enclosure test.

#include "radiosity/transport/occlusion.h"

#include <algorithm>
#include <limits>

namespace radmesh {

namespace {

// Whether a polygon k lies outside the convex hull of the polygons a and b
// (normals na, nb): true when every point of k lies on or outside some
// supporting plane of that hull. Then k meets no segment from a to b but
// those on the hull's boundary, which join points on the edges of a and b
// (no area of either: they carry no light). Planes tried: the two
// polygons' own planes and the planes through an edge of one polygon and a
// vertex of the other that have both polygons on one side. A patch that
// only touches the hull (a wall of the room along which the shaft runs, a
// face standing on the edge of one polygon) is thus clear; otherwise its
// shadow rays would be cast, and the few that graze it in single precision
// would make a pair near the room's corners look partly hidden.
// The planes depend on a and b alone: they are made as the first polygon
// tested needs them, in a fixed order, and kept for the next ones (a shaft
// has several candidates, and each would make every plane anew). A plane costs a
// pass over a's and b's points, and there are 2 |a| |b| to try: past
// kMostWork points classified, no more are tried (a shaft between two
// round faces of 20,000 vertices each would take 3 x 10^13 steps),
// and the candidate is taken as in the way (its rays are cast).
template <class A, class B>
class ShaftPlanes {
public:
  ShaftPlanes(const A& a, const B& b, const Vec3& na, const Vec3& nb, double eps)
      : a_(a), b_(b), na_(na), nb_(nb), eps_(eps), planes_(scratch()) {
    planes_.clear();
  }
  template <class C>
  bool separates(const C& k) {
    if (behind_all(k, a_[0], na_) || behind_all(k, b_[0], nb_)) return true;
    for (const Plane& p : planes_)
      if (outside(k, p)) return true;
    Plane p;
    while (next(p)) {
      planes_.push_back(p);
      if (outside(k, p)) return true;
    }
    return false;
  }

private:
  struct Plane {
    Vec3 origin, normal;
  };
  static std::vector<Plane>& scratch() {
    thread_local std::vector<Plane> planes;
    return planes;
  }
  template <class C>
  bool behind_all(const C& k, const Vec3& origin, const Vec3& n) const {
    for (const Vec3& p : k)
      if (glm::dot(p - origin, n) > eps_) return false;
    return true;
  }
  template <class C>
  bool outside(const C& k, const Plane& p) const {
    for (const Vec3& q : k)
      if (glm::dot(q - p.origin, p.normal) < -eps_) return false;
    return true;
  }
  // The next supporting plane through an edge of one polygon (a's edges
  // with b's vertices, then b's with a's) and a vertex of the other,
  // oriented with both polygons on its non-positive side; false when none
  // is left.
  bool next(Plane& out) {
    const size_t na = std::size(a_), nb = std::size(b_);
    while (side_ < 2 && work_ <= kMostWork) {
      const bool from_a = side_ == 0;
      const size_t ne = from_a ? na : nb, no = from_a ? nb : na;
      if (edge_ == ne) {
        ++side_;
        edge_ = corner_ = 0;
        continue;
      }
      const size_t i = edge_, c = corner_;
      if (++corner_ == no) {
        corner_ = 0;
        ++edge_;
      }
      work_ += na + nb;
      if (from_a ? plane(a_, b_, i, c, out) : plane(b_, a_, i, c, out)) return true;
    }
    return false;
  }
  template <class E, class O>
  bool plane(const E& e, const O& o, size_t i, size_t c, Plane& out) const {
    const size_t ne = std::size(e);
    const Vec3& p0 = e[i];
    const Vec3& p1 = e[(i + 1) % ne];
    Vec3 m = glm::cross(p1 - p0, o[c] - p0);
    const double len = glm::length(m);
    if (len <= 0.0) return false;
    m /= len;
    int pos = 0, neg = 0;
    for (const Vec3& q : e) {
      const double d = glm::dot(q - p0, m);
      pos += d > eps_;
      neg += d < -eps_;
    }
    for (const Vec3& q : o) {
      const double d = glm::dot(q - p0, m);
      pos += d > eps_;
      neg += d < -eps_;
    }
    if (pos > 0 && neg > 0) return false;  // not a supporting plane
    out = {p0, pos > 0 ? -m : m};
    return true;
  }

  const A& a_;
  const B& b_;
  Vec3 na_, nb_;
  double eps_;
  std::vector<Plane>& planes_;
  size_t side_ = 0, edge_ = 0, corner_ = 0;
  static constexpr size_t kMostWork = size_t{1} << 20;  // two polygons of 250 vertices and 4 need 532 k
  size_t work_ = 0;
};

}  // namespace

Occlusion::Occlusion(const Scene& scene) {
  const size_t np = scene.patches.size();
  eps_ = 1e-9 * scene.diagonal();
  polys_.resize(np);
  std::vector<Box3> boxes(np);
  for (size_t p = 0; p < np; ++p) {
    Poly& poly = polys_[p];
    poly.v = scene.loop_points(scene.patches[p].outer);
    poly.normal = scene.patches[p].normal;
    for (const Vec3& v : poly.v) poly.box.add(v);
    boxes[p] = poly.box;
  }
  // Convex enclosure: no vertex behind any patch. The scene's bounding-box
  // corners decide most patches at once (every vertex lies in the box, so a
  // patch with all eight corners in front has every vertex in front).
  Box3 all;
  for (const Poly& poly : polys_) all.add(poly.box);
  convex_ = true;
  for (size_t p = 0; p < np && convex_; ++p) {
    bool corners_in_front = true;
    for (int c = 0; c < 8 && corners_in_front; ++c) {
      const Vec3 corner((c & 1) ? all.hi.x : all.lo.x, (c & 2) ? all.hi.y : all.lo.y, (c & 4) ? all.hi.z : all.lo.z);
      corners_in_front = glm::dot(corner - polys_[p].v[0], polys_[p].normal) >= -eps_;
    }
    if (corners_in_front) continue;
    for (const Vec3& v : scene.vertices)
      if (glm::dot(v - polys_[p].v[0], polys_[p].normal) < -eps_) {
        convex_ = false;
        break;
      }
  }
  tree_ = BoxTree(boxes);  // also for patches_near
  if (convex_) return;
  if (np <= kCachedPatches) {
    pair_ = std::make_unique<std::atomic<unsigned char>[]>(np * np);
    for (size_t i = 0; i < np * np; ++i) pair_[i].store(0, std::memory_order_relaxed);
  }
}

template <class A, class B>
bool Occlusion::shaft_blocked(int pa, int pb, const A& a, const B& b, const Vec3& na, const Vec3& nb) const {
  Box3 shaft;
  for (const Vec3& v : a) shaft.add(v);
  for (const Vec3& v : b) shaft.add(v);
  // The candidates first: with more than kMaxTests of them the shaft is
  // taken as occludable whatever the tests would say, so none is made.
  std::array<int, kMaxTests> candidates;
  int count = 0;
  const bool few = tree_.overlapping(shaft, eps_, [&](int k) {
    if (k == pa || k == pb) return true;
    if (count == kMaxTests) return false;
    candidates[static_cast<size_t>(count++)] = k;
    return true;
  });
  if (!few) return true;
  if (count == 0) return false;
  ShaftPlanes<A, B> planes(a, b, na, nb, eps_);
  for (int i = 0; i < count; ++i)
    if (!planes.separates(polys_[static_cast<size_t>(candidates[static_cast<size_t>(i)])].v)) return true;
  return false;
}

bool Occlusion::may_occlude(int p, int q) const {
  if (convex_ || p == q) return false;
  const size_t np = polys_.size();
  const size_t a = static_cast<size_t>(std::min(p, q)), b = static_cast<size_t>(std::max(p, q));
  if (pair_) {
    const unsigned char known = pair_[a * np + b].load(std::memory_order_relaxed);
    if (known) return known == 2;
  }
  const Poly& pp = polys_[a];
  const Poly& pq = polys_[b];
  const bool blocked = shaft_blocked(static_cast<int>(a), static_cast<int>(b), pp.v, pq.v, pp.normal, pq.normal);
  if (pair_) pair_[a * np + b].store(blocked ? 2 : 1, std::memory_order_relaxed);
  return blocked;
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

void Occlusion::patches_near(const Vec3& x, double r, std::vector<int>& out) const {
  out.clear();
  tree_.overlapping(Box3{x, x}, r, [&](int k) {
    out.push_back(k);
    return true;
  });
  std::sort(out.begin(), out.end());
}

double Occlusion::distance(int p, const Vec3& x) const {
  const Poly& poly = polys_[static_cast<size_t>(p)];
  return distance_to_polygon(x, poly.v, poly.normal);
}

bool Occlusion::may_occlude(int pa, int pb, const Triangle& a, const Triangle& b) const {
  if (convex_) return false;
  if (pa == pb) return false;  // a planar patch: a segment between its points stays in its plane
  if (pair_ && !may_occlude(pa, pb)) return false;  // the patches' shaft is clear, so is theirs
  return shaft_blocked(pa, pb, a.v, b.v, a.normal, b.normal);
}

template <class B>
bool Occlusion::point_shaft(int px, const Vec3& x, const Vec3& nx, int pb, const B& b, const Vec3& nb) const {
  if (convex_ || px == pb) return false;
  if (pair_ && !may_occlude(px, pb)) return false;  // the patches' shaft is clear, so is this one
  return shaft_blocked(px, pb, std::array<Vec3, 1>{x}, b, nx, nb);
}

bool Occlusion::may_occlude(int px, const Vec3& x, const Vec3& nx, int pb, const std::array<Vec3, 4>& b,
                            const Vec3& nb) const {
  return point_shaft(px, x, nx, pb, b, nb);
}

bool Occlusion::may_occlude(int px, const Vec3& x, const Vec3& nx, int pb, const Triangle& b) const {
  return point_shaft(px, x, nx, pb, b.v, b.normal);
}

Occlusion::Candidates Occlusion::candidates(int px, const Vec3& x, const Vec3& nx, int pb) const {
  Candidates c;
  const Poly& b = polys_[static_cast<size_t>(pb)];
  Box3 shaft = b.box;
  shaft.add(x);
  const std::array<Vec3, 1> a{x};
  // At most 4 x kMaxTests patches tested, so that a point's cost per source
  // stays bounded where the whole source's shaft meets many boxes.
  int tested = 0;
  ShaftPlanes<std::array<Vec3, 1>, std::vector<Vec3>> planes(a, b.v, nx, b.normal, eps_);
  c.all = !tree_.overlapping(shaft, eps_, [&](int k) {
    if (k == px || k == pb) return true;
    if (++tested > 4 * kMaxTests) return false;
    if (planes.separates(polys_[static_cast<size_t>(k)].v)) return true;
    if (c.count == kMaxTests) return false;
    c.k[static_cast<size_t>(c.count++)] = k;
    return true;
  });
  return c;
}

template <class B>
bool Occlusion::candidate_shaft(const Candidates& c, int px, const Vec3& x, const Vec3& nx, int pb, const B& b,
                                const Vec3& nb) const {
  if (c.all) return point_shaft(px, x, nx, pb, b, nb);
  if (c.count == 0) return false;
  Box3 shaft;
  shaft.add(x);
  for (const Vec3& v : b) shaft.add(v);
  const std::array<Vec3, 1> a{x};
  ShaftPlanes<std::array<Vec3, 1>, B> planes(a, b, nx, nb, eps_);
  for (int i = 0; i < c.count; ++i) {
    const Poly& k = polys_[static_cast<size_t>(c.k[static_cast<size_t>(i)])];
    if (k.box.overlaps(shaft, eps_) && !planes.separates(k.v)) return true;
  }
  return false;
}

bool Occlusion::may_occlude(const Candidates& c, int px, const Vec3& x, const Vec3& nx, int pb,
                            const std::array<Vec3, 4>& b, const Vec3& nb) const {
  return candidate_shaft(c, px, x, nx, pb, b, nb);
}

bool Occlusion::may_occlude(const Candidates& c, int px, const Vec3& x, const Vec3& nx, int pb,
                            const Triangle& b) const {
  return candidate_shaft(c, px, x, nx, pb, b.v, b.normal);
}

}  // namespace radmesh
