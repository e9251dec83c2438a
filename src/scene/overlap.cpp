// Faces that lie in one plane facing the same way: cut out of the face they
// lie in, or refused where they overlap otherwise (see overlap.h).

#include "core/box_tree.h"
#include "radmesh/errors.h"
#include "scene/overlap.h"

#include <algorithm>
#include <array>
#include <climits>
#include <cstdint>
#include <cmath>
#include <numeric>
#include <string>

namespace radmesh {

namespace {

using Point2 = std::array<double, 2>;
using Polygon2 = std::vector<Point2>;  // counter-clockwise

// Outlines with more vertices than this are tested through their triangles
// (the separating-axis test costs (n + m)^2).
constexpr size_t kMaxDirectVertices = 32;

double cross2(const Point2& o, const Point2& a, const Point2& b) {
  return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

bool convex(const Polygon2& poly) {
  for (size_t i = 0; i < poly.size(); ++i)
    if (cross2(poly[i], poly[(i + 1) % poly.size()], poly[(i + 2) % poly.size()]) < 0.0) return false;
  return true;
}

// Whether two convex polygons of one plane reach into each other by more
// than tol: along every edge normal of either (their separating axes) the
// projections overlap by more than tol. Polygons that touch or are apart
// have an axis where they overlap by at most tol; most pairs stop at the
// first few axes.
bool overlap_more_than(const Polygon2& a, const Polygon2& b, double tol) {
  for (const Polygon2* t : {&a, &b})
    for (size_t e = 0; e < t->size(); ++e) {
      const Point2& p = (*t)[e];
      const Point2& q = (*t)[(e + 1) % t->size()];
      const double nx = q[1] - p[1], ny = p[0] - q[0];
      double alo = INFINITY, ahi = -INFINITY, blo = INFINITY, bhi = -INFINITY;
      for (const Point2& v : a) {
        alo = std::min(alo, v[0] * nx + v[1] * ny);
        ahi = std::max(ahi, v[0] * nx + v[1] * ny);
      }
      for (const Point2& v : b) {
        blo = std::min(blo, v[0] * nx + v[1] * ny);
        bhi = std::max(bhi, v[0] * nx + v[1] * ny);
      }
      if (!(std::min(ahi, bhi) - std::max(alo, blo) > tol * std::sqrt(nx * nx + ny * ny))) return false;
    }
  return true;
}

// The centroid of the vertices of the part two convex polygons share (a
// clipped by each edge of b), for the message.
Point2 shared_point(const Polygon2& a, const Polygon2& b) {
  Polygon2 poly = a, next;
  for (size_t e = 0; e < b.size() && !poly.empty(); ++e) {
    const Point2& p = b[e];
    const Point2& q = b[(e + 1) % b.size()];
    next.clear();
    for (size_t i = 0; i < poly.size(); ++i) {
      const Point2& u = poly[i];
      const Point2& v = poly[(i + 1) % poly.size()];
      const double su = cross2(p, q, u), sv = cross2(p, q, v);
      if (su >= 0.0) next.push_back(u);
      if ((su >= 0.0) != (sv >= 0.0)) {
        const double t = su / (su - sv);
        next.push_back({u[0] + t * (v[0] - u[0]), u[1] + t * (v[1] - u[1])});
      }
    }
    poly.swap(next);
  }
  Point2 c{0.0, 0.0};
  for (const Point2& p : poly) {
    c[0] += p[0] / static_cast<double>(poly.size());
    c[1] += p[1] / static_cast<double>(poly.size());
  }
  return c;
}

// A plane's axes about a point of it, (u, w, n) right-handed: a loop
// counter-clockwise around n is counter-clockwise in (u, w). About a point
// of the face, not the origin, the coordinates keep their digits in a scene
// far from the origin.
struct PlaneAxes {
  Vec3 o, u, w;
  PlaneAxes(const Vec3& normal, const Vec3& origin)
      : o(origin),
        u(glm::normalize(glm::cross(normal, std::abs(normal.x) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0)))),
        w(glm::cross(normal, u)) {}
  PlaneAxes(const Scene& scene, const Patch& patch)
      : PlaneAxes(patch.normal, scene.vertices[static_cast<size_t>(patch.outer[0])]) {}
  Point2 flat(const Vec3& x) const { return {glm::dot(x - o, u), glm::dot(x - o, w)}; }
  Vec3 lift(const Point2& p) const { return o + p[0] * u + p[1] * w; }
};

std::vector<Box3> outline_boxes(const Scene& scene) {
  std::vector<Box3> boxes(scene.patches.size());
  for (size_t p = 0; p < boxes.size(); ++p)
    for (const int v : scene.patches[p].outer) boxes[p].add(scene.vertices[static_cast<size_t>(v)]);
  return boxes;
}

// Patches p and q face the same way, q's outline lies on p's plane and p's
// plane is tilted from q's by less than tol over p's size (its box's
// diagonal).
bool coplanar(const Scene& scene, const std::vector<Box3>& boxes, size_t p, size_t q, double tol) {
  const Patch& a = scene.patches[p];
  const Patch& b = scene.patches[q];
  if (!(glm::dot(a.normal, b.normal) > 0.0) ||
      glm::length(glm::cross(a.normal, b.normal)) * glm::length(boxes[p].hi - boxes[p].lo) > tol)
    return false;
  const Vec3& origin = scene.vertices[static_cast<size_t>(a.outer[0])];
  return std::all_of(b.outer.begin(), b.outer.end(), [&](int v) {
    return std::abs(glm::dot(scene.vertices[static_cast<size_t>(v)] - origin, a.normal)) <= tol;
  });
}

// A loop in a plane's axes, into `poly` (kept by the caller: a million
// faces would otherwise allocate a million times).
void flat_loop(const Scene& scene, const std::vector<int>& loop, const PlaneAxes& axes, Polygon2& poly) {
  poly.clear();
  for (const int v : loop) poly.push_back(axes.flat(scene.vertices[static_cast<size_t>(v)]));
}

Polygon2 flat_loop(const Scene& scene, const std::vector<int>& loop, const PlaneAxes& axes) {
  Polygon2 poly;
  flat_loop(scene, loop, axes, poly);
  return poly;
}

// Crossing number: x strictly inside the polygon (on its edge: either).
bool inside(const Polygon2& poly, const Point2& x) {
  bool in = false;
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const Point2& a = poly[i];
    const Point2& b = poly[j];
    if ((a[1] > x[1]) != (b[1] > x[1]) && x[0] < a[0] + (x[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1])) in = !in;
  }
  return in;
}

// Whether two segments come within tol of each other (crossing: distance 0).
bool segments_near(const Point2& a0, const Point2& a1, const Point2& b0, const Point2& b1, double tol) {
  const double d1 = cross2(a0, a1, b0), d2 = cross2(a0, a1, b1), d3 = cross2(b0, b1, a0), d4 = cross2(b0, b1, a1);
  if (((d1 < 0.0 && d2 > 0.0) || (d1 > 0.0 && d2 < 0.0)) && ((d3 < 0.0 && d4 > 0.0) || (d3 > 0.0 && d4 < 0.0)))
    return true;
  // The end points' distances (geometry.h's, in the plane z = 0).
  const auto d = [](const Point2& x, const Point2& a, const Point2& b) {
    return point_segment_distance(Vec3(x[0], x[1], 0.0), Vec3(a[0], a[1], 0.0), Vec3(b[0], b[1], 0.0));
  };
  return std::min({d(a0, b0, b1), d(a1, b0, b1), d(b0, a0, a1), d(b1, a0, a1)}) <= tol;
}

// Whether an edge of loop a comes within tol of an edge of loop b.
bool loops_near(const Polygon2& a, const Polygon2& b, double tol) {
  for (size_t i = 0; i < a.size(); ++i)
    for (size_t j = 0; j < b.size(); ++j)
      if (segments_near(a[i], a[(i + 1) % a.size()], b[j], b[(j + 1) % b.size()], tol)) return true;
  return false;
}

// Edge pairs a containment test may compare; past this the face is not cut
// (and the overlap check refuses it).
constexpr size_t kMaxContainmentPairs = 1 << 20;

// Whether the outline `in` (a face's, or a group's of faces: counter-
// clockwise) lies inside face `out` (its outline less its first `holes`
// holes) with every edge clear of those edges by more than tol, and no
// such hole inside it.
bool lies_inside(const Scene& scene, size_t out, size_t holes, const std::vector<int>& in, double tol) {
  const Patch& o = scene.patches[out];
  const PlaneAxes axes(scene, o);
  std::vector<Polygon2> loops = {flat_loop(scene, o.outer, axes)};
  for (size_t h = 0; h < holes; ++h) loops.push_back(flat_loop(scene, o.holes[h], axes));
  const Polygon2 poly = flat_loop(scene, in, axes);
  size_t pairs = 0;
  for (const Polygon2& loop : loops) pairs += loop.size() * poly.size();
  if (pairs > kMaxContainmentPairs) return false;
  if (!inside(loops[0], poly[0])) return false;
  for (size_t h = 1; h < loops.size(); ++h)
    if (inside(loops[h], poly[0]) || inside(poly, loops[h][0])) return false;
  return std::none_of(loops.begin(), loops.end(), [&](const Polygon2& loop) { return loops_near(loop, poly, tol); });
}

// Whether two loops of one orientation run along a common edge (in
// opposite directions).
bool share_an_edge(const std::vector<int>& a, const std::vector<int>& b) {
  for (size_t i = 0; i < a.size(); ++i)
    for (size_t j = 0; j < b.size(); ++j)
      if (a[i] == b[(j + 1) % b.size()] && a[(i + 1) % a.size()] == b[j]) return true;
  return false;
}

// The outline of faces of one plane without holes joined along shared
// edges (a rug of tiles), counter-clockwise as theirs are: the edges that no
// other face of the group runs along the other way. Empty unless those
// make one loop through distinct vertices enclosing the faces' area: not
// where faces meet only at a corner or an edge ends on another's middle,
// nor around a part of the plane they leave open (a ring of tiles, whose
// middle would be an island of the face below).
std::vector<int> joined_outline(const Scene& scene, const std::vector<size_t>& faces) {
  std::vector<std::pair<int, int>> edges;
  double area = 0.0;
  for (const size_t f : faces) {
    const std::vector<int>& o = scene.patches[f].outer;
    for (size_t i = 0; i < o.size(); ++i) edges.emplace_back(o[i], o[(i + 1) % o.size()]);
    area += scene.patch_area(static_cast<int>(f));
  }
  std::sort(edges.begin(), edges.end());
  std::vector<std::pair<int, int>> next;  // boundary edges, by first vertex
  for (const auto& [a, b] : edges)
    if (!std::binary_search(edges.begin(), edges.end(), std::pair<int, int>(b, a))) next.emplace_back(a, b);
  for (size_t i = 1; i < next.size(); ++i)
    if (next[i].first == next[i - 1].first) return {};  // a pinch, or an edge twice
  std::vector<int> loop;
  for (int v = next.empty() ? -1 : next[0].first; v >= 0 && loop.size() <= next.size();) {
    loop.push_back(v);
    const auto it = std::lower_bound(next.begin(), next.end(), std::pair<int, int>(v, INT_MIN));
    if (it == next.end() || it->first != v) return {};
    v = it->second;
    if (v == loop[0]) break;
  }
  if (loop.size() != next.size() || loop.size() < 3) return {};
  const double joined = 0.5 * glm::dot(newell_normal(scene.loop_points(loop)), scene.patches[faces[0]].normal);
  if (!(std::abs(joined - area) <= 1e-9 * area)) return {};
  return loop;
}

// The error for patches p and q that overlap around `at`.
InputError overlap_error(const Scene& scene, size_t p, size_t q, const Vec3& at, double tol) {
  const Patch& first = scene.patches[p];
  const Patch& second = scene.patches[q];
  return InputError(where(second.file, second.line) + "face '" + second.name + "' and face '" + first.name + "'" +
                    also_at(first.file, first.line) + " lie in one plane facing the same way and overlap (around (" + format_number(at.x) + ", " +
                    format_number(at.y) + ", " + format_number(at.z) +
                    ")): which of them is lit there is not defined, and the light would count the area twice; "
                    "cut the overlap out of one of them (a hole in the ceiling where a lamp lies in it), or lift one "
                    "off the other by more than " +
                    format_number(tol) + " (" + format_number(kCoplanarOverlapTolerance) + " of the scene size)");
}

// Whether the outline `in` can become a hole of patch `out`: it lies in
// out's plane as build_scene wants holes to (within planarity_tolerance of
// out's size, at least its box's diagonal / sqrt 3), inside it and clear of
// its edges and of its first `holes` holes (all of them by default).
bool fits_as_hole(const Scene& scene, const std::vector<Box3>& boxes, size_t out, const std::vector<int>& in,
                  double tol, double planarity_tolerance, size_t holes = SIZE_MAX) {
  const Patch& o = scene.patches[out];
  const Vec3& origin = scene.vertices[static_cast<size_t>(o.outer[0])];
  const double off = planarity_tolerance * glm::length(boxes[out].hi - boxes[out].lo) / std::sqrt(3.0);
  for (const int v : in)
    if (std::abs(glm::dot(scene.vertices[static_cast<size_t>(v)] - origin, o.normal)) > off) return false;
  return lies_inside(scene, out, std::min(holes, o.holes.size()), in, tol);
}

// Where face `in` (outline `outline`, with the faces `outs` that may hold
// it) fits in none of them only because it touches what was cut out of one
// of them for another face (`made`: (face cut into, face cut out), one per
// hole added, in order), refuses it naming that face: faces that meet at a
// corner, or along part of an edge, cannot be cut out together, and the
// overlap error alone would not say why.
void refuse_touching_cut(const Scene& scene, const std::vector<Box3>& boxes, size_t in, const std::vector<int>& outline,
                         const std::vector<size_t>& outs, const std::vector<std::pair<size_t, size_t>>& made,
                         double tol, double planarity_tolerance) {
  for (const size_t out : outs) {
    std::vector<size_t> cut;  // faces cut out of `out`, in hole order
    for (const auto& [into, face] : made)
      if (into == out) cut.push_back(face);
    if (cut.empty()) continue;
    const Patch& o = scene.patches[out];
    const size_t own = o.holes.size() - cut.size();  // the holes it had before the cuts
    if (!fits_as_hole(scene, boxes, out, outline, tol, planarity_tolerance, own)) continue;
    const PlaneAxes axes(scene, o);
    const Polygon2 poly = flat_loop(scene, outline, axes);
    for (size_t h = 0; h < cut.size(); ++h) {
      if (!loops_near(flat_loop(scene, o.holes[own + h], axes), poly, tol)) continue;
      const Patch& a = scene.patches[in];
      const Patch& b = scene.patches[cut[h]];
      const std::string head = where(a.file, a.line) + "face '" + a.name + "' lies in face '" + o.name + "'" +
                               also_at(o.file, o.line) + " and touches face '" + b.name + "'" +
                               also_at(b.file, b.line) + ", cut out of it already";
      if (share_an_edge(a.outer, b.outer))
        throw InputError(head + ", along an edge, but the faces joined with them by their edges enclose part of "
                                "face '" + o.name + "' (a ring of tiles) or meet only at a corner, which one hole "
                                "cannot follow; fill the part they enclose with a face of its own, or lift them off "
                                "face '" + o.name + "' by more than " + format_number(tol));
      throw InputError(head + ", without sharing whole edges with it (at a corner, or along part of an edge): the "
                              "two cannot be cut out of it together; make them share the edges where they meet (the "
                              "same vertices at both ends), or keep them more than " +
                       format_number(tol) + " apart");
    }
  }
}

// The test of a pair of faces in one plane that is not a cut: two convex
// faces without holes are tested whole (convex faces along a shared edge lie
// on its two sides); the others are left to the mesh's triangles.
struct PairCheck {
  Scene& scene;
  double tol;
  std::vector<signed char> direct;  // per patch, -1 until known
  Polygon2 pa, pb;

  bool is_direct(size_t p) {
    if (direct[p] < 0) {
      const Patch& patch = scene.patches[p];
      direct[p] = patch.holes.empty() && patch.outer.size() <= kMaxDirectVertices;
      if (direct[p]) {
        flat_loop(scene, patch.outer, PlaneAxes(scene, patch), pa);
        direct[p] = convex(pa);
      }
    }
    return direct[p] == 1;
  }
  void check(size_t p, size_t q) {
    if (!is_direct(p) || !is_direct(q)) {
      scene.coplanar_pairs.emplace_back(static_cast<int>(p), static_cast<int>(q));
      return;
    }
    if (share_an_edge(scene.patches[p].outer, scene.patches[q].outer)) return;
    const PlaneAxes axes(scene, scene.patches[p]);
    flat_loop(scene, scene.patches[p].outer, axes, pa);
    flat_loop(scene, scene.patches[q].outer, axes, pb);
    if (overlap_more_than(pa, pb, tol)) throw overlap_error(scene, p, q, axes.lift(shared_point(pa, pb)), tol);
  }
};

// Patch areas, each computed when first asked for.
struct PatchAreas {
  const Scene& scene;
  std::vector<double> areas;  // -1 until known

  double operator()(size_t p) {
    if (areas[p] < 0.0) areas[p] = scene.patch_area(static_cast<int>(p));
    return areas[p];
  }
};

// What is cut: a face, or faces of one plane joined along shared edges
// (a rug of tiles, a grid of lamp panels) as one outline, each with the
// faces that may hold it (those holding every member).
struct CutUnit {
  std::vector<size_t> members;
  std::vector<int> outline;
  double area = 0.0;
  std::vector<size_t> outs;
};

// The units to cut from `containing` ((in, out): per face without holes,
// the faces of larger area holding it; sorted), in the order of their
// groups.
std::vector<CutUnit> cut_units(const Scene& scene, const std::vector<Box3>& boxes, const BoxTree& tree, double tol,
                               const std::vector<std::pair<size_t, size_t>>& containing, PatchAreas& area) {
  const size_t np = scene.patches.size();
  std::vector<CutUnit> units;
  std::vector<size_t> first(np, containing.size());  // per face, its first entry in containing
  for (size_t k = containing.size(); k-- > 0;) first[containing[k].first] = k;
  auto outs_of = [&](size_t in) {
    std::vector<size_t> outs;
    for (size_t k = first[in]; k < containing.size() && containing[k].first == in; ++k)
      outs.push_back(containing[k].second);
    return outs;
  };
  // Faces that may be cut, joined where they share an edge.
  std::vector<size_t> cuttable;
  for (size_t k = 0; k < containing.size(); ++k)
    if (k == 0 || containing[k - 1].first != containing[k].first) cuttable.push_back(containing[k].first);
  std::vector<size_t> group(np);
  std::iota(group.begin(), group.end(), size_t{0});
  auto find = [&](size_t x) {
    while (group[x] != x) x = group[x] = group[group[x]];
    return x;
  };
  for (const size_t p : cuttable) {
    const std::vector<int>& a = scene.patches[p].outer;
    tree.overlapping(boxes[p], tol, [&](int qi) {
      const size_t q = static_cast<size_t>(qi);
      const std::vector<int>& b = scene.patches[q].outer;
      if (q != p && first[q] < containing.size() && a.size() * b.size() <= kMaxContainmentPairs &&
          coplanar(scene, boxes, p, q, tol) && share_an_edge(a, b))
        group[find(p)] = find(q);
      return true;
    });
  }
  std::vector<std::pair<size_t, size_t>> joined;  // (group, face), faces of a group together
  for (const size_t f : cuttable) joined.emplace_back(find(f), f);
  std::sort(joined.begin(), joined.end());
  for (size_t k = 0, end; k < joined.size(); k = end) {
    std::vector<size_t> faces;
    for (end = k; end < joined.size() && joined[end].first == joined[k].first; ++end)
      faces.push_back(joined[end].second);
    std::vector<int> outline = faces.size() > 1 ? joined_outline(scene, faces) : std::vector<int>();
    if (outline.empty()) {  // one face, or faces that do not join into one outline: each alone
      for (const size_t f : faces) units.push_back({{f}, scene.patches[f].outer, area(f), outs_of(f)});
      continue;
    }
    CutUnit u{faces, std::move(outline), 0.0, outs_of(faces[0])};
    for (const size_t f : faces) {
      u.area += area(f);
      const std::vector<size_t> outs = outs_of(f);  // sorted, as containing is
      std::erase_if(u.outs, [&](size_t o) { return !std::binary_search(outs.begin(), outs.end(), o); });
    }
    units.push_back(std::move(u));
  }
  return units;
}

}  // namespace

std::vector<std::pair<int, int>> settle_coplanar_faces(Scene& scene, double planarity_tolerance) {
  const size_t np = scene.patches.size();
  const double tol = kCoplanarOverlapTolerance * scene.diagonal();
  const std::vector<Box3> boxes = outline_boxes(scene);
  scene.coplanar_pairs.clear();

  PairCheck pairs{scene, tol, std::vector<signed char>(np, -1), {}, {}};
  // Whether out's box, grown by tol, holds in's box: a pair that may be a
  // cut, checked once the cuts are made.
  auto holds = [&](size_t out, size_t in) {
    return glm::all(glm::lessThanEqual(boxes[out].lo - tol, boxes[in].lo)) &&
           glm::all(glm::greaterThanEqual(boxes[out].hi + tol, boxes[in].hi));
  };
  std::vector<std::pair<size_t, size_t>> held;  // (p, q), p < q
  const BoxTree tree(boxes);
  for (size_t p = 0; p < np; ++p)
    tree.overlapping(boxes[p], tol, [&](int qi) {
      const size_t q = static_cast<size_t>(qi);
      if (q <= p || !(coplanar(scene, boxes, p, q, tol) || coplanar(scene, boxes, q, p, tol))) return true;
      if (holds(p, q) || holds(q, p))
        held.emplace_back(p, q);
      else
        pairs.check(p, q);
      return true;
    });

  // Cuts: per face without holes, the faces of larger area holding it.
  PatchAreas area{scene, std::vector<double>(np, -1.0)};
  std::vector<std::pair<size_t, size_t>> containing;  // (in, out)
  for (const auto& [a, b] : held)
    for (const auto& [in, out] : {std::pair<size_t, size_t>(a, b), std::pair<size_t, size_t>(b, a)})
      if (scene.patches[in].holes.empty() && holds(out, in) && area(out) > area(in)) containing.emplace_back(in, out);
  std::sort(containing.begin(), containing.end());

  std::vector<CutUnit> units;
  if (!containing.empty()) units = cut_units(scene, boxes, tree, tol, containing, area);
  // Largest first: nothing is cut out of a face before the face itself has
  // been placed, so the holes it has then are its own (a ring's: the floor
  // shows through, and it is not cut).
  std::stable_sort(units.begin(), units.end(), [](const CutUnit& x, const CutUnit& y) {
    return x.area > y.area || (x.area == y.area && x.members[0] < y.members[0]);
  });
  std::vector<std::pair<int, int>> cuts;  // (in, out), in the order made
  std::vector<std::pair<size_t, size_t>> cut_pairs;  // the same as (p, q), p < q
  std::vector<std::pair<size_t, size_t>> made;  // (face cut into, first face of the unit cut), in hole order
  for (const CutUnit& u : units) {
    size_t best = np;
    for (const size_t out : u.outs)  // never a member: no face holds itself
      if (area(out) > u.area && (best == np || area.areas[out] < area.areas[best]) &&
          fits_as_hole(scene, boxes, out, u.outline, tol, planarity_tolerance))
        best = out;
    if (best == np) {
      refuse_touching_cut(scene, boxes, u.members[0], u.outline, u.outs, made, tol, planarity_tolerance);
      continue;
    }
    made.emplace_back(best, u.members[0]);
    std::vector<int> hole = u.outline;
    std::reverse(hole.begin(), hole.end());  // clockwise around the normal
    scene.patches[best].holes.push_back(std::move(hole));
    pairs.direct[best] = 0;
    for (const size_t in : u.members) {
      cuts.emplace_back(static_cast<int>(in), static_cast<int>(best));
      cut_pairs.emplace_back(std::min(in, best), std::max(in, best));
    }
  }
  std::sort(cut_pairs.begin(), cut_pairs.end());
  for (const auto& pq : held)
    if (!std::binary_search(cut_pairs.begin(), cut_pairs.end(), pq)) pairs.check(pq.first, pq.second);
  std::sort(scene.coplanar_pairs.begin(), scene.coplanar_pairs.end());
  return cuts;
}

void refuse_coplanar_overlaps(const Scene& scene, const Mesh& mesh) {
  if (scene.coplanar_pairs.empty()) return;
  const size_t np = scene.patches.size();
  const double tol = kCoplanarOverlapTolerance * scene.diagonal();
  std::vector<char> involved(np, 0);
  for (const auto& [p, q] : scene.coplanar_pairs) involved[static_cast<size_t>(p)] = involved[static_cast<size_t>(q)] = 1;
  const std::vector<std::pair<int, int>>& pairs = scene.coplanar_pairs;  // sorted

  // Their triangles, pair by pair where their boxes meet, in the first
  // patch's plane.
  std::vector<int> tris;
  std::vector<Box3> tri_boxes;
  for (int t = 0; t < mesh.triangle_count(); ++t) {
    if (!involved[static_cast<size_t>(mesh.patch[static_cast<size_t>(t)])] || mesh.zero_area(t)) continue;
    Box3 b;
    for (const int v : mesh.triangles[static_cast<size_t>(t)]) b.add(mesh.positions[static_cast<size_t>(v)]);
    tris.push_back(t);
    tri_boxes.push_back(b);
  }
  const BoxTree tri_tree(tri_boxes);
  for (size_t i = 0; i < tris.size(); ++i) {
    const size_t p = static_cast<size_t>(mesh.patch[static_cast<size_t>(tris[i])]);
    const PlaneAxes axes(scene, scene.patches[p]);
    auto flat = [&](int t) {
      Polygon2 f;
      for (const int v : mesh.triangles[static_cast<size_t>(t)]) f.push_back(axes.flat(mesh.positions[static_cast<size_t>(v)]));
      return f;
    };
    const Polygon2 a = flat(tris[i]);
    tri_tree.overlapping(tri_boxes[i], tol, [&](int j) {
      const size_t q = static_cast<size_t>(mesh.patch[static_cast<size_t>(tris[static_cast<size_t>(j)])]);
      if (q <= p || !std::binary_search(pairs.begin(), pairs.end(), std::pair<int, int>(static_cast<int>(p), static_cast<int>(q))))
        return true;
      const Polygon2 b = flat(tris[static_cast<size_t>(j)]);
      if (overlap_more_than(a, b, tol)) throw overlap_error(scene, p, q, axes.lift(shared_point(a, b)), tol);
      return true;
    });
  }
}

}  // namespace radmesh
