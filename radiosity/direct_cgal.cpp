// Exact direct illumination: emitter polygon minus the occluders' shadows,
// with CGAL's exact 2-D Boolean operations. The only CGAL translation unit of
// the radiosity module.

#include "radiosity/direct.h"

#include "meshing/errors.h"
#include "radiosity/form_factor.h"

#include <CGAL/Boolean_set_operations_2.h>
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Polygon_2.h>
#include <CGAL/Polygon_set_2.h>
#include <CGAL/Polygon_with_holes_2.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace radmesh {

namespace {

using EK = CGAL::Exact_predicates_exact_constructions_kernel;
using Point3 = EK::Point_3;
using Polygon2 = CGAL::Polygon_2<EK>;
using PolygonWithHoles2 = CGAL::Polygon_with_holes_2<EK>;
using PolygonSet2 = CGAL::Polygon_set_2<EK>;

Point3 exact(const Vec3& p) { return Point3(p.x, p.y, p.z); }

struct Emitter {
  int patch = -1;
  Vec3 normal{0.0};
  EK::Plane_3 plane;             // oriented: the front (emitting) side is positive
  int drop = 0;                  // the coordinate dropped to map the plane to 2-D
  PolygonWithHoles2 shape;       // in the 2-D map
  std::array<Point3, 4> corners;  // the 2-D bounding box lifted back to the plane
  Vec3 lo{0.0}, hi{0.0};
  Rgb emission{0.0};

  EK::Point_2 to2(const Point3& p) const {
    if (drop == 0) return EK::Point_2(p.y(), p.z());
    if (drop == 1) return EK::Point_2(p.z(), p.x());
    return EK::Point_2(p.x(), p.y());
  }
  // The point of the plane above a 2-D point (exact).
  Point3 lift(const EK::Point_2& q) const {
    const EK::FT a = plane.a(), b = plane.b(), c = plane.c(), d = plane.d();
    if (drop == 0) return Point3(-(b * q.x() + c * q.y() + d) / a, q.x(), q.y());
    if (drop == 1) return Point3(q.y(), -(a * q.y() + c * q.x() + d) / b, q.x());
    return Point3(q.x(), q.y(), -(a * q.x() + b * q.y() + d) / c);
  }
};

struct OccluderTriangle {
  int patch;
  std::array<Point3, 3> v;
  Vec3 lo, hi;
};

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

struct DirectIllumination::Impl {
  const Scene& scene;
  std::vector<Emitter> emitters;
  std::vector<OccluderTriangle> occluders;
  explicit Impl(const Scene& s) : scene(s) {}

  double visible(const Vec3& x, const Vec3& n, int receiver, const Emitter& e, bool occlude) const {
    const Point3 X = exact(x);
    if (e.plane.oriented_side(X) != CGAL::ON_POSITIVE_SIDE) return 0.0;
    PolygonSet2 lit(e.shape);
    if (occlude) {
      // The pyramid from x over the emitter's box, and the slab between the
      // emitter plane and x's parallel plane.
      std::vector<EK::Plane_3> planes;
      const Point3 inside = CGAL::centroid(e.corners[0], e.corners[1], e.corners[2], e.corners[3]);
      for (int i = 0; i < 4; ++i) {
        EK::Plane_3 side(X, e.corners[static_cast<size_t>(i)], e.corners[static_cast<size_t>((i + 1) % 4)]);
        if (side.is_degenerate()) return 0.0;  // x in the emitter's plane
        if (side.oriented_side(inside) == CGAL::ON_NEGATIVE_SIDE) side = side.opposite();
        planes.push_back(side);
      }
      planes.push_back(e.plane);
      const EK::Plane_3 level(X, e.plane.orthogonal_vector());  // x's parallel plane; keep the emitter side
      planes.push_back(level.opposite());
      const Vec3 lo = glm::min(x, e.lo), hi = glm::max(x, e.hi);
      std::vector<Polygon2> shadows;
      for (const OccluderTriangle& t : occluders) {
        if (t.patch == receiver || t.patch == e.patch) continue;
        if (glm::any(glm::lessThan(hi, t.lo)) || glm::any(glm::lessThan(t.hi, lo))) continue;
        // Nothing strictly in front of the emitter: cannot occlude it.
        if (std::none_of(t.v.begin(), t.v.end(),
                         [&](const Point3& p) { return e.plane.oriented_side(p) == CGAL::ON_POSITIVE_SIDE; }))
          continue;
        std::vector<Point3> poly(t.v.begin(), t.v.end());
        for (const EK::Plane_3& pl : planes) {
          poly = clip(poly, pl);
          if (poly.size() < 3) break;
        }
        if (poly.size() < 3) continue;
        // A vertex on x's parallel plane is x itself (the pyramid's apex):
        // x lies on this occluder, which then hides nothing of measure.
        bool at_apex = false;
        for (const Point3& p : poly) at_apex = at_apex || level.has_on(p);
        if (at_apex) continue;
        Polygon2 shadow;
        for (const Point3& p : poly) {
          const auto hit = CGAL::intersection(EK::Line_3(X, p), e.plane);
          const Point3* q = hit ? boost::get<Point3>(&*hit) : nullptr;
          if (!q) {
            shadow.clear();
            break;
          }
          const EK::Point_2 q2 = e.to2(*q);
          if (shadow.is_empty() || shadow.vertices_end()[-1] != q2) shadow.push_back(q2);
        }
        while (shadow.size() > 1 && shadow.vertices_end()[-1] == shadow.vertices_begin()[0])
          shadow.erase(shadow.vertices_end() - 1);
        if (shadow.size() < 3 || shadow.area() == 0) continue;
        if (shadow.orientation() == CGAL::CLOCKWISE) shadow.reverse_orientation();
        if (!shadow.is_simple()) continue;  // cannot happen for a convex piece; be safe
        shadows.push_back(std::move(shadow));
      }
      if (!shadows.empty()) {
        PolygonSet2 dark;
        dark.join(shadows.begin(), shadows.end());
        lit.difference(dark);
      }
    }
    std::vector<PolygonWithHoles2> parts;
    lit.polygons_with_holes(std::back_inserter(parts));
    double sum = 0.0;
    auto loop3 = [&](const Polygon2& p) {
      std::vector<Vec3> out;
      for (auto v = p.vertices_begin(); v != p.vertices_end(); ++v) {
        const Point3 q = e.lift(*v);
        out.emplace_back(CGAL::to_double(q.x()), CGAL::to_double(q.y()), CGAL::to_double(q.z()));
      }
      return out;
    };
    for (const PolygonWithHoles2& part : parts) {
      const std::vector<Vec3> outer = loop3(part.outer_boundary());
      sum += lambert_contour_sum(x, n, outer.data(), outer.size());
      for (auto h = part.holes_begin(); h != part.holes_end(); ++h) {
        const std::vector<Vec3> hole = loop3(*h);
        sum += lambert_contour_sum(x, n, hole.data(), hole.size());
      }
    }
    return std::abs(sum) / (2.0 * std::numbers::pi);
  }
};

DirectIllumination::DirectIllumination(const Scene& scene) : impl_(std::make_unique<Impl>(scene)) {
  const Mesh coarse = triangulate_patches(scene);
  for (int t = 0; t < coarse.triangle_count(); ++t) {
    OccluderTriangle o;
    o.patch = coarse.patch[static_cast<size_t>(t)];
    const auto& tri = coarse.triangles[static_cast<size_t>(t)];
    o.lo = o.hi = coarse.positions[static_cast<size_t>(tri[0])];
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = coarse.positions[static_cast<size_t>(tri[static_cast<size_t>(k)])];
      o.v[static_cast<size_t>(k)] = exact(p);
      o.lo = glm::min(o.lo, p);
      o.hi = glm::max(o.hi, p);
    }
    impl_->occluders.push_back(o);
  }
  for (size_t p = 0; p < scene.patches.size(); ++p) {
    const Patch& patch = scene.patches[p];
    const Material& m = scene.material_of(patch);
    if (std::max({m.emission.x, m.emission.y, m.emission.z}) <= 0.0) continue;
    Emitter e;
    e.patch = static_cast<int>(p);
    e.normal = patch.normal;
    e.emission = m.emission;
    const std::vector<Vec3> outer = scene.loop_points(patch.outer);
    e.plane = EK::Plane_3(exact(outer[0]), EK::Vector_3(patch.normal.x, patch.normal.y, patch.normal.z));
    const Vec3 an = glm::abs(patch.normal);
    e.drop = an.x >= an.y && an.x >= an.z ? 0 : (an.y >= an.z ? 1 : 2);
    // Vertices are projected onto the (double) plane exactly, so the shape lies in it.
    auto polygon = [&](const std::vector<int>& loop) {
      Polygon2 poly;
      for (int v : loop) poly.push_back(e.to2(e.plane.projection(exact(scene.vertices[static_cast<size_t>(v)]))));
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
    for (int i = 0; i < 4; ++i) e.corners[static_cast<size_t>(i)] = e.lift(c2[i]);
    e.lo = e.hi = Vec3(CGAL::to_double(e.corners[0].x()), CGAL::to_double(e.corners[0].y()),
                       CGAL::to_double(e.corners[0].z()));
    for (const Point3& q : e.corners) {
      const Vec3 d(CGAL::to_double(q.x()), CGAL::to_double(q.y()), CGAL::to_double(q.z()));
      e.lo = glm::min(e.lo, d);
      e.hi = glm::max(e.hi, d);
    }
    impl_->emitters.push_back(std::move(e));
  }
}

DirectIllumination::~DirectIllumination() = default;

double DirectIllumination::visible_form_factor(const Vec3& x, const Vec3& n, int receiver, int emitter) const {
  for (const Emitter& e : impl_->emitters)
    if (e.patch == emitter) return impl_->visible(x, n, receiver, e, true);
  return 0.0;
}

double DirectIllumination::unoccluded_form_factor(const Vec3& x, const Vec3& n, int emitter) const {
  for (const Emitter& e : impl_->emitters)
    if (e.patch == emitter) return impl_->visible(x, n, -1, e, false);
  return 0.0;
}

Rgb DirectIllumination::reflected(const Vec3& x, int patch) const {
  const Patch& p = impl_->scene.patches[static_cast<size_t>(patch)];
  const Rgb rho = impl_->scene.material_of(p).reflectance;
  if (std::max({rho.x, rho.y, rho.z}) <= 0.0) return Rgb(0.0);
  Rgb sum(0.0);
  for (const Emitter& e : impl_->emitters)
    if (e.patch != patch) sum += e.emission * impl_->visible(x, p.normal, patch, e, true);
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
