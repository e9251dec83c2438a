// Discontinuity lines with exact constructions: contacts (D0) and the
// shadow boundaries of emitter polygons (D1/D2).

#include "core/box_tree.h"
#include "radmesh/discontinuity.h"
#include "radmesh/errors.h"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <set>

namespace radmesh {

DiscontinuityMode parse_discontinuity_mode(const std::string& text) {
  if (text == "off") return DiscontinuityMode::off;
  if (text == "contacts") return DiscontinuityMode::contacts;
  if (text == "full") return DiscontinuityMode::full;
  throw InputError("discontinuity '" + text + "': expected off, contacts or full", {"discontinuity"});
}

const char* to_string(DiscontinuityMode mode) {
  switch (mode) {
    case DiscontinuityMode::off: return "off";
    case DiscontinuityMode::contacts: return "contacts";
    case DiscontinuityMode::full: return "full";
  }
  return "?";
}

namespace {

using EK = CGAL::Exact_predicates_exact_constructions_kernel;

Vec3 to_vec(const EK::Point_3& p) {
  return Vec3(CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z()));
}
EK::Point_3 to_exact(const Vec3& p) { return EK::Point_3(p.x, p.y, p.z); }

struct Poly {
  std::vector<std::vector<Vec3>> loops;  // outer first, then holes
  Vec3 normal, origin, lo, hi;
  Vec3 u, v;                                            // in-plane frame
  std::vector<std::vector<std::array<double, 2>>> loops2;  // loops in (u, v)
  double dist(const Vec3& p) const { return glm::dot(p - origin, normal); }
  std::array<double, 2> to2(const Vec3& p) const { return {glm::dot(p - origin, u), glm::dot(p - origin, v)}; }
};

std::vector<Poly> make_polys(const Scene& scene) {
  std::vector<Poly> polys(scene.patches.size());
  for (size_t p = 0; p < polys.size(); ++p) {
    const Patch& patch = scene.patches[p];
    Poly& poly = polys[p];
    poly.loops.push_back(scene.loop_points(patch.outer));
    for (const auto& h : patch.holes) poly.loops.push_back(scene.loop_points(h));
    poly.normal = patch.normal;
    poly.origin = poly.loops[0][0];
    poly.lo = poly.hi = poly.origin;
    for (const Vec3& q : poly.loops[0]) {
      poly.lo = glm::min(poly.lo, q);
      poly.hi = glm::max(poly.hi, q);
    }
    poly.u = glm::normalize(poly.loops[0][1] - poly.loops[0][0]);
    poly.v = glm::cross(poly.normal, poly.u);
    for (const auto& loop : poly.loops) {
      poly.loops2.emplace_back();
      for (const Vec3& q : loop) poly.loops2.back().push_back(poly.to2(q));
    }
  }
  return polys;
}

// Each patch's bounding box, in patch order (for BoxTree).
std::vector<Box3> poly_boxes(const std::vector<Poly>& polys) {
  std::vector<Box3> boxes(polys.size());
  for (size_t p = 0; p < polys.size(); ++p) {
    boxes[p].lo = polys[p].lo;
    boxes[p].hi = polys[p].hi;
  }
  return boxes;
}

// The patches whose boxes come within `margin` of `box`, in patch order (as
// a scan would find them), into `out`.
void near_patches(const BoxTree& tree, const Box3& box, double margin, std::vector<int>& out) {
  out.clear();
  tree.overlapping(box, margin, [&](int q) {
    out.push_back(q);
    return true;
  });
  std::sort(out.begin(), out.end());
}

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
  const auto [px, py] = t.to2(p);
  bool in = false;
  for (const auto& loop : t.loops2)
    for (size_t i = 0, n = loop.size(); i < n; ++i) {
      const auto [ax, ay] = loop[i];
      const auto [bx, by] = loop[(i + 1) % n];
      if ((ay > py) != (by > py) && px < ax + (py - ay) * (bx - ax) / (by - ay)) in = !in;
    }
  return in;
}

double boundary_distance(const Poly& t, const Vec3& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& loop : t.loops)
    for (size_t i = 0, n = loop.size(); i < n; ++i)
      best = std::min(best, point_segment_distance(p, loop[i], loop[(i + 1) % n]));
  return best;
}

// The parts of segment (a, b) inside polygon t and off its boundary.
std::vector<std::pair<Vec3, Vec3>> clip(const Poly& t, const Vec3& a, const Vec3& b, double eps) {
  std::vector<std::pair<Vec3, Vec3>> out;
  const Vec3 ab = b - a;
  const double len = glm::length(ab);
  if (len <= eps) return out;
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
    out.push_back({a + ts[k] * ab, a + ts[k + 1] * ab});
  }
  return out;
}

}  // namespace

std::vector<DiscontinuitySegment> contact_segments(const Scene& scene) {
  const double eps = 1e-9 * scene.diagonal();
  const std::vector<Poly> polys = make_polys(scene);
  std::vector<DiscontinuitySegment> out;
  const std::vector<Box3> boxes = poly_boxes(polys);
  const BoxTree tree(boxes);
  std::vector<int> near;
  for (size_t p = 0; p < polys.size(); ++p) {
    near_patches(tree, boxes[p], eps, near);
    for (int qi : near) {
      const size_t q = static_cast<size_t>(qi);
      if (p == q) continue;
      const Poly& t = polys[p];
      const Poly& o = polys[q];
      if (glm::length(glm::cross(t.normal, o.normal)) <= 1e-12) continue;  // parallel or coplanar
      for (const auto& [a, b] : slice(o, t, eps))
        for (const auto& [c, d] : clip(t, a, b, eps)) {
          DiscontinuitySegment seg;
          seg.patch = static_cast<int>(p);
          seg.other = static_cast<int>(q);
          seg.a = c;
          seg.b = d;
          out.push_back(seg);
        }
    }
  }
  return out;
}

std::vector<DiscontinuitySegment> overhang_segments(const Scene& scene, double max_gap) {
  const double eps = 1e-9 * scene.diagonal();
  std::vector<DiscontinuitySegment> out;
  if (!(max_gap > eps)) return out;
  const std::vector<Poly> polys = make_polys(scene);
  const std::vector<Box3> boxes = poly_boxes(polys);
  const BoxTree tree(boxes);
  std::vector<int> near;
  for (size_t p = 0; p < polys.size(); ++p) {
    const Poly& t = polys[p];
    near_patches(tree, boxes[p], max_gap, near);
    for (int qi : near) {
      const Poly& o = polys[static_cast<size_t>(qi)];
      // Only a face that covers the patch (within about 25 degrees of
      // parallel): a steep one near it (a wall's foot a hair above a floor,
      // the lowest triangles of a scanned statue) would project a sliver.
      if (static_cast<size_t>(qi) == p || std::abs(glm::dot(o.normal, t.normal)) < 0.9) continue;
      bool in_front = true;
      for (const Vec3& x : o.loops[0]) {
        const double d = t.dist(x);
        in_front = in_front && d > eps && d <= max_gap;
      }
      if (!in_front) continue;
      for (const auto& loop : o.loops)
        for (size_t i = 0, n = loop.size(); i < n; ++i) {
          const Vec3 a = loop[i] - t.dist(loop[i]) * t.normal;
          const Vec3 b = loop[(i + 1) % n] - t.dist(loop[(i + 1) % n]) * t.normal;
          for (const auto& [c, d] : clip(t, a, b, eps)) {
            DiscontinuitySegment seg;
            seg.patch = static_cast<int>(p);
            seg.other = qi;
            seg.a = c;
            seg.b = d;
            out.push_back(seg);
          }
        }
    }
  }
  return out;
}

namespace {

// Does the segment (a, b) pass through the inside of a patch? It does when a
// and b lie strictly on opposite sides of the patch's plane (beyond eps) and
// the crossing point is inside the polygon. Touching a plane, or starting on
// a patch, does not count. The patches sit in a BoxTree walked along the
// segment: it meets the few patches near it, not every patch of the scene.
class Blockers {
public:
  Blockers(const std::vector<Poly>& polys, double eps) : polys_(polys), eps_(eps), tree_(poly_boxes(polys)) {}
  bool blocked(const Vec3& a, const Vec3& b) const {
    return !tree_.where([&](const Box3& box) { return segment_meets_box(a, b, box); }, [&](int i) {
      const Poly& t = polys_[static_cast<size_t>(i)];
      const double da = t.dist(a), db = t.dist(b);
      if (!((da > eps_ && db < -eps_) || (da < -eps_ && db > eps_))) return true;
      return !inside(t, a + (da / (da - db)) * (b - a));
    });
  }
  const BoxTree& tree() const { return tree_; }

private:
  // Does segment (a, b) meet the box grown by eps? (Slabs: the parameter
  // interval inside each pair of faces.)
  bool segment_meets_box(const Vec3& a, const Vec3& b, const Box3& box) const {
    double t0 = 0.0, t1 = 1.0;
    for (int k = 0; k < 3; ++k) {
      const double lo = box.lo[k] - eps_, hi = box.hi[k] + eps_, d = b[k] - a[k];
      if (d == 0.0) {
        if (a[k] < lo || a[k] > hi) return false;
        continue;
      }
      const double u = (lo - a[k]) / d, v = (hi - a[k]) / d;
      t0 = std::max(t0, std::min(u, v));
      t1 = std::min(t1, std::max(u, v));
      if (t0 > t1) return false;
    }
    return true;
  }
  const std::vector<Poly>& polys_;
  double eps_;
  BoxTree tree_;
};

// Parameters of the closest points p0 + s d0 and p1 + t d1 of two lines;
// false when they are (nearly) parallel.
bool line_params(const Vec3& p0, const Vec3& d0, const Vec3& p1, const Vec3& d1, double* s, double* t) {
  const Vec3 w = p0 - p1;
  const double a = glm::dot(d0, d0), b = glm::dot(d0, d1), c = glm::dot(d1, d1);
  const double d = glm::dot(d0, w), e = glm::dot(d1, w);
  const double den = a * c - b * b;
  if (!(den > 1e-14 * a * c)) return false;
  *s = (b * e - c * d) / den;
  *t = (a * e - b * d) / den;
  return true;
}

// A point on the receiver's plane and the generator it sees: whether it lies
// in the event's wedge, and whether the generator line is unblocked there.
struct Event {
  std::function<bool(const Vec3&)> in_wedge;
  std::function<bool(const Vec3&)> clear;
};

class ShadowCaster {
public:
  ShadowCaster(const Scene& scene, const std::vector<DiscontinuitySegment>& contacts, const ShadowOptions& opt,
               ShadowReport& rep)
      : scene_(scene), contacts_(contacts), opt_(opt), rep_(rep), polys_(make_polys(scene)),
        diag_(std::max(scene.diagonal(), std::numeric_limits<double>::min())), eps_(1e-9 * diag_),
        blockers_(polys_, eps_) {
    for (const Patch& patch : scene.patches) {
      loops_.push_back({patch.outer});
      loops_.back().insert(loops_.back().end(), patch.holes.begin(), patch.holes.end());
    }
    for (size_t p = 0; p < scene.patches.size(); ++p)
      for (const auto& loop : loops(static_cast<int>(p)))
        for (size_t i = 0; i < loop.size(); ++i) {
          const int a = loop[i], b = loop[(i + 1) % loop.size()];
          edge_patches_[{std::min(a, b), std::max(a, b)}].push_back(static_cast<int>(p));
          neighbours_[a].insert(b);
          neighbours_[b].insert(a);
        }
  }

  std::vector<DiscontinuitySegment> run() {
    const int np = static_cast<int>(polys_.size());
    std::vector<std::pair<double, int>> emitters;
    double strongest = 0.0;
    for (int p = 0; p < np; ++p) {
      const Rgb& e = scene_.material_of(p).emission;
      const double power = max3(e) * scene_.patch_area(p);
      if (power > 0.0) emitters.push_back({power, p});
      strongest = std::max(strongest, power);
    }
    std::stable_sort(emitters.begin(), emitters.end(), [](auto& x, auto& y) { return x.first > y.first; });
    rep_.emitters = static_cast<int>(emitters.size());
    found_.assign(static_cast<size_t>(np), {});
    for (const auto& [power, e] : emitters) {
      if (power < opt_.weak_emitter * strongest) {
        ++rep_.weak_emitters_skipped;
        continue;
      }
      for (int r = 0; r < np; ++r)
        if (r != e) pair(e, r);
    }
    return finish();
  }

private:
  // The outer loop and the holes of patch p (made once, in the constructor).
  const std::vector<std::vector<int>>& loops(int p) const { return loops_[static_cast<size_t>(p)]; }
  const Vec3& pos(int v) const { return scene_.vertices[static_cast<size_t>(v)]; }

  void pair(int e, int r) {
    const Poly& E = polys_[static_cast<size_t>(e)];
    const Poly& R = polys_[static_cast<size_t>(r)];
    ++rep_.pairs;
    bool r_front = false, e_front = false;
    for (const Vec3& q : R.loops[0]) r_front = r_front || E.dist(q) > eps_;
    for (const Vec3& q : E.loops[0]) e_front = e_front || R.dist(q) > eps_;
    if (!r_front || !e_front) {
      ++rep_.back_facing_pairs_skipped;
      return;
    }
    // Occluders: patches in the shaft between the emitter and the receiver
    // (their boxes overlap its box, no side of it has them all outside) with
    // a point in front of both. A patch outside the shaft meets no segment
    // from the receiver to the emitter, so it makes no event: the scan went
    // over every patch, and every patch in the shaft's box made events, which
    // made shadow lines quadratic in the patches.
    const std::vector<Side> sides = shaft_sides(E, R);
    Box3 box;
    box.add(Box3{E.lo, E.hi});
    box.add(Box3{R.lo, R.hi});
    std::vector<int> occluders;
    auto in_shaft = [&](const Box3& b) { return b.overlaps(box, eps_) && !box_outside(sides, b); };
    blockers_.tree().where(in_shaft, [&](int o) {
      if (o == e || o == r) return true;
      const Poly& O = polys_[static_cast<size_t>(o)];
      bool fe = false, fr = false;
      for (const Vec3& q : O.loops[0]) {
        fe = fe || E.dist(q) > eps_;
        fr = fr || R.dist(q) > eps_;
      }
      if (fe && fr && !outside(sides, O)) occluders.push_back(o);
      return true;
    });
    std::sort(occluders.begin(), occluders.end());  // in patch order, as the scan found them
    if (occluders.empty()) {
      ++rep_.no_occluder_pairs_skipped;
      return;
    }
    const EK::Plane_3 plane_r(to_exact(R.origin), EK::Vector_3(R.normal.x, R.normal.y, R.normal.z));
    std::set<std::array<int, 4>> seen;
    const auto& emitter_loops = loops(e);
    for (int o : occluders)
      for (const auto& loop : loops(o))
        for (size_t i = 0; i < loop.size(); ++i) {
          const int a = loop[i], b = loop[(i + 1) % loop.size()];
          for (const auto& eloop : emitter_loops)
            for (size_t k = 0; k < eloop.size(); ++k) {
              const int v = eloop[k], f1 = eloop[(k + 1) % eloop.size()];
              if (seen.insert({0, v, std::min(a, b), std::max(a, b)}).second)
                emitter_vertex_event(e, r, o, v, a, b, plane_r);
              if (seen.insert({1, a, std::min(v, f1), std::max(v, f1)}).second)
                occluder_vertex_event(e, r, o, a, v, f1, plane_r);
            }
        }
  }

  // A side of the shaft, the convex hull of the emitter's and the receiver's
  // outer loops: a plane through an edge of one and a corner of the other
  // with every corner of both on its inner side (dot(n, x) <= d + eps).
  // Sides through other corners are not looked for: fewer sides cull less,
  // never wrongly.
  struct Side {
    Vec3 n;
    double d;
  };
  static constexpr size_t kMostShaftPairs = 64;
  std::vector<Side> shaft_sides(const Poly& E, const Poly& R) const {
    std::vector<Side> sides;
    const std::vector<Vec3>& a = E.loops[0];
    const std::vector<Vec3>& b = R.loops[0];
    if (a.size() * b.size() > kMostShaftPairs) return sides;  // long loops: the box alone
    auto try_side = [&](const Vec3& p, const Vec3& q, const Vec3& c) {
      Vec3 n = glm::cross(q - p, c - p);
      const double len = glm::length(n);
      if (!(len > 1e-12 * glm::length(q - p) * glm::length(c - p))) return;
      n /= len;
      double d = glm::dot(n, p);
      bool above = false, below = false;
      for (const auto* loop : {&a, &b})
        for (const Vec3& x : *loop) {
          const double s = glm::dot(n, x) - d;
          above = above || s > eps_;
          below = below || s < -eps_;
        }
      if (above && below) return;
      if (above) {
        n = -n;
        d = -d;
      }
      sides.push_back({n, d});
    };
    for (const auto& [edges, corners] : {std::pair{&a, &b}, std::pair{&b, &a}})
      for (size_t i = 0; i < edges->size(); ++i)
        for (const Vec3& c : *corners) try_side((*edges)[i], (*edges)[(i + 1) % edges->size()], c);
    return sides;
  }
  // Is the whole box beyond eps outside one side of the shaft?
  bool box_outside(const std::vector<Side>& sides, const Box3& b) const {
    const Vec3 c = b.centre(), h = 0.5 * (b.hi - b.lo);
    for (const Side& s : sides)
      if (glm::dot(s.n, c) - glm::dot(glm::abs(s.n), h) - s.d > eps_) return true;
    return false;
  }
  // Is every corner of O beyond eps outside one side of the shaft?
  bool outside(const std::vector<Side>& sides, const Poly& O) const {
    for (const Side& s : sides) {
      bool all = true;
      for (const Vec3& x : O.loops[0]) all = all && glm::dot(s.n, x) - s.d > eps_;
      if (all) return true;
    }
    return false;
  }

  // Is some neighbour of vertex v (along any patch loop) within eps of the
  // plane through `p0` with unit normal n?
  bool edge_in_plane(int v, const Vec3& p0, const Vec3& n) const {
    auto it = neighbours_.find(v);
    if (it == neighbours_.end()) return false;
    for (int w : it->second)
      if (std::abs(glm::dot(pos(w) - p0, n)) <= eps_) return true;
    return false;
  }

  // EV: emitter vertex v, occluder edge (a, b).
  void emitter_vertex_event(int e, int r, int o, int v, int a, int b, const EK::Plane_3& plane_r) {
    const Poly& E = polys_[static_cast<size_t>(e)];
    const Poly& R = polys_[static_cast<size_t>(r)];
    const Vec3 V = pos(v), A = pos(a), B = pos(b);
    const double dv = R.dist(V), da = R.dist(A), db = R.dist(B);
    // V in front of the receiver; the edge partly between V and the receiver,
    // and partly in front of the emitter.
    if (dv <= eps_ || std::max(da, db) <= eps_ || std::min(da, db) >= dv - eps_) return;
    if (std::max(E.dist(A), E.dist(B)) <= eps_) return;
    Vec3 n = glm::cross(B - A, V - A);
    if (glm::length(n) <= 1e-12 * glm::length(B - A) * glm::length(V - A)) return;
    n = glm::normalize(n);
    // Silhouette: the faces at the edge must lie on one side of the plane.
    bool plus = false, minus = false;
    for (int q : edge_patches_.at({std::min(a, b), std::max(a, b)}))
      for (const Vec3& w : polys_[static_cast<size_t>(q)].loops[0]) {
        const double d = glm::dot(w - A, n);
        plus = plus || d > eps_;
        minus = minus || d < -eps_;
      }
    if (plus && minus) {
      ++rep_.non_silhouette_skipped;
      return;
    }
    const int kind = edge_in_plane(v, V, n) ? 1 : 2;
    Event ev;
    ev.in_wedge = [&, V, A, B](const Vec3& X) {
      double t, s;
      if (!line_params(X, V - X, A, B - A, &t, &s)) return false;
      return s > 1e-12 && s < 1.0 - 1e-12 && t > 1e-12 && t < 1.0 - 1e-12 && E.dist(X) > eps_;
    };
    ev.clear = [&, V, A, B](const Vec3& X) {
      double t, s;
      if (!line_params(X, V - X, A, B - A, &t, &s)) return false;
      const Vec3 G = X + t * (V - X), d = 1e-6 * (V - X);
      return !blockers_.blocked(X, G - d) && !blockers_.blocked(G + d, V);
    };
    const auto cuts = {EK::Line_3(to_exact(V), to_exact(A)), EK::Line_3(to_exact(V), to_exact(B))};
    cast(e, r, o, kind, VisualEvent::emitter_vertex, EK::Plane_3(to_exact(V), to_exact(A), to_exact(B)), plane_r,
         cuts, ev);
  }

  // VE: occluder vertex w, emitter edge (f0, f1).
  void occluder_vertex_event(int e, int r, int o, int w, int f0, int f1, const EK::Plane_3& plane_r) {
    const Poly& E = polys_[static_cast<size_t>(e)];
    const Poly& R = polys_[static_cast<size_t>(r)];
    const Vec3 W = pos(w), F0 = pos(f0), F1 = pos(f1);
    const double dw = R.dist(W);
    if (dw <= eps_ || E.dist(W) <= eps_ || std::max(R.dist(F0), R.dist(F1)) <= dw + eps_) return;
    Vec3 n = glm::cross(F1 - F0, W - F0);
    if (glm::length(n) <= 1e-12 * glm::length(F1 - F0) * glm::length(W - F0)) return;
    n = glm::normalize(n);
    const int kind = edge_in_plane(w, W, n) ? 1 : 2;
    Event ev;
    ev.in_wedge = [&, W, F0, F1](const Vec3& X) {
      double t, s;
      if (!line_params(X, W - X, F0, F1 - F0, &t, &s)) return false;
      return s > 1e-12 && s < 1.0 - 1e-12 && t > 1.0 + 1e-12;
    };
    ev.clear = [&, W, F0, F1](const Vec3& X) {
      double t, s;
      if (!line_params(X, W - X, F0, F1 - F0, &t, &s)) return false;
      const Vec3 Q = F0 + s * (F1 - F0), d = 1e-6 * (Q - X);
      return !blockers_.blocked(X, W - d) && !blockers_.blocked(W + d, Q);
    };
    const auto cuts = {EK::Line_3(to_exact(F0), to_exact(W)), EK::Line_3(to_exact(F1), to_exact(W))};
    cast(e, r, o, kind, VisualEvent::occluder_vertex, EK::Plane_3(to_exact(F0), to_exact(F1), to_exact(W)), plane_r,
         cuts, ev);
  }

  // Cuts the critical plane with the receiver's plane (exact), clips the line
  // to the receiver, splits it where the wedge's edge rays meet the receiver
  // (exact points), keeps the parts inside the wedge and, of those, the
  // pieces whose generator line is unblocked.
  void cast(int e, int r, int o, int kind, VisualEvent event, const EK::Plane_3& critical, const EK::Plane_3& plane_r,
            std::initializer_list<EK::Line_3> edge_rays, const Event& ev) {
    const Poly& R = polys_[static_cast<size_t>(r)];
    const auto hit = CGAL::intersection(critical, plane_r);
    if (!hit) return;
    const EK::Line_3* line = boost::get<EK::Line_3>(&*hit);
    if (!line) return;  // the critical plane is the receiver's plane
    const Vec3 centre = 0.5 * (R.lo + R.hi);
    const EK::Point_3 foot = line->projection(to_exact(centre));
    const EK::Vector_3 dir = line->to_vector();
    const Vec3 dir_d(CGAL::to_double(dir.x()), CGAL::to_double(dir.y()), CGAL::to_double(dir.z()));
    const double k = (glm::length(R.hi - R.lo) + 1.0 * eps_) / glm::length(dir_d);
    const Vec3 A = to_vec(foot - dir * k), B = to_vec(foot + dir * k);
    std::vector<Vec3> cut_points;
    for (const EK::Line_3& ray : edge_rays) {
      const auto x = CGAL::intersection(ray, plane_r);
      if (x)
        if (const EK::Point_3* p = boost::get<EK::Point_3>(&*x)) cut_points.push_back(to_vec(*p));
    }
    const double piece_len = diag_ / 64.0;
    for (const auto& piece : clip(R, A, B, eps_)) {
      const Vec3 c = piece.first, d = piece.second;  // not bindings: a lambda below captures c
      const Vec3 cd = d - c;
      const double len2 = glm::dot(cd, cd), len = std::sqrt(len2);
      std::vector<std::pair<double, Vec3>> ts = {{0.0, c}, {1.0, d}};
      for (const Vec3& q : cut_points) {
        const double t = glm::dot(q - c, cd) / len2;
        if (t * len > eps_ && (1.0 - t) * len > eps_) ts.push_back({t, q});
      }
      std::sort(ts.begin(), ts.end(), [](auto& x, auto& y) { return x.first < y.first; });
      for (size_t i = 0; i + 1 < ts.size(); ++i) {
        const double t0 = ts[i].first, t1 = ts[i + 1].first;
        if ((t1 - t0) * len <= eps_ || !ev.in_wedge(c + 0.5 * (t0 + t1) * cd)) continue;
        const int m = std::clamp(static_cast<int>(std::ceil((t1 - t0) * len / piece_len)), 1,
                                 std::max(1, opt_.visibility_pieces));
        int run = -1;  // first clear piece of the current run
        auto at = [&](int j) { return j == 0 ? ts[i].second : (j == m ? ts[i + 1].second : c + (t0 + (t1 - t0) * j / m) * cd); };
        for (int j = 0; j <= m; ++j) {
          const bool ok = j < m && ev.clear(c + (t0 + (t1 - t0) * (j + 0.5) / m) * cd);
          if (j < m && !ok) ++rep_.hidden_pieces_dropped;
          if (ok && run < 0) run = j;
          if (!ok && run >= 0) {
            DiscontinuitySegment seg;
            seg.patch = r;
            seg.other = o;
            seg.emitter = e;
            seg.kind = kind;
            seg.event = event;
            seg.a = at(run);
            seg.b = at(j);
            found_[static_cast<size_t>(r)].push_back(seg);
            run = -1;
          }
        }
      }
    }
  }

  // Per receiver: every point of a line keeps its lowest kind (contacts
  // first, then D1, then D2): a segment loses the parts that run along a
  // segment already kept. Then the budget.
  std::vector<DiscontinuitySegment> finish() {
    std::vector<KeptSegments> kept(found_.size());
    for (const DiscontinuitySegment& c : contacts_) kept[static_cast<size_t>(c.patch)].push_back(c);
    std::vector<DiscontinuitySegment> out;
    for (size_t r = 0; r < found_.size(); ++r) {
      auto& f = found_[r];
      std::stable_sort(f.begin(), f.end(), [](auto& x, auto& y) { return x.kind < y.kind; });
      int added = 0, over = 0;
      for (const DiscontinuitySegment& s : f) {
        for (const DiscontinuitySegment& piece : subtract(s, kept[r])) {
          if (near_duplicate(piece, kept[r])) {
            ++rep_.near_duplicates_dropped;
            continue;
          }
          if (added >= opt_.max_lines_per_receiver) {
            ++over;
            continue;
          }
          kept[r].push_back(piece);
          out.push_back(piece);
          ++added;
          ++(piece.kind == 1 ? rep_.d1 : rep_.d2);
        }
      }
      if (over > 0) {
        ++rep_.budget_receivers;
        rep_.lines_dropped_by_budget += over;
        const Patch& patch = scene_.patches[r];
        rep_.warnings.push_back(where(patch.file, patch.line) + "receiver '" + patch.name + "': " +
                                std::to_string(added + over) + " shadow lines, kept " + std::to_string(added) +
                                " (budget per receiver; raise it with --max-shadow-lines)");
      }
    }
    return out;
  }

  // The segments kept on one receiver, found by box in the order they were
  // kept: BoxTrees over blocks of them whose sizes at least double from the
  // newest block to the oldest (a new block swallows the smaller ones before
  // it), and a short list of the latest. So a query visits O(log n) trees,
  // and each segment joins O(log n) trees in all. A scan of all of them for
  // every new segment would be quadratic, and the floor under a large field
  // of boxes holds many thousands of contact segments and is offered more
  // shadow lines still.
  class KeptSegments {
  public:
    void push_back(const DiscontinuitySegment& s) {
      segs_.push_back(s);
      if (segs_.size() - covered_ < kTail) return;
      size_t begin = covered_;
      while (!blocks_.empty() && blocks_.back().end - blocks_.back().begin <= segs_.size() - begin) {
        begin = blocks_.back().begin;
        blocks_.pop_back();
      }
      std::vector<Box3> boxes;
      for (size_t i = begin; i < segs_.size(); ++i) boxes.push_back(box_of(segs_[i]));
      blocks_.push_back({begin, segs_.size(), BoxTree(boxes)});
      covered_ = segs_.size();
    }
    // Calls visit(k) for every kept k whose box overlaps s's grown by eps,
    // in the order they were kept, until visit returns false.
    template <class F>
    void near(const DiscontinuitySegment& s, double eps, F&& visit) const {
      const Box3 box = box_of(s);
      thread_local std::vector<size_t> hits;
      hits.clear();
      for (const Block& b : blocks_)
        b.tree.overlapping(box, eps, [&](int i) {
          hits.push_back(b.begin + static_cast<size_t>(i));
          return true;
        });
      for (size_t i = covered_; i < segs_.size(); ++i)
        if (box_of(segs_[i]).overlaps(box, eps)) hits.push_back(i);
      std::sort(hits.begin(), hits.end());
      for (size_t i : hits)
        if (!visit(segs_[i])) return;
    }

  private:
    static constexpr size_t kTail = 32;
    struct Block {
      size_t begin, end;
      BoxTree tree;
    };
    static Box3 box_of(const DiscontinuitySegment& s) {
      Box3 b;
      b.add(s.a);
      b.add(s.b);
      return b;
    }
    std::vector<DiscontinuitySegment> segs_;
    size_t covered_ = 0;  // segs_[0, covered_) are in blocks_
    std::vector<Block> blocks_;
  };

  // Is s within min_separation of one kept segment at both ends and its middle?
  bool near_duplicate(const DiscontinuitySegment& s, const KeptSegments& kept) const {
    const double tol = opt_.min_separation;
    if (!(tol > 0.0)) return false;
    auto dist = [](const Vec3& p, const DiscontinuitySegment& k) { return point_segment_distance(p, k.a, k.b); };
    const Vec3 mid = 0.5 * (s.a + s.b);
    bool found = false;
    kept.near(s, tol, [&](const DiscontinuitySegment& k) {
      found = dist(s.a, k) <= tol && dist(s.b, k) <= tol && dist(mid, k) <= tol;
      return !found;
    });
    return found;
  }

  // The parts of s not covered by collinear segments in `kept`.
  std::vector<DiscontinuitySegment> subtract(const DiscontinuitySegment& s, const KeptSegments& kept) const {
    const Vec3 ab = s.b - s.a;
    const double len2 = glm::dot(ab, ab), len = std::sqrt(len2);
    // Intervals of s still free, with their end points.
    std::vector<std::pair<std::pair<double, Vec3>, std::pair<double, Vec3>>> free = {{{0.0, s.a}, {1.0, s.b}}};
    auto off_line = [&](const Vec3& p) { return glm::length(glm::cross(p - s.a, ab)) / len > eps_; };
    kept.near(s, eps_, [&](const DiscontinuitySegment& k) {
      if (off_line(k.a) || off_line(k.b)) return true;
      std::pair<double, Vec3> c0 = {glm::dot(k.a - s.a, ab) / len2, k.a}, c1 = {glm::dot(k.b - s.a, ab) / len2, k.b};
      if (c0.first > c1.first) std::swap(c0, c1);
      decltype(free) next;
      for (const auto& [f0, f1] : free) {
        if (c1.first <= f0.first || c0.first >= f1.first) {
          next.push_back({f0, f1});
          continue;
        }
        if (c0.first > f0.first) next.push_back({f0, c0});
        if (c1.first < f1.first) next.push_back({c1, f1});
      }
      free = std::move(next);
      return true;
    });
    std::vector<DiscontinuitySegment> out;
    for (const auto& [f0, f1] : free) {
      if ((f1.first - f0.first) * len <= eps_) continue;
      DiscontinuitySegment piece = s;
      piece.a = f0.second;
      piece.b = f1.second;
      out.push_back(piece);
    }
    return out;
  }

  const Scene& scene_;
  const std::vector<DiscontinuitySegment>& contacts_;
  std::vector<std::vector<std::vector<int>>> loops_;  // per patch: outer loop, then holes
  ShadowOptions opt_;
  ShadowReport& rep_;
  std::vector<Poly> polys_;
  double diag_;
  double eps_;
  Blockers blockers_;
  std::map<std::pair<int, int>, std::vector<int>> edge_patches_;
  std::map<int, std::set<int>> neighbours_;
  std::vector<std::vector<DiscontinuitySegment>> found_;  // per receiver, before merging
};

}  // namespace

std::vector<DiscontinuitySegment> shadow_segments(const Scene& scene,
                                                  const std::vector<DiscontinuitySegment>& contacts,
                                                  const ShadowOptions& options, ShadowReport* report) {
  if (!(options.weak_emitter >= 0.0) || options.max_lines_per_receiver < 0 || options.visibility_pieces < 1)
    throw InputError("shadow options out of range: weak_emitter " + std::to_string(options.weak_emitter) +
                     ", max_lines_per_receiver " + std::to_string(options.max_lines_per_receiver) +
                     ", visibility_pieces " + std::to_string(options.visibility_pieces));
  ShadowReport rep;
  ShadowCaster caster(scene, contacts, options, rep);
  std::vector<DiscontinuitySegment> out = caster.run();
  if (report) *report = std::move(rep);
  return out;
}

}  // namespace radmesh
