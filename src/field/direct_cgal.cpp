// Exact direct illumination: emitter polygon minus the occluders' shadows.
// CGAL's exact kernel clips and projects where double precision would not
// do; the 2-D Boolean operations are Clipper's, exact in integers on a fine
// grid. The only CGAL translation unit of the radiosity module.

#include "radmesh/direct.h"

#include "core/box_tree.h"
#include "radmesh/errors.h"
#include "radmesh/form_factor.h"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Polygon_2.h>
#include <CGAL/Polygon_with_holes_2.h>

#include <polyclipping/clipper.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <unordered_map>

namespace radmesh {

namespace {

using EK = CGAL::Exact_predicates_exact_constructions_kernel;
using Point3 = EK::Point_3;
using Polygon2 = CGAL::Polygon_2<EK>;
using PolygonWithHoles2 = CGAL::Polygon_with_holes_2<EK>;

Point3 exact(const Vec3& p) { return Point3(p.x, p.y, p.z); }
Vec3 rounded(const Point3& p) { return Vec3(CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z())); }

struct Emitter {
  int patch = -1;
  Vec3 normal{0.0};
  EK::Plane_3 plane;             // oriented: the front (emitting) side is positive
  int drop = 0;                  // the coordinate dropped to map the plane to 2-D
  PolygonWithHoles2 shape;       // in the 2-D map
  std::array<Point3, 4> corners;  // the 2-D bounding box lifted back to the plane
  Vec3 lo{0.0}, hi{0.0};
  Rgb emission{0.0};
  std::vector<Vec3> base;               // the pyramid's base: the outline if convex (at most 16 corners), else `corners`
  Vec3 base_centre{0.0};
  std::vector<bool> in_front;            // per occluder: a corner strictly in front of the plane
  std::vector<std::vector<Vec3>> loops;  // outline, then holes (scene coordinates)
  Vec3 origin{0.0};                      // a point of the plane (double): n . y = n . origin
  int iu = 1, iv = 2;                    // the scene axes of the 2-D map's u and v
  double umin = 0.0, umax = 0.0, vmin = 0.0, vmax = 0.0;  // the padded box of the 2-D map
  // The integer grid of the Boolean operations: a 2-D point (u, v) is
  // ((u - cu) grid, (v - cv) grid) rounded, grid a power of two making the
  // padded box at most 2^51 units across (Clipper takes up to 2^62).
  double cu = 0.0, cv = 0.0, grid = 1.0;
  ClipperLib::Paths lit;  // the emitter on that grid: outline counter-clockwise, holes clockwise

  // A polygon of the 2-D map on the grid.
  ClipperLib::Path on_grid(const Polygon2& poly) const {
    ClipperLib::Path path;
    for (auto v = poly.vertices_begin(); v != poly.vertices_end(); ++v)
      path.push_back({static_cast<ClipperLib::cInt>(std::llround((CGAL::to_double(v->x()) - cu) * grid)),
                      static_cast<ClipperLib::cInt>(std::llround((CGAL::to_double(v->y()) - cv) * grid))});
    return path;
  }
  // The point of the plane (double) above the 2-D point (u, v).
  Vec3 on_plane(double u, double v) const {
    Vec3 y(0.0);
    y[iu] = u;
    y[iv] = v;
    y[drop] = origin[drop] + (normal[iu] * (origin[iu] - u) + normal[iv] * (origin[iv] - v)) / normal[drop];
    return y;
  }
  // A grid point lifted onto the plane.
  Vec3 on_plane(const ClipperLib::IntPoint& p) const {
    return on_plane(cu + static_cast<double>(p.X) / grid, cv + static_cast<double>(p.Y) / grid);
  }

  EK::Point_2 to2(const Point3& p) const {
    if (drop == 0) return EK::Point_2(p.y(), p.z());
    if (drop == 1) return EK::Point_2(p.z(), p.x());
    return EK::Point_2(p.x(), p.y());
  }
  // A loop of the 2-D map lifted back onto the plane, rounded to double.
  std::vector<Vec3> lifted(const Polygon2& poly) const;
  // The point of the plane above a 2-D point (exact).
  Point3 lift(const EK::Point_2& q) const {
    const EK::FT a = plane.a(), b = plane.b(), c = plane.c(), d = plane.d();
    if (drop == 0) return Point3(-(b * q.x() + c * q.y() + d) / a, q.x(), q.y());
    if (drop == 1) return Point3(q.y(), -(a * q.y() + c * q.x() + d) / b, q.x());
    return Point3(q.x(), q.y(), -(a * q.x() + b * q.y() + d) / c);
  }
};

std::vector<Vec3> Emitter::lifted(const Polygon2& poly) const {
  // In double from the rounded 2-D corners, the same whatever CGAL has
  // evaluated exactly before (the emitter is shared between threads).
  std::vector<Vec3> out;
  for (auto v = poly.vertices_begin(); v != poly.vertices_end(); ++v)
    out.push_back(on_plane(CGAL::to_double(v->x()), CGAL::to_double(v->y())));
  return out;
}

// A convex planar polygon that may cast a shadow: a whole patch where its
// outline is convex, without holes and exactly planar, else one triangle of
// it. One polygon per such patch gives half the shadows of its triangles and
// none of the coinciding diagonals that the exact union must resolve.
struct OccluderPolygon {
  int patch = -1;
  std::vector<Point3> v;
  std::vector<Vec3> d;  // the same corners in double
  Vec3 lo{0.0}, hi{0.0};
};

// Drops repeated corners (consecutive, and the last equal to the first);
// false when what is left encloses no area.
bool has_area(Polygon2& poly) {
  Polygon2 out;
  for (auto v = poly.vertices_begin(); v != poly.vertices_end(); ++v)
    if (out.is_empty() || out.vertices_end()[-1] != *v) out.push_back(*v);
  while (out.size() > 1 && out.vertices_end()[-1] == out.vertices_begin()[0]) out.erase(out.vertices_end() - 1);
  poly = std::move(out);
  return poly.size() >= 3 && poly.area() != 0;
}

// Sutherland-Hodgman in exact arithmetic: keeps the part on the positive side
// of `plane` (boundary included).
std::vector<Point3> clip(const std::vector<Point3>& poly, const EK::Plane_3& plane) {
  std::vector<Point3> out;
  const size_t m = poly.size();
  for (size_t i = 0; i < m; ++i) {
    const Point3& a = poly[i];
    const Point3& b = poly[(i + 1) % m];
    const auto sa = plane.oriented_side(a), sb = plane.oriented_side(b);
    if (sa != CGAL::ON_NEGATIVE_SIDE) out.push_back(a);
    if ((sa == CGAL::ON_POSITIVE_SIDE && sb == CGAL::ON_NEGATIVE_SIDE) ||
        (sa == CGAL::ON_NEGATIVE_SIDE && sb == CGAL::ON_POSITIVE_SIDE)) {
      const auto hit = CGAL::intersection(EK::Line_3(a, b), plane);
      if (hit)
        if (const Point3* p = boost::get<Point3>(&*hit)) out.push_back(*p);
    }
  }
  return out;
}

}  // namespace

// A patch whose outline is convex and has no holes, in double (for the
// test that one occluder hides a whole emitter); empty outline otherwise.
struct ConvexOccluder {
  std::vector<Vec3> outline;  // counter-clockwise around `normal`
  Vec3 normal{0.0};
};

struct DirectIllumination::Impl {
  const Scene& scene;
  std::vector<Emitter> emitters;
  std::vector<OccluderPolygon> occluders;  // in patch order
  BoxTree occluder_boxes;                  // their boxes (item t: occluders[t])
  std::vector<ConvexOccluder> convex;       // per patch
  // Per patch: where it is a face of a closed surface facing out (see
  // find_solids), the box of that surface; else empty.
  std::vector<Box3> solid_box;
  explicit Impl(const Scene& s) : scene(s) {}
  // Bounds on the shaft test's cost per vertex (see shaft and the emitters' base).
  static constexpr size_t kMostBaseCorners = 16;
  static constexpr double kMostAxisWork = 131072.0;  // a triangle in a 16-sided pyramid: 3 x 32 x 20 = 1,920

  // The closed surfaces facing out among the patches: a set of patches
  // joined by shared edges in which every edge is shared by exactly two of
  // them, once in each direction (a closed, consistently oriented surface),
  // enclosing a positive volume (its normals point out). A segment from a
  // point outside such a surface's box into the solid enters it through a
  // face turned towards the point, so from there the faces turned away hide
  // nothing more (a sphere's far side, a box's back faces), and the exact
  // clip need not union their shadows.
  void find_solids() {
    const size_t np = scene.patches.size();
    solid_box.assign(np, Box3{});
    auto key = [](int a, int b) { return (static_cast<uint64_t>(static_cast<uint32_t>(a)) << 32) | static_cast<uint32_t>(b); };
    std::unordered_map<uint64_t, int> directed;  // edge a -> b: how many patches have it
    std::unordered_map<uint64_t, int> owner;     // edge {a, b}: the first patch having it
    std::vector<int> parent(np);
    for (size_t p = 0; p < np; ++p) parent[p] = static_cast<int>(p);
    auto find = [&](int p) {
      while (parent[static_cast<size_t>(p)] != p) p = parent[static_cast<size_t>(p)] = parent[static_cast<size_t>(parent[static_cast<size_t>(p)])];
      return p;
    };
    auto edges = [&](size_t p, auto&& visit) {
      const Patch& patch = scene.patches[p];
      auto loop = [&](const std::vector<int>& l) {
        for (size_t i = 0; i < l.size(); ++i) visit(l[i], l[(i + 1) % l.size()]);
      };
      loop(patch.outer);
      for (const auto& h : patch.holes) loop(h);
    };
    for (size_t p = 0; p < np; ++p)
      edges(p, [&](int a, int b) {
        ++directed[key(a, b)];
        const auto [it, fresh] = owner.try_emplace(key(std::min(a, b), std::max(a, b)), static_cast<int>(p));
        if (!fresh) parent[static_cast<size_t>(find(static_cast<int>(p)))] = find(it->second);
      });
    std::vector<char> closed(np, 1);
    std::vector<double> volume(np, 0.0);
    std::vector<Box3> box(np);
    for (size_t p = 0; p < np; ++p) {
      const size_t r = static_cast<size_t>(find(static_cast<int>(p)));
      edges(p, [&](int a, int b) {
        const auto back = directed.find(key(b, a));
        if (directed[key(a, b)] != 1 || back == directed.end() || back->second != 1) closed[r] = 0;
        box[r].add(scene.vertices[static_cast<size_t>(a)]);
      });
      const Patch& patch = scene.patches[p];
      volume[r] += scene.patch_area(static_cast<int>(p)) *
                   glm::dot(patch.normal, scene.vertices[static_cast<size_t>(patch.outer[0])]) / 3.0;
    }
    for (size_t p = 0; p < np; ++p) {
      const size_t r = static_cast<size_t>(find(static_cast<int>(p)));
      if (closed[r] && volume[r] > 0.0) solid_box[p] = box[r];
    }
  }

  // The part of occluder t that lies in the pyramid from x over the
  // emitter's padded box and in the slab between the emitter's plane and
  // x's parallel plane, projected from x onto the emitter's 2-D map, in
  // exact arithmetic; empty when it hides nothing of measure.
  static Polygon2 exact_shadow(const OccluderPolygon& t, const Point3& X, const Emitter& e,
                               std::vector<EK::Plane_3>& planes) {
    if (planes.empty()) {
      const Point3 inside = CGAL::centroid(e.corners[0], e.corners[1], e.corners[2], e.corners[3]);
      for (int i = 0; i < 4; ++i) {
        EK::Plane_3 side(X, e.corners[static_cast<size_t>(i)], e.corners[static_cast<size_t>((i + 1) % 4)]);
        if (side.oriented_side(inside) == CGAL::ON_NEGATIVE_SIDE) side = side.opposite();
        planes.push_back(side);
      }
      planes.push_back(e.plane);
      planes.push_back(EK::Plane_3(X, e.plane.orthogonal_vector()).opposite());  // x's parallel plane
    }
    std::vector<Point3> poly = t.v;
    for (const EK::Plane_3& pl : planes) {
      poly = clip(poly, pl);
      if (poly.size() < 3) return {};
    }
    // A vertex on x's parallel plane is x itself (the pyramid's apex): x
    // lies on this occluder, which then hides nothing of measure.
    for (const Point3& p : poly)
      if (planes.back().has_on(p)) return {};
    Polygon2 shadow;
    for (const Point3& p : poly) {
      const auto hit = CGAL::intersection(EK::Line_3(X, p), e.plane);
      const Point3* q = hit ? boost::get<Point3>(&*hit) : nullptr;
      if (!q) return {};
      shadow.push_back(e.to2(*q));
    }
    return has_area(shadow) && shadow.is_simple() ? shadow : Polygon2{};
  }

  // The same shadow, computed in double where that is well conditioned:
  // the central projection from x onto the emitter's plane in homogeneous
  // coordinates, p -> (A, B, W) = (s (p - x)_u, s (p - x)_v, n . (x - p)),
  // with s = n . (x - origin) the height of x over the plane and image
  // (x_u + A / W, x_v + B / W). These are linear in p, so the pyramid and
  // the slab are half-planes in (A, B, W), and the polygon is clipped
  // there. Corners come out rounded to double: a corner two occluders share
  // (the edge between a box's faces) is computed alike for both, so CGAL
  // need not resolve their equality in exact arithmetic, which would make
  // the union slow. The exact path is taken where a clipped corner comes
  // within 1e-4 s of x's parallel plane (it is then near x, and the
  // division loses digits) or the rounded shadow is not simple.
  static Polygon2 shadow(const OccluderPolygon& t, const Vec3& x, const Point3& X, double s, const Emitter& e,
                         std::vector<EK::Plane_3>& planes) {
    // x in the occluder's plane: seen edge on, it hides nothing of measure.
    if (CGAL::orientation(t.v[0], t.v[1], t.v[2], X) == CGAL::COPLANAR && !CGAL::collinear(t.v[0], t.v[1], t.v[2]))
      return {};
    if (!(s > 0.0)) return exact_shadow(t, X, e, planes);  // x within rounding of the emitter's plane
    struct H {
      double a, b, w;
    };
    std::vector<H> poly, next;
    for (const Vec3& p : t.d) {
      const Vec3 d = p - x;
      poly.push_back({s * d[e.iu], s * d[e.iv], -glm::dot(e.normal, d)});
    }
    const double xu = x[e.iu], xv = x[e.iv];
    // The half-planes kept: x's side of its parallel plane, the emitter's
    // front, and the four sides of the box.
    auto keep = [&](int k, const H& h) {
      switch (k) {
        case 0: return h.w;
        case 1: return s - h.w;
        case 2: return h.a + (xu - e.umin) * h.w;
        case 3: return (e.umax - xu) * h.w - h.a;
        case 4: return h.b + (xv - e.vmin) * h.w;
        default: return (e.vmax - xv) * h.w - h.b;
      }
    };
    for (int k = 0; k < 6; ++k) {
      // Sutherland-Hodgman; an edge is cut from its end inside, so an edge
      // shared by two occluders is cut at the same point in both.
      next.clear();
      const size_t m = poly.size();
      for (size_t i = 0; i < m; ++i) {
        const H& a = poly[i];
        const H& b = poly[(i + 1) % m];
        const double ga = keep(k, a), gb = keep(k, b);
        if (ga >= 0.0) next.push_back(a);
        if ((ga > 0.0 && gb < 0.0) || (ga < 0.0 && gb > 0.0)) {
          const H& in = ga > 0.0 ? a : b;
          const H& out = ga > 0.0 ? b : a;
          const double gi = std::max(ga, gb), go = std::min(ga, gb);
          const double u = gi / (gi - go);
          next.push_back({in.a + u * (out.a - in.a), in.b + u * (out.b - in.b), in.w + u * (out.w - in.w)});
        }
      }
      poly.swap(next);
      if (poly.size() < 3) return {};
    }
    Polygon2 out;
    for (const H& h : poly) {
      if (!(h.w >= 1e-4 * s)) return exact_shadow(t, X, e, planes);
      out.push_back(EK::Point_2(xu + h.a / h.w, xv + h.b / h.w));
    }
    if (!has_area(out)) return {};  // seen edge on: a sliver as thin as the rounding
    if (!out.is_simple()) return exact_shadow(t, X, e, planes);
    return out;
  }

  // The exact visible part; `candidates` (indices into `occluders`) are the
  // occluders that may hide some of it, null for none.
  double visible(const Vec3& x, const Vec3& n, int receiver, const Emitter& e,
                 const std::vector<int>* candidates) const {
    const Point3 X = exact(x);
    if (e.plane.oriented_side(X) != CGAL::ON_POSITIVE_SIDE) return 0.0;
    std::vector<Polygon2> shadows;
    if (candidates) {
      const double s = glm::dot(e.normal, x - e.origin);
      std::vector<EK::Plane_3> planes;  // the exact path's pyramid and slab, made when first needed
      const Vec3 lo = glm::min(x, e.lo), hi = glm::max(x, e.hi);
      for (const int index : *candidates) {
        const OccluderPolygon& t = occluders[static_cast<size_t>(index)];
        if (t.patch == receiver || t.patch == e.patch) continue;
        if (glm::any(glm::lessThan(hi, t.lo)) || glm::any(glm::lessThan(t.hi, lo))) continue;
        // Nothing strictly in front of the emitter: cannot occlude it.
        if (std::none_of(t.v.begin(), t.v.end(),
                         [&](const Point3& p) { return e.plane.oriented_side(p) == CGAL::ON_POSITIVE_SIDE; }))
          continue;
        Polygon2 dark = shadow(t, x, X, s, e, planes);
        if (!dark.is_empty()) shadows.push_back(std::move(dark));
      }
    }
    if (shadows.empty()) return unoccluded(x, n, e);
    // The emitter minus the union of the shadows, on the grid (nonzero
    // winding: every shadow made counter-clockwise). Integer arithmetic
    // decides every crossing alike whichever shadows share an edge; the
    // corners are rounded to the grid (by at most 2^-51 of the emitter's
    // padded box), about the double rounding they had already. CGAL's exact
    // Boolean operations (Polygon_set_2, Epeck) give the same values and
    // cost many times more (docs/decisions.md).
    ClipperLib::Clipper clipper;
    clipper.AddPaths(e.lit, ClipperLib::ptSubject, true);
    for (const Polygon2& dark : shadows) {
      ClipperLib::Path path = e.on_grid(dark);
      if (!ClipperLib::Orientation(path)) ClipperLib::ReversePath(path);
      clipper.AddPath(path, ClipperLib::ptClip, true);  // false (ignored) for a shadow that snapped to no area
    }
    ClipperLib::Paths lit;
    clipper.Execute(ClipperLib::ctDifference, lit, ClipperLib::pftNonZero, ClipperLib::pftNonZero);
    double sum = 0.0;
    std::vector<Vec3> loop;
    for (const ClipperLib::Path& p : lit) {
      loop.clear();
      for (const ClipperLib::IntPoint& q : p) loop.push_back(e.on_plane(q));
      sum += lambert_contour_sum(x, n, loop.data(), loop.size());
    }
    return std::abs(sum) / (2.0 * std::numbers::pi);
  }

  // The cheap test: which occluders in front of the emitter may meet the pyramid from x
  // over the emitter's (padded) box, within the slab between the emitter and
  // x. A triangle is cleared when all its corners lie outside one of the
  // pyramid's planes by a margin (1e-9 of the pyramid's size) far above the
  // rounding of these double-precision tests, so a cleared triangle surely
  // hides nothing; the others go to the exact clip. Returns true when one of
  // the others passes within the margin of x (x lies on another surface,
  // where the light depends on the side it is approached from).
  void shaft(const Vec3& x, int receiver, const Emitter& e, std::vector<int>& out) const {
    out.clear();
    const double margin = 1e-9 * (glm::length(x - e.base_centre) + glm::length(e.hi - e.lo));
    // The pyramid: apex x over the emitter's convex base.
    const size_t nb = e.base.size();
    std::vector<Vec3> hull;
    hull.reserve(nb + 1);
    hull.push_back(x);
    hull.insert(hull.end(), e.base.begin(), e.base.end());
    std::vector<Vec3> hull_edges;
    hull_edges.reserve(2 * nb);
    for (size_t i = 0; i < nb; ++i) {
      hull_edges.push_back(e.base[i] - x);
      hull_edges.push_back(e.base[(i + 1) % nb] - e.base[i]);
    }
    // Separating-axis test of a triangle and the pyramid, both convex:
    // clear when their projections on some axis overlap by no more than the
    // margin (a triangle that only touches the pyramid, as a wall meeting
    // the emitter's edge does, hides nothing). Axes: the pyramid's faces,
    // the triangle's plane, and the cross products of their edges.
    // The pyramid's extent along an axis, and that axis's length.
    struct Extent {
      Vec3 axis{0.0};
      double lo = INFINITY, hi = -INFINITY, len = 0.0;
    };
    auto extent = [&](const Vec3& axis) {
      Extent h;
      h.axis = axis;
      h.len = glm::length(axis);
      for (const Vec3& p : hull) {
        const double d = glm::dot(p, axis);
        h.lo = std::min(h.lo, d);
        h.hi = std::max(h.hi, d);
      }
      return h;
    };
    // The pyramid's faces (its sides, then the emitter's plane): the axes
    // every occluder is tested on first, and what the box tree prunes by.
    thread_local std::vector<Extent> faces;
    faces.clear();
    for (size_t i = 0; i < nb; ++i) faces.push_back(extent(glm::cross(hull_edges[2 * i], hull_edges[2 * ((i + 1) % nb)])));
    faces.push_back(extent(e.normal));
    // Separating-axis test of a triangle and the pyramid, both convex:
    // clear when their projections on some axis overlap by no more than the
    // margin (a triangle that only touches the pyramid, as a wall meeting
    // the emitter's edge does, hides nothing). Axes: the pyramid's faces,
    // the triangle's plane, and the cross products of their edges.
    auto apart = [&](const std::vector<Vec3>& t, const Extent& h) {
      if (!(h.len > 1e-300)) return false;
      double tlo = INFINITY, thi = -INFINITY;
      for (const Vec3& p : t) {
        const double d = glm::dot(p, h.axis);
        tlo = std::min(tlo, d);
        thi = std::max(thi, d);
      }
      return h.hi <= tlo + margin * h.len || thi <= h.lo + margin * h.len;
    };
    std::vector<Vec3> te;
    auto separated = [&](const std::vector<Vec3>& t) {
      for (const Extent& f : faces)
        if (apart(t, f)) return true;
      te.clear();
      for (size_t i = 0; i < t.size(); ++i) te.push_back(t[(i + 1) % t.size()] - t[i]);
      if (apart(t, extent(glm::cross(te[0], te[1])))) return true;
      // The edge pairs' axes cost (pyramid edges) x (occluder edges) x
      // (their points): past kMostAxisWork (an occluder of 256 corners in a
      // wide pyramid: 67 M steps a vertex) the occluder goes to the exact
      // clip, which finds what it hides (or nothing) all the same.
      if (static_cast<double>(hull_edges.size()) * static_cast<double>(te.size()) *
              static_cast<double>(hull.size() + t.size()) >
          kMostAxisWork)
        return false;
      for (const Vec3& he : hull_edges)
        for (const Vec3& edge : te)
          if (apart(t, extent(glm::cross(he, edge)))) return true;
      return false;
    };
    // The occluders whose boxes meet the pyramid's box, by the box tree
    // (not a pass over all of them: this runs per vertex and emitter), in
    // the order of their numbers. A subtree whose box lies beyond one of
    // the pyramid's faces (its corners' projections on the face's normal
    // all at or past the pyramid's) is skipped: every occluder in it would
    // be separated on that axis.
    Box3 point_box;
    point_box.add(x);
    Box3 query;
    query.add(glm::min(x, e.lo) - Vec3(margin));
    query.add(glm::max(x, e.hi) + Vec3(margin));
    auto beyond = [&](const Box3& b) {
      for (const Extent& f : faces) {
        // The box's extent on the axis: its centre's projection +- the
        // half-extents' projection on |axis|.
        const double c = glm::dot(b.centre(), f.axis), r = glm::dot(0.5 * (b.hi - b.lo), glm::abs(f.axis));
        if (c - r >= f.hi || c + r <= f.lo) return true;
      }
      return false;
    };
    thread_local std::vector<int> met;
    met.clear();
    occluder_boxes.where([&](const Box3& b) { return b.overlaps(query, 0.0) && !beyond(b); },
                         [&](int t) {
                           if (e.in_front[static_cast<size_t>(t)]) met.push_back(t);
                           return true;
                         });
    std::sort(met.begin(), met.end());
    for (const int index : met) {
      const OccluderPolygon& t = occluders[static_cast<size_t>(index)];
      if (t.patch == receiver || t.patch == e.patch) continue;
      // A face of a closed solid turned away from x, x outside the
      // solid's box: its shadow lies in those of the faces turned to x.
      const Box3& solid = solid_box[static_cast<size_t>(t.patch)];
      if (!solid.empty() && !solid.overlaps(point_box, margin) &&
          glm::dot(x - t.d[0], scene.patches[static_cast<size_t>(t.patch)].normal) < -margin)
        continue;
      if (!separated(t.d)) out.push_back(index);
    }
  }

  // True when one convex occluder patch among the candidates' patches hides
  // the whole emitter from x: the segment from x to every corner of the
  // emitter's outline (or of its base) crosses the occluder's plane inside
  // its outline (by the margin). Then it hides their convex hull, and so the
  // emitter.
  bool hidden_by_one(const Vec3& x, const Emitter& e, const std::vector<int>& candidates) const {
    const double margin = 1e-9 * (glm::length(x - e.base_centre) + glm::length(e.hi - e.lo));
    int last = -1;
    for (const int index : candidates) {
      const int patch = occluders[static_cast<size_t>(index)].patch;
      if (patch == last) continue;
      last = patch;
      const ConvexOccluder& c = convex[static_cast<size_t>(patch)];
      if (c.outline.empty()) continue;
      const double sx = glm::dot(x - c.outline[0], c.normal);
      bool all = true;
      // The emitter's corners, or past kMostBaseCorners its base (its box,
      // which holds it): each corner costs a pass over the occluder's
      // outline, and a round lamp over a round table of 1,024 corners each
      // would take 1 M steps a vertex.
      for (const Vec3& v : e.loops[0].size() <= kMostBaseCorners ? e.loops[0] : e.base) {
        const double sv = glm::dot(v - c.outline[0], c.normal);
        if (!((sx > margin && sv < -margin) || (sx < -margin && sv > margin))) {
          all = false;
          break;
        }
        const Vec3 q = x + (sx / (sx - sv)) * (v - x);
        for (size_t i = 0; i < c.outline.size() && all; ++i) {
          const Vec3& a = c.outline[i];
          const Vec3& b = c.outline[(i + 1) % c.outline.size()];
          all = glm::dot(glm::cross(b - a, q - a), c.normal) > margin * glm::length(b - a);
        }
        if (!all) break;
      }
      if (all) return true;
    }
    return false;
  }

  // Lambert's formula for the whole emitter (its loops as the exact path
  // would hand them over when nothing is in the way).
  static double unoccluded(const Vec3& x, const Vec3& n, const Emitter& e) {
    double sum = 0.0;
    for (const std::vector<Vec3>& loop : e.loops) sum += lambert_contour_sum(x, n, loop.data(), loop.size());
    return std::abs(sum) / (2.0 * std::numbers::pi);
  }

  // The visible form factor by the cheapest exact path: 0 behind the
  // emitter or facing away from it, Lambert's formula when the shaft is clear, 0 when one convex
  // occluder hides it all, the exact clip of the triangles that may be in
  // it otherwise.
  double fast_visible(const Vec3& x, const Vec3& n, int receiver, const Emitter& e, DirectCounts& counts,
                      std::vector<int>& scratch) const {
    // Behind the emitter, or the emitter's outline wholly behind x's tangent
    // plane (a surface facing away from the light): nothing to see.
    const bool faces_away =
        std::none_of(e.loops[0].begin(), e.loops[0].end(), [&](const Vec3& v) { return glm::dot(n, v - x) > 0.0; });
    if (faces_away || e.plane.oriented_side(exact(x)) != CGAL::ON_POSITIVE_SIDE) {
      ++counts.behind;
      return 0.0;
    }
    shaft(x, receiver, e, scratch);
    if (scratch.empty()) {
      ++counts.unoccluded;
      return unoccluded(x, n, e);
    }
    if (hidden_by_one(x, e, scratch)) {
      ++counts.hidden;
      return 0.0;
    }
    ++counts.clipped;
    const double f = visible(x, n, receiver, e, &scratch);
    if (f == 0.0) ++counts.dark;
    return f;
  }

  // The constructor's parts, in its order: the convex outlines, the
  // occluders (after find_solids) and each emitter.
  void find_convex_outlines();
  void add_occluders();
  Emitter make_emitter(size_t p) const;
};

// Per patch without holes whose outline turns one way at every corner
// (counter-clockwise around its normal), that outline (ConvexOccluder).
void DirectIllumination::Impl::find_convex_outlines() {
  convex.resize(scene.patches.size());
  for (size_t p = 0; p < scene.patches.size(); ++p) {
    const Patch& patch = scene.patches[p];
    if (!patch.holes.empty()) continue;
    std::vector<Vec3> outline = scene.loop_points(patch.outer);
    double turn = 0.0;
    bool is_convex = outline.size() >= 3;
    for (size_t i = 0; i < outline.size() && is_convex; ++i) {
      const Vec3& a = outline[i];
      const Vec3& b = outline[(i + 1) % outline.size()];
      const Vec3& c = outline[(i + 2) % outline.size()];
      const double z = glm::dot(glm::cross(b - a, c - b), patch.normal);
      is_convex = z >= 0.0;
      turn += z;
    }
    if (is_convex && turn > 0.0) convex[p] = {std::move(outline), patch.normal};
  }
}

// The occluders, in patch order: a patch whose outline is convex is one
// (see `whole` below), any other patch its triangles; and a box tree over
// them.
void DirectIllumination::Impl::add_occluders() {
  auto add = [&](int patch, const std::vector<Vec3>& corners) {
    OccluderPolygon o;
    o.patch = patch;
    o.d = corners;
    o.lo = o.hi = corners[0];
    for (const Vec3& c : corners) {
      o.v.push_back(exact(c));
      o.lo = glm::min(o.lo, c);
      o.hi = glm::max(o.hi, c);
    }
    occluders.push_back(std::move(o));
  };
  // A convex outline strictly convex at every corner and exactly planar
  // (checked in exact arithmetic) is one occluder; any other patch is its
  // triangles.
  auto whole = [](const std::vector<Vec3>& outline) {
    if (outline.size() <= 3) return outline.size() == 3;
    std::vector<Point3> q;
    for (const Vec3& v : outline) q.push_back(exact(v));
    for (size_t i = 0; i < q.size(); ++i)
      if (CGAL::collinear(q[i], q[(i + 1) % q.size()], q[(i + 2) % q.size()])) return false;
    for (size_t i = 3; i < q.size(); ++i)
      if (!CGAL::coplanar(q[0], q[1], q[2], q[i])) return false;
    return true;
  };
  std::vector<char> one(scene.patches.size(), 0), added(scene.patches.size(), 0);
  for (size_t p = 0; p < scene.patches.size(); ++p) one[p] = whole(convex[p].outline);
  const Mesh coarse = triangulate_patches(scene);
  for (int t = 0; t < coarse.triangle_count(); ++t) {
    const size_t p = static_cast<size_t>(coarse.patch[static_cast<size_t>(t)]);
    if (one[p]) {
      if (!added[p]) add(static_cast<int>(p), convex[p].outline);
      added[p] = 1;
      continue;
    }
    const auto& tri = coarse.triangles[static_cast<size_t>(t)];
    add(static_cast<int>(p), {coarse.positions[static_cast<size_t>(tri[0])], coarse.positions[static_cast<size_t>(tri[1])],
            coarse.positions[static_cast<size_t>(tri[2])]});
  }
  {
    std::vector<Box3> boxes(occluders.size());
    for (size_t t = 0; t < boxes.size(); ++t) {
      boxes[t].add(occluders[t].lo);
      boxes[t].add(occluders[t].hi);
    }
    occluder_boxes = BoxTree(boxes);
  }
}

// The emitter of patch p: its plane and 2-D map, its outline and holes as
// polygons (plain numbers, and on the clip's integer grid), the base of its
// shaft's pyramid and which occluders have a corner in front of it.
Emitter DirectIllumination::Impl::make_emitter(size_t p) const {
  const Patch& patch = scene.patches[p];
  const Material& m = scene.material_of(patch);
  Emitter e;
  e.patch = static_cast<int>(p);
  e.normal = patch.normal;
  e.emission = m.emission;
  const std::vector<Vec3> outer = scene.loop_points(patch.outer);
  e.plane = EK::Plane_3(exact(outer[0]), EK::Vector_3(patch.normal.x, patch.normal.y, patch.normal.z));
  e.origin = outer[0];
  const Vec3 an = glm::abs(patch.normal);
  e.drop = an.x >= an.y && an.x >= an.z ? 0 : (an.y >= an.z ? 1 : 2);
  e.iu = (e.drop + 1) % 3;
  e.iv = (e.drop + 2) % 3;
  // Vertices are projected onto the (double) plane, then rounded: the 2-D
  // map's corners are plain numbers, shared by every thread.
  auto polygon = [&](const std::vector<int>& loop) {
    Polygon2 poly;
    for (int v : loop) {
      const EK::Point_2 q = e.to2(e.plane.projection(exact(scene.vertices[static_cast<size_t>(v)])));
      poly.push_back(EK::Point_2(CGAL::to_double(q.x()), CGAL::to_double(q.y())));
    }
    if (poly.orientation() == CGAL::CLOCKWISE) poly.reverse_orientation();
    return poly;
  };
  Polygon2 outer2 = polygon(patch.outer);
  if (!outer2.is_simple()) throw GeometryError(where(patch.file, patch.line) + "emitter '" + patch.name + "' is not a simple polygon");
  std::vector<Polygon2> holes;
  for (const auto& h : patch.holes) {
    Polygon2 hp = polygon(h);
    hp.reverse_orientation();
    holes.push_back(hp);
  }
  e.shape = PolygonWithHoles2(outer2, holes.begin(), holes.end());
  const CGAL::Bbox_2 box = outer2.bbox();
  // A box a little larger than the emitter (the pyramid only bounds the clip).
  const double pad = 1e-3 * std::max(box.xmax() - box.xmin(), box.ymax() - box.ymin());
  const EK::Point_2 c2[4] = {{box.xmin() - pad, box.ymin() - pad},
                             {box.xmax() + pad, box.ymin() - pad},
                             {box.xmax() + pad, box.ymax() + pad},
                             {box.xmin() - pad, box.ymax() + pad}};
  e.umin = box.xmin() - pad;
  e.umax = box.xmax() + pad;
  e.vmin = box.ymin() - pad;
  e.vmax = box.ymax() + pad;
  e.cu = 0.5 * (e.umin + e.umax);
  e.cv = 0.5 * (e.vmin + e.vmax);
  e.grid = std::ldexp(1.0, 51 - std::ilogb(std::max(e.umax - e.umin, e.vmax - e.vmin)) - 1);
  if (!std::isfinite(e.grid) || !(e.grid > 0.0))
    throw GeometryError(where(patch.file, patch.line) + "emitter '" + patch.name + "' is too small (" +
                        format_number(e.umax - e.umin) + " across) for the exact direct light");
  e.lit.push_back(e.on_grid(outer2));  // counter-clockwise (made so above)
  for (const Polygon2& h : holes) e.lit.push_back(e.on_grid(h));  // clockwise
  for (int i = 0; i < 4; ++i) e.corners[static_cast<size_t>(i)] = e.lift(c2[i]);
  // Evaluated exactly now, while one thread holds them: CGAL tightens an
  // object's interval when it first evaluates it exactly, so a shared
  // object evaluated later, by whichever thread first needs it, could
  // round differently from one run to the next.
  CGAL::exact(e.plane);
  for (const Point3& q : e.corners) CGAL::exact(q);
  for (const Point3& q : e.corners) e.base.push_back(rounded(q));
  e.lo = e.hi = e.base[0];
  for (const Vec3& d : e.base) {
    e.lo = glm::min(e.lo, d);
    e.hi = glm::max(e.hi, d);
  }
  e.loops.push_back(e.lifted(e.shape.outer_boundary()));
  for (auto h = e.shape.holes_begin(); h != e.shape.holes_end(); ++h) e.loops.push_back(e.lifted(*h));
  // The pyramid's base: a convex emitter's own outline, unless it has many
  // corners (a round lamp of 256): every vertex's shaft test costs a pass
  // over the base's corners per corner, and the box's pyramid only clears
  // a little less.
  if (patch.holes.empty() && e.loops[0].size() <= kMostBaseCorners && e.shape.outer_boundary().is_convex())
    e.base = e.loops[0];
  for (const Vec3& b : e.base) e.base_centre += b / static_cast<double>(e.base.size());
  e.in_front.resize(occluders.size());
  for (size_t t = 0; t < occluders.size(); ++t) {
    const OccluderPolygon& o = occluders[t];
    e.in_front[t] = std::any_of(o.v.begin(), o.v.end(),
                                [&](const Point3& p) { return e.plane.oriented_side(p) == CGAL::ON_POSITIVE_SIDE; });
  }
  return e;
}

DirectIllumination::DirectIllumination(const Scene& scene) : impl_(std::make_unique<Impl>(scene)) {
  impl_->find_convex_outlines();
  impl_->find_solids();
  impl_->add_occluders();
  for (size_t p = 0; p < scene.patches.size(); ++p) {
    const Material& m = scene.material_of(scene.patches[p]);
    if (max3(m.emission) <= 0.0) continue;
    impl_->emitters.push_back(impl_->make_emitter(p));
  }
}

DirectIllumination::~DirectIllumination() = default;

double DirectIllumination::visible_form_factor(const Vec3& x, const Vec3& n, int receiver, int emitter) const {
  std::vector<int> all(impl_->occluders.size());
  for (size_t t = 0; t < all.size(); ++t) all[t] = static_cast<int>(t);
  for (const Emitter& e : impl_->emitters)
    if (e.patch == emitter) return impl_->visible(x, n, receiver, e, &all);
  return 0.0;
}

double DirectIllumination::unoccluded_form_factor(const Vec3& x, const Vec3& n, int emitter) const {
  for (const Emitter& e : impl_->emitters)
    if (e.patch == emitter) return impl_->visible(x, n, -1, e, nullptr);
  return 0.0;
}

Rgb DirectIllumination::reflected(const Vec3& x, int patch, DirectCounts* counts) const {
  const Patch& p = impl_->scene.patches[static_cast<size_t>(patch)];
  const Rgb rho = impl_->scene.material_of(p).reflectance;
  if (max3(rho) <= 0.0) return Rgb(0.0);
  DirectCounts local;
  std::vector<int> scratch;
  Rgb sum(0.0);
  for (const Emitter& e : impl_->emitters)
    if (e.patch != patch) sum += e.emission * impl_->fast_visible(x, p.normal, patch, e, local, scratch);
  if (counts) *counts += local;
  return rho * sum;
}

std::vector<std::array<Rgb, 3>> direct_corner_values(const DirectIllumination& direct, const Mesh& mesh) {
  std::vector<std::array<Rgb, 3>> out(static_cast<size_t>(mesh.triangle_count()));
  tbb::parallel_for(0, mesh.triangle_count(), [&](int t) {
    const auto& tri = mesh.triangles[static_cast<size_t>(t)];
    const Vec3 c = mesh.centroid(t);
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = mesh.positions[static_cast<size_t>(tri[static_cast<size_t>(k)])];
      out[static_cast<size_t>(t)][static_cast<size_t>(k)] =
          direct.reflected(p + 1e-7 * (c - p), mesh.patch[static_cast<size_t>(t)]);
    }
  });
  return out;
}

NodalField direct_field(const DirectIllumination& direct, const Mesh& mesh) {
  const auto corners = direct_corner_values(direct, mesh);
  NodalField f;
  for (int t = 0; t < mesh.triangle_count(); ++t) {
    std::array<int, 3> c{};
    for (int k = 0; k < 3; ++k) {
      const int v = mesh.triangles[static_cast<size_t>(t)][static_cast<size_t>(k)];
      c[static_cast<size_t>(k)] = static_cast<int>(f.points.size());
      f.points.push_back(mesh.positions[static_cast<size_t>(v)]);
      f.source_vertex.push_back(v);
      f.radiosity.push_back(corners[static_cast<size_t>(t)][static_cast<size_t>(k)]);
    }
    f.corners.push_back(c);
  }
  return f;
}

}  // namespace radmesh
