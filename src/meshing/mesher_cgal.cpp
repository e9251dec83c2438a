// Initial mesh of every patch: CGAL constrained Delaunay triangulation in the
// patch's plane, refined by CGAL's Delaunay mesher. Its bookkeeping that needs
// no CGAL (boundary segments and the points on them, line end ids, messages)
// is boundary_points.cpp, so that this stays one CGAL translation unit.
//
// Conformity between patches: every boundary segment of every patch is split
// at the same global points on both sides. Points on a segment are (1) scene
// vertices lying on it, (2) an even pre-split to the maximum edge length, and
// (3) the points CGAL's mesher adds when it splits an encroached boundary
// edge; (3) are passed to every other patch with a collinear overlapping
// segment, which is then meshed again. This repeats until no patch gains a
// point; the last allowed round inserts the points without refinement (the
// patch's interior points from its last refinement are kept), so the result
// is always conforming.

#include "core/box_tree.h"
#include "core/snap.h"
#include "meshing/boundary_points.h"
#include "radmesh/errors.h"
#include "radmesh/mesh.h"
#include "scene/overlap.h"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Constrained_triangulation_plus_2.h>
#include <CGAL/Delaunay_mesh_face_base_2.h>
#include <CGAL/Delaunay_mesh_size_criteria_2.h>
#include <CGAL/Delaunay_mesh_vertex_base_2.h>
#include <CGAL/Delaunay_mesher_2.h>
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <numbers>
#include <optional>
#include <set>
#include <sstream>
#include <unordered_map>

namespace radmesh {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
// Global vertex id; -1 for points CGAL created (default-constructed).
struct VertexId {
  int id = -1;
};
using Vb = CGAL::Triangulation_vertex_base_with_info_2<VertexId, K, CGAL::Delaunay_mesh_vertex_base_2<K>>;
using Fb = CGAL::Triangulation_face_base_with_info_2<int, K, CGAL::Delaunay_mesh_face_base_2<K>>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
using CDTBase = CGAL::Constrained_Delaunay_triangulation_2<K, Tds, CGAL::Exact_predicates_tag>;
// The constraint hierarchy lets discontinuity lines cross and overlap.
using CDT = CGAL::Constrained_triangulation_plus_2<CDTBase>;
using EK = CGAL::Exact_predicates_exact_constructions_kernel;
using SizeCriteria = CGAL::Delaunay_mesh_size_criteria_2<CDT>;

// CGAL's size-and-angle criteria, except that a triangle whose shortest edge
// is below `floor` is not refined for its angle. Where discontinuity lines
// meet or run at small angles, the angle bound alone would ask for ever
// smaller triangles (the small angle is in the input); the floor bounds that.
class Criteria : public SizeCriteria {
public:
  Criteria(double squared_sine_bound, double size_bound, double floor)
      : CGAL::Delaunay_mesh_criteria_2<CDT>(squared_sine_bound),
        SizeCriteria(squared_sine_bound, size_bound),
        floor2_(floor * floor) {}

  class Is_bad : public SizeCriteria::Is_bad {
  public:
    Is_bad(double bound, double size_bound, const Geom_traits& traits, double floor2)
        : SizeCriteria::Is_bad(bound, size_bound, traits), floor2_(floor2) {}
    CGAL::Mesh_2::Face_badness operator()(const Quality q) const { return SizeCriteria::Is_bad::operator()(q); }
    CGAL::Mesh_2::Face_badness operator()(const CDT::Face_handle& fh, Quality& q) const {
      const CGAL::Mesh_2::Face_badness r = SizeCriteria::Is_bad::operator()(fh, q);
      if (r != CGAL::Mesh_2::BAD) return r;  // too large (imperative), or fine
      const K::Point_2 &a = fh->vertex(0)->point(), &b = fh->vertex(1)->point(), &c = fh->vertex(2)->point();
      const double shortest = std::min({CGAL::squared_distance(a, b), CGAL::squared_distance(b, c),
                                        CGAL::squared_distance(c, a)});
      if (shortest >= floor2_) return r;
      q = Quality(1.0, q.size());  // so that re-checking the stored quality agrees
      return CGAL::Mesh_2::NOT_BAD;
    }

  private:
    double floor2_;
  };
  Is_bad is_bad_object() const { return Is_bad(this->bound(), this->size_bound(), this->traits, floor2_); }

private:
  double floor2_;
};
using Mesher = CGAL::Delaunay_mesher_2<CDT, Criteria>;
using Point2 = K::Point_2;

constexpr int kMaxRounds = 5;
// A face this many times its size from the origin has lost 6 of double's
// 16 digits to its position (the hint of a failed triangulation).
constexpr double kFarForItsSize = 1e6;

// A patch's plane as CGAL sees it: an orthonormal frame (u, v, n),
// right-handed, at the patch's first corner, with lengths in units of the
// patch's radius about that corner and coordinates snapped to multiples of
// 2^-33 of that radius. Scaling or moving a scene then hands CGAL the same
// numbers, not numbers a few ulps apart: the ties among cocircular points
// (a rectangle's corners, an even split of its edges) and the mesher's
// Steiner points come out the same, so the mesh is the same mesh, scaled or
// moved. The snap (1e-10 of the radius) is far below the points' merging
// distance (1e-9 of the scene's diagonal); the points the mesher adds on
// the outline and the lines are put back on them (constrained_positions).
struct Frame {
  Vec3 origin, u, v;
  double scale = 1.0;  // one unit in the plane, in scene units
  Point2 to2(const Vec3& p) const {
    const Point2 q = unsnapped(p);
    return Point2(internal::snap_unit(q.x()), internal::snap_unit(q.y()));
  }
  // For constructions whose result goes back to 3-D (line crossings).
  Point2 unsnapped(const Vec3& p) const {
    const Vec3 d = p - origin;
    return Point2(glm::dot(d, u) / scale, glm::dot(d, v) / scale);
  }
  Vec3 to3(const Point2& q) const { return origin + (q.x() * scale) * u + (q.y() * scale) * v; }
  // A length in scene units, in the plane's units, to 36 bits: the mesher's
  // bounds, the same numbers for a scaled or moved scene as well.
  double in_plane(double length) const {
    int e = 0;
    const double m = std::frexp(length / scale, &e);
    return std::ldexp(std::nearbyint(std::ldexp(m, 36)), e - 36);
  }
};

Frame make_frame(const Scene& scene, const Patch& patch) {
  Frame f;
  f.origin = scene.vertices[static_cast<size_t>(patch.outer[0])];
  // u along the first edge: the frame moves with the patch.
  const Vec3 n = patch.normal;
  const Vec3 e = scene.vertices[static_cast<size_t>(patch.outer[1])] - f.origin;
  f.u = glm::normalize(e - glm::dot(e, n) * n);
  f.v = glm::cross(n, f.u);
  double radius = 0.0;
  for (const int c : patch.outer)
    radius = std::max(radius, glm::length(scene.vertices[static_cast<size_t>(c)] - f.origin));
  f.scale = radius;
  return f;
}

// A 2-D box as a flat Box3, for BoxTree queries within one patch's plane.
Box3 flat_box(const CGAL::Bbox_2& b) {
  Box3 r;
  r.add(Vec3(b.xmin(), b.ymin(), 0.0));
  r.add(Vec3(b.xmax(), b.ymax(), 0.0));
  return r;
}

// Which of a list of 2-D segments (the first in order) holds an edge: both
// its ends within `tol` of the segment.
class SegmentsHolding {
 public:
  SegmentsHolding(const std::vector<std::pair<K::Segment_2, int>>& segments, double tol)
      : segments_(segments), tol_(tol), tree_(boxes(segments)) {}
  int first_holding(const Point2& p0, const Point2& p1) const {
    int first = -1;
    tree_.overlapping(flat_box(p0.bbox() + p1.bbox()), tol_, [&](int i) {
      const K::Segment_2& s = segments_[static_cast<size_t>(i)].first;
      if ((first < 0 || i < first) && CGAL::squared_distance(p0, s) <= tol_ * tol_ &&
          CGAL::squared_distance(p1, s) <= tol_ * tol_)
        first = i;
      return true;
    });
    return first;
  }

 private:
  static std::vector<Box3> boxes(const std::vector<std::pair<K::Segment_2, int>>& segments) {
    std::vector<Box3> b(segments.size());
    for (size_t i = 0; i < segments.size(); ++i) b[i] = flat_box(segments[i].first.bbox());
    return b;
  }
  const std::vector<std::pair<K::Segment_2, int>>& segments_;
  double tol_;
  BoxTree tree_;
};

// Marks the faces inside the patch: odd nesting depth, counting only the
// constrained edges for which `on_boundary` holds (interior constraints,
// the discontinuity lines, do not change what is inside).
template <class OnBoundary>
void mark_domain(CDT& cdt, OnBoundary on_boundary) {
  for (auto f = cdt.all_faces_begin(); f != cdt.all_faces_end(); ++f) f->info() = -1;
  std::vector<std::pair<CDT::Face_handle, int>> border = {{cdt.infinite_face(), 0}};
  while (!border.empty()) {
    auto [start, depth] = border.back();
    border.pop_back();
    if (start->info() != -1) continue;
    std::vector<CDT::Face_handle> stack = {start};
    start->info() = depth;
    while (!stack.empty()) {
      CDT::Face_handle f = stack.back();
      stack.pop_back();
      for (int i = 0; i < 3; ++i) {
        CDT::Face_handle nb = f->neighbor(i);
        if (nb->info() != -1) continue;
        const CDT::Edge e(f, i);
        if (cdt.is_constrained(e) && on_boundary(e)) {
          border.push_back({nb, depth + 1});
        } else {
          nb->info() = depth;
          stack.push_back(nb);
        }
      }
    }
  }
  for (auto f = cdt.all_faces_begin(); f != cdt.all_faces_end(); ++f) f->set_in_domain(f->info() % 2 == 1);
}

// The end points of a triangulation edge.
std::pair<Point2, Point2> edge_points(const CDT::Edge& e) {
  return std::pair<Point2, Point2>(e.first->vertex(CDT::cw(e.second))->point(),
                                   e.first->vertex(CDT::ccw(e.second))->point());
}

// Marks the faces inside the patch whose outline and holes are the segments
// of `outline` (mark_domain: only the constrained edges on them count).
void mark_inside(CDT& cdt, const SegmentsHolding& outline) {
  mark_domain(cdt, [&](const CDT::Edge& e) {
    const auto [p0, p1] = edge_points(e);
    return outline.first_holding(p0, p1) >= 0;
  });
}

// Shared state of one mesh_scene call; the boundary segments and the points
// on them are its base's (boundary_points.h).
class SceneMesher : private internal::BoundaryPoints {
public:
  // refine = false: each patch's constrained triangulation as it is.
  SceneMesher(const Scene& scene, const MeshingOptions& opt, bool refine)
      : internal::BoundaryPoints(scene), opt_(opt), refine_(refine) {
    if (refine_) {
      find_overlaps();
      if (opt.discontinuity != DiscontinuityMode::off) setup_constraints();
      seed_points(opt_.max_edge);
    }
  }

  Mesh run(MeshReport* report) {
    const int np = static_cast<int>(scene_.patches.size());
    std::vector<char> dirty(static_cast<size_t>(np), 1);
    std::vector<std::vector<std::array<int, 3>>> tris(static_cast<size_t>(np));
    double all_triangles = 0.0;  // in `tris`
    int rounds = 0;
    for (bool any = true; any; ++rounds) {
      any = false;
      const bool refine = refine_ && rounds + 1 < kMaxRounds;
      // Jacobi rounds: every dirty patch is meshed against the boundary
      // points known at the start of the round; the points they add are
      // shared afterwards. The result does not depend on the patch order.
      std::vector<int> todo;
      for (int p = 0; p < np; ++p)
        if (dirty[static_cast<size_t>(p)]) todo.push_back(p);
      std::fill(dirty.begin(), dirty.end(), 0);
      pending_.clear();
      for (int p : todo) {
        // The work bound: the mesher may add as many points to this patch
        // as the other patches leave of max_elements (each point makes
        // about two triangles).
        auto& mine = tris[static_cast<size_t>(p)];
        const double others = all_triangles - static_cast<double>(mine.size());
        point_budget_ = opt_.max_elements - others;
        mine = mesh_patch(p, refine);
        all_triangles = others + static_cast<double>(mine.size());
      }
      for (const Pending& pd : pending_) {
        const int same = find_point(pd.segment, positions_[static_cast<size_t>(pd.vertex)]);
        if (same >= 0) {
          alias_[pd.vertex] = same;
          continue;
        }
        std::vector<int> touched;
        add_point(pd.segment, pd.vertex, &touched);
        for (int q : touched)
          if (q != pd.patch) dirty[static_cast<size_t>(q)] = 1;
      }
      for (char d : dirty) any = any || d;
      if (any && rounds >= kMaxRounds)
        throw GeometryError(scene_.source + ": patches did not agree on shared boundary vertices after " +
                            std::to_string(rounds + 1) + " rounds");
    }
    Mesh mesh;
    mesh.positions = std::move(positions_);
    for (int p = 0; p < np; ++p)
      for (auto t : tris[static_cast<size_t>(p)]) {
        for (int& v : t)
          if (auto it = alias_.find(v); it != alias_.end()) v = it->second;
        mesh.triangles.push_back(t);
        mesh.patch.push_back(p);
      }
    for (auto& [p, edges] : features_)
      for (auto e : edges) {
        for (int& v : e)
          if (auto it = alias_.find(v); it != alias_.end()) v = it->second;
        mesh.feature_edges.push_back({std::min(e[0], e[1]), std::max(e[0], e[1])});
      }
    internal::compact(mesh);
    if (report) {
      report->boundary_rounds = rounds;
      report->contact_segments = contact_count_;
      report->shadow_segments = shadow_count_;
      report->crossings = crossings_;
      report->rounding_crossings = 0;
      report->thin_faces_unrefined = static_cast<int>(thin_.size());
      report->warnings = warnings_;
      for (const auto& [p, n] : rounding_crossings_) report->rounding_crossings += n;
      report->shadow = shadow_report_;
      report->warnings.insert(report->warnings.end(), shadow_report_.warnings.begin(), shadow_report_.warnings.end());
      report->discontinuities = discontinuities_;
    }
    return mesh;
  }

private:
  // The discontinuity lines of the scene: contacts and overhangs, then
  // (discontinuity full) the shadow boundaries.
  std::vector<DiscontinuitySegment> discontinuity_lines() {
    std::vector<DiscontinuitySegment> lines = contact_segments(scene_);
    const std::vector<DiscontinuitySegment> overhangs =
        overhang_segments(scene_, opt_.min_separation_fraction * opt_.max_edge);
    lines.insert(lines.end(), overhangs.begin(), overhangs.end());
    if (opt_.discontinuity == DiscontinuityMode::full) {
      ShadowOptions so = opt_.shadow;
      if (so.min_separation == 0.0) so.min_separation = opt_.min_separation_fraction * opt_.max_edge;
      std::vector<DiscontinuitySegment> shadows = shadow_segments(scene_, lines, so, &shadow_report_);
      lines.insert(lines.end(), shadows.begin(), shadows.end());
    }
    return lines;
  }

  // Discontinuity segments become constraints of their patch. Where two of
  // them cross, the crossing is constructed exactly (CGAL Epeck, in the
  // patch's plane) and rounded once; both are split there, so the CDT gets
  // constraints that meet only at shared end points. Their end points get
  // global ids once (shared by every round, internal::LinePoints) and, where
  // they lie on the patch's boundary, are shared with the neighbours like
  // any boundary point.
  void setup_constraints() {
    const std::vector<DiscontinuitySegment> lines = discontinuity_lines();
    internal::LinePoints points(positions_, scene_.vertices.size(), eps_, near_);
    std::vector<std::vector<size_t>> by_patch(scene_.patches.size());
    for (size_t i = 0; i < lines.size(); ++i) by_patch[static_cast<size_t>(lines[i].patch)].push_back(i);
    std::vector<std::vector<size_t>> segments_of(scene_.patches.size());  // boundary segments per patch
    for (size_t s = 0; s < segments_.size(); ++s) segments_of[static_cast<size_t>(segments_[s].patch)].push_back(s);
    for (size_t p = 0; p < by_patch.size(); ++p) {
      if (by_patch[p].empty()) continue;
      patch_constraints(p, lines, by_patch, segments_of, points);
    }
  }

  // The constraints of patch p from its lines (by_patch[p]): their exact
  // crossings, then each line's pieces between its ends and crossings.
  void patch_constraints(size_t p, const std::vector<DiscontinuitySegment>& lines,
                         const std::vector<std::vector<size_t>>& by_patch,
                         const std::vector<std::vector<size_t>>& segments_of, internal::LinePoints& points) {
    const Patch& patch = scene_.patches[p];
    const Frame frame = make_frame(scene_, patch);
    std::vector<int> own = patch.outer;
    for (const auto& hole : patch.holes) own.insert(own.end(), hole.begin(), hole.end());
    std::sort(own.begin(), own.end());
    // A piece lying on one of the patch's boundary segments (a line whose
    // end moved onto a corner, along the edge it started on) is that edge
    // already: inserted again over it, CGAL's mesher crashed.
    auto along_boundary = [&](int a, int b) {
      double t;
      for (size_t s : segments_of[p])
        if (on_line(s, positions_[static_cast<size_t>(a)], &t) && t >= -1e-9 && t <= 1.0 + 1e-9 &&
            on_line(s, positions_[static_cast<size_t>(b)], &t) && t >= -1e-9 && t <= 1.0 + 1e-9)
          return true;
      return false;
    };
    // A line's end within near_ of a corner of its own patch is that corner
    // (an overhang clipped to a tilted face's corner ends 1e-7 of the
    // diagonal from it, and CGAL's mesher can crash refining towards it);
    // not any point within near_, since an end moved onto another patch's
    // boundary point lies off its own patch's boundary, which can crash the
    // mesher too.
    auto end_id = [&](const Vec3& q) {
      const int corner = points.own_corner(q, own);
      return corner >= 0 ? corner : points.id_of(q);
    };
    // Exact crossings of the patch's lines, as parameters along each line.
    std::vector<std::vector<std::pair<double, Vec3>>> cuts(by_patch[p].size());
    std::vector<EK::Segment_2> seg2;
    std::vector<Box3> flat;  // each line's box, for the pairs that may cross
    for (size_t i : by_patch[p]) {
      const Point2 a = frame.unsnapped(lines[i].a), b = frame.unsnapped(lines[i].b);
      seg2.emplace_back(EK::Point_2(a.x(), a.y()), EK::Point_2(b.x(), b.y()));
      flat.push_back(flat_box(a.bbox() + b.bbox()));
    }
    const BoxTree line_tree(flat);
    std::vector<size_t> partners;
    for (size_t i = 0; i < seg2.size(); ++i) {
      partners.clear();
      line_tree.overlapping(flat[i], 0.0, [&](int j) {
        if (static_cast<size_t>(j) > i) partners.push_back(static_cast<size_t>(j));
        return true;
      });
      std::sort(partners.begin(), partners.end());  // in the order of the pairwise scan
      for (size_t j : partners) {
        const auto hit = CGAL::intersection(seg2[i], seg2[j]);
        if (!hit) continue;
        const EK::Point_2* x = boost::get<EK::Point_2>(&*hit);
        if (!x) continue;  // collinear overlap: the constraint hierarchy handles it
        const Vec3 q = frame.to3(Point2(CGAL::to_double(x->x()), CGAL::to_double(x->y())));
        for (size_t k : {i, j}) {
          const DiscontinuitySegment& d = lines[by_patch[p][k]];
          const double t = glm::dot(q - d.a, d.b - d.a) / glm::dot(d.b - d.a, d.b - d.a);
          if (glm::length(q - d.a) > eps_ && glm::length(q - d.b) > eps_) cuts[k].push_back({t, q});
        }
        ++crossings_;
      }
    }
    for (size_t k = 0; k < by_patch[p].size(); ++k) {
      const DiscontinuitySegment& d = lines[by_patch[p][k]];
      auto& c = cuts[k];
      c.push_back({0.0, d.a});
      c.push_back({1.0, d.b});
      // Crossings lie strictly inside (more than eps from either end), so
      // the sorted cuts start at d.a and end at d.b.
      std::sort(c.begin(), c.end(), [](auto& x, auto& y) { return x.first < y.first; });
      const int first = end_id(c[0].second);
      int prev = first;
      for (size_t i = 1; i < c.size(); ++i) {
        const int cur = i + 1 < c.size() ? points.id_of(c[i].second) : end_id(c[i].second);
        if (cur != prev && !along_boundary(prev, cur)) constraints_[p].push_back({prev, cur, d.kind});
        prev = cur;
      }
      for (int g : {first, prev})
        for (size_t s : segments_of[p]) add_point(s, g, nullptr);
      discontinuities_.push_back(d);
      ++(d.kind == 0 ? contact_count_ : shadow_count_);
    }
  }

  // Triangulates and refines one patch. New points on its boundary are made
  // global; they are recorded in pending_ and shared after the round.
  std::vector<std::array<int, 3>> mesh_patch(int p, bool refine) {
    const Patch& patch = scene_.patches[static_cast<size_t>(p)];
    const Frame frame = make_frame(scene_, patch);
    CDT cdt;
    std::vector<size_t> my_segments;
    for (int s = patch_segments_[static_cast<size_t>(p)]; s < patch_segments_[static_cast<size_t>(p) + 1]; ++s)
      my_segments.push_back(static_cast<size_t>(s));

    const std::vector<CDT::Vertex_handle> boundary_vertices = insert_boundary(cdt, frame, my_segments);
    const std::vector<std::pair<K::Segment_2, int>> lines2 = insert_lines(cdt, frame, p, refine, boundary_vertices);
    // The rounded end points must not make lines cross anywhere but at
    // their shared ends: CGAL would then add a crossing vertex (counted; the
    // triangulation stays valid, as it uses exact predicates).
    int& extra_crossings = rounding_crossings_[p];
    extra_crossings = 0;
    for (auto v = cdt.finite_vertices_begin(); v != cdt.finite_vertices_end(); ++v)
      if (v->info().id < 0) ++extra_crossings;
    if (!cdt.is_valid()) {
      std::ostringstream m;
      m << where(patch.file, patch.line) << "face '" << patch.name
        << "': the triangulation with its discontinuity lines is not valid after rounding";
      throw GeometryError(m.str());
    }
    // The kind of discontinuity line an edge lies on (both ends on one
    // piece; points the mesher adds on a piece lie on it too).
    const SegmentsHolding line_pieces(lines2, frame.in_plane(eps_));
    // A constrained edge is on the patch boundary when it lies on one of the
    // outline's (or a hole's) segments, whether or not a line runs along it
    // too: asking "not on a line" instead loses the sliver between a line
    // chained through a boundary point near it and that boundary (the
    // chained piece off the boundary would count as boundary).
    std::vector<std::pair<K::Segment_2, int>> outline2;
    for (size_t s : my_segments)
      outline2.push_back({K::Segment_2(frame.to2(positions_[static_cast<size_t>(segments_[s].a)]),
                                       frame.to2(positions_[static_cast<size_t>(segments_[s].b)])),
                          0});
    const SegmentsHolding outline(outline2, frame.in_plane(eps_));
    mark_inside(cdt, outline);

    const double patch_area = scene_.patch_area(p);
    if (refine) refine = refinable(cdt, p, patch, frame, my_segments, lines2, patch_area);
    if (refine) refine = refine_patch(cdt, p, patch, frame, patch_area, outline);
    number_new_vertices(cdt, frame, p, my_segments, refine);
    collect_features(cdt, p, lines2, line_pieces);
    return patch_triangles(cdt, patch);
  }

  // `near`: a face to start locating the point from.
  CDT::Vertex_handle insert_vertex(CDT& cdt, const Frame& frame, int g, CDT::Face_handle near = CDT::Face_handle()) {
    auto vh = cdt.insert(frame.to2(positions_[static_cast<size_t>(g)]), near);
    vh->info().id = g;
    return vh;
  }

  // The patch's boundary segments as constraints, each through the points
  // on it; returns the vertices inserted, in order.
  std::vector<CDT::Vertex_handle> insert_boundary(CDT& cdt, const Frame& frame,
                                                  const std::vector<size_t>& my_segments) {
    std::vector<CDT::Vertex_handle> boundary_vertices;
    for (size_t s : my_segments) {
      // Points sorted along the segment.
      std::vector<std::pair<double, int>> pts = {{0.0, segments_[s].a}, {1.0, segments_[s].b}};
      for (int g : seg_points_[s]) {
        double t;
        on_line(s, positions_[static_cast<size_t>(g)], &t);
        pts.push_back({t, g});
      }
      std::sort(pts.begin(), pts.end());
      // On an edge cut into many points (as where a narrow gap runs along
      // it), CGAL locates a point by a scan of the edges while the
      // triangulation is still a line (quadratic), so a vertex of the
      // outline off that line goes in first and each point is located from
      // the one before it; only there, since both change the triangulation
      // where points are cocircular.
      const bool many = pts.size() > kCollinearRun;
      if (cdt.dimension() < 2 && many)
        for (size_t o : my_segments) {
          const Vec3 q = positions_[static_cast<size_t>(segments_[o].b)];
          double t;
          if (!on_line(s, q, &t)) {
            insert_vertex(cdt, frame, segments_[o].b);
            break;
          }
        }
      CDT::Vertex_handle prev = insert_vertex(cdt, frame, pts[0].second);
      boundary_vertices.push_back(prev);
      for (size_t i = 1; i < pts.size(); ++i) {
        CDT::Vertex_handle cur = insert_vertex(cdt, frame, pts[i].second, many ? prev->face() : CDT::Face_handle());
        boundary_vertices.push_back(cur);
        if (prev != cur) cdt.insert_constraint(prev, cur);
        prev = cur;
      }
    }
    return boundary_vertices;
  }

  // The patch's discontinuity lines as constraints, each chained through
  // the points that lie on it; then, in the last round (no refinement), the
  // interior points of its last refined mesh. Returns the line pieces as
  // inserted, each with its line's kind: a line chained through a point
  // that lies near it (within near_) bends there, and the edges the mesher
  // makes on it lie on its pieces, not on the line.
  std::vector<std::pair<K::Segment_2, int>> insert_lines(CDT& cdt, const Frame& frame, int p, bool refine,
                                                         const std::vector<CDT::Vertex_handle>& boundary_vertices) {
    std::vector<std::pair<K::Segment_2, int>> lines2;
    // The last round (no refinement) keeps the patch's interior points from
    // its last refined mesh; those the mesher put on a line are chained into
    // it, so the line is not crossed by a sliver.
    std::vector<const Steiner*> on_line;  // kept points the mesher put on a line
    if (!refine)
      for (const Steiner& st : steiner_[p])
        if (st.on_line) on_line.push_back(&st);
    // Every other input point of the patch (boundary points, line ends) that
    // lies on a line up to rounding is chained into it as well: a line end
    // constructed on another line (a shadow boundary ending on a contact
    // line) is rounded off it by 1e-15, and a constraint passing that close
    // to a vertex is split by the mesher towards it without end, until it
    // crashes.
    std::vector<std::pair<Point2, int>> ends;
    for (const CDT::Vertex_handle& v : boundary_vertices) ends.push_back({v->point(), v->info().id});
    for (const auto& [a, b, kind] : constraints_[static_cast<size_t>(p)]) {
      (void)kind;
      for (const int g : {a, b}) ends.push_back({frame.to2(positions_[static_cast<size_t>(g)]), g});
    }
    // The candidates (kept points on a line, then the ends) in a box tree,
    // since a scan over all of them for every line is quadratic on a floor
    // with thousands of contact lines.
    std::vector<std::pair<Point2, int>> candidates;
    for (const Steiner* sp : on_line) candidates.push_back({sp->q, sp->id});
    candidates.insert(candidates.end(), ends.begin(), ends.end());
    std::vector<Box3> candidate_boxes(candidates.size());
    for (size_t i = 0; i < candidates.size(); ++i) candidate_boxes[i] = flat_box(candidates[i].first.bbox());
    const BoxTree candidate_tree(candidate_boxes);
    const double near2 = frame.in_plane(near_);
    for (const auto& constraint : constraints_[static_cast<size_t>(p)]) {
      // Named copies: clang 14 cannot capture structured bindings in a lambda.
      const int a = constraint[0], b = constraint[1];
      CDT::Vertex_handle va = insert_vertex(cdt, frame, a), vb = insert_vertex(cdt, frame, b);
      const K::Segment_2 seg(va->point(), vb->point());
      const CGAL::Bbox_2 sb = seg.bbox();
      const CGAL::Bbox_2 near(sb.xmin() - near2, sb.ymin() - near2, sb.xmax() + near2, sb.ymax() + near2);
      std::vector<std::pair<double, int>> chain;
      auto chain_if_on = [&](const Point2& q, int g) {
        if (g == a || g == b || !CGAL::do_overlap(q.bbox(), near) || CGAL::squared_distance(q, seg) > near2 * near2)
          return;
        const double da = std::sqrt(CGAL::squared_distance(q, va->point()));
        const double db = std::sqrt(CGAL::squared_distance(q, vb->point()));
        if (da > near2 && db > near2) chain.push_back({da, g});  // inside the line, not at an end
      };
      candidate_tree.overlapping(flat_box(near), 0.0, [&](int i) {
        chain_if_on(candidates[static_cast<size_t>(i)].first, candidates[static_cast<size_t>(i)].second);
        return true;
      });
      std::sort(chain.begin(), chain.end());
      chain.erase(std::unique(chain.begin(), chain.end(),
                              [](const auto& x, const auto& y) { return x.second == y.second; }),
                  chain.end());
      CDT::Vertex_handle prev = va;
      auto piece = [&](CDT::Vertex_handle cur) {
        if (cur == prev) return;
        cdt.insert_constraint(prev, cur);
        lines2.push_back({K::Segment_2(prev->point(), cur->point()), constraint[2]});
        prev = cur;
      };
      for (const auto& chained : chain) piece(insert_vertex(cdt, frame, chained.second));
      piece(vb);
    }
    if (!refine)
      for (const Steiner& st : steiner_[p])
        if (!st.on_line) insert_vertex(cdt, frame, st.id);
    return lines2;
  }

  // Whether a patch to be refined may be: not a sliver, narrower than the
  // separation floor (its width: twice its area over its perimeter) and
  // over 100 times longer than wide, which is left as the triangulation of
  // its outline and lines since the mesher would cut its long edges about
  // a width apart (see the budget in refine_patch) and light does not vary
  // across it (the element hierarchy still splits it); nor a patch with a
  // tiny line piece or a narrow part (narrow()), said in a warning; nor one
  // found too dense before (dense_).
  bool refinable(const CDT& cdt, int p, const Patch& patch, const Frame& frame, const std::vector<size_t>& my_segments,
                 const std::vector<std::pair<K::Segment_2, int>>& lines2, double patch_area) {
    double perimeter = 0.0;
    for (size_t s : my_segments)
      perimeter += glm::length(positions_[static_cast<size_t>(segments_[s].b)] - positions_[static_cast<size_t>(segments_[s].a)]);
    const double width = 2.0 * patch_area / perimeter;
    const double floor = opt_.min_separation_fraction * opt_.max_edge;
    const bool sliver = width < floor && perimeter > 200.0 * width;
    // A line piece shorter than 1e-6 of the scene's size (a tilted panel's
    // overhang clipped to a floor's edge in two pieces 2e-6 long): CGAL's
    // mesher can crash refining around it (inexact constructions at that
    // scale), and no light varies over it.
    std::string gap;
    if (!sliver) {
      for (const auto& [piece, kind] : lines2) {
        const double length = std::sqrt(piece.squared_length()) * frame.scale;
        if (length < kTinyPiece * diagonal_) {
          gap = "a piece of a discontinuity line on it is " + format_number(length) +
                " long, under " + format_number(kTinyPiece) + " of the scene's size, and refining around it is not "
                "reliable";
          break;
        }
      }
      if (gap.empty()) {
        gap = narrow(cdt, patch, frame, floor);
        if (!gap.empty())
          gap += ", so refining it to --max-edge " + format_number(opt_.max_edge) +
                 " would cut that edge about as finely along its length";
      }
    }
    if (sliver || !gap.empty() || dense_.count(p) > 0) {
      if (thin_.insert(p).second && !gap.empty())
        warnings_.push_back(where(patch.file, patch.line) + "face '" + patch.name + "': " + gap +
                            ": left as the triangulation of its outline and lines (the hierarchical method still "
                            "splits it where its links ask)");
      return false;
    }
    return true;
  }

  // Refines the patch's triangulation by CGAL's mesher, step by step within
  // a point budget. Returns false where the refinement made the patch too
  // dense (kDense): then it is the triangulation before refinement again,
  // and stays so in later rounds.
  bool refine_patch(CDT& cdt, int p, const Patch& patch, const Frame& frame, double patch_area,
                    const SegmentsHolding& outline) {
    bool refine = true;
    // The triangulation before refinement, kept while a dense patch may
    // fall back to it (below).
    std::optional<CDT> unrefined;
    {
      if (!opt_.refine_narrow_strips) unrefined.emplace(cdt);
      const double s = std::sin(opt_.min_angle * std::numbers::pi / 180.0);
      Mesher mesher(cdt, Criteria(s * s, frame.in_plane(opt_.max_edge),
                                  frame.in_plane(opt_.min_separation_fraction * opt_.max_edge)));
      // What the edge length asks for: the points there are, the constrained
      // edges (outline and lines) cut at --max-edge, the inside filled. The
      // mesher splits a constrained edge while a point lies in its diametral
      // circle, so the two long edges of a sliver w wide are cut about w
      // apart (a face 0.8 long and 1e-7 wide would take 16 M points); a
      // thousand times what is asked for stops it.
      double constrained = 0.0;
      for (auto e = cdt.finite_edges_begin(); e != cdt.finite_edges_end(); ++e)
        if (cdt.is_constrained(*e)) {
          const auto [p0, p1] = edge_points(*e);
          constrained += std::sqrt(CGAL::squared_distance(p0, p1)) * frame.scale;
        }
      const double h = opt_.max_edge;
      const double asked =
          static_cast<double>(cdt.number_of_vertices()) + constrained / h + patch_area / (0.43 * h * h);
      const double budget = std::min(point_budget_, 1000.0 * asked + 1e5);
      mesher.init(true);
      // Step by step, so that a patch whose lines and points lie far closer
      // together than the edge length (a vertex moved a millimetre off a
      // plane makes near-coincident shadow lines, a sliver face its own two
      // edges) stops at the bound with an error instead of meshing for
      // minutes.
      double points = 0.0;
      const double dense = kDense * asked + kDenseMin;
      while (mesher.step_by_step_refine_mesh()) {
        if (++points > dense && unrefined) break;
        if (points > budget)
          throw GeometryError(internal::budget_error(patch, h, budget, point_budget_, asked, opt_.max_elements),
                              {"max_edge", "discontinuity"});
      }
      if (unrefined && points > dense) {
        dense_.insert(p);
        thin_.insert(p);
        warnings_.push_back(internal::dense_warning(patch, h, dense, kDense, asked, kDenseMin));
        refine = false;
      } else {
        mark_inside(cdt, outline);
      }
    }
    if (unrefined && !refine) {
      cdt = *unrefined;
      mark_inside(cdt, outline);
    }
    return refine;
  }

  // Global ids for new vertices. Those on a boundary segment get the
  // segment's exact 3-D point and are shared; the others are remembered
  // for a last round without refinement.
  void number_new_vertices(CDT& cdt, const Frame& frame, int p, const std::vector<size_t>& my_segments, bool refine) {
    const std::map<CDT::Vertex_handle, Vec3> on_edges = constrained_positions(cdt);
    std::vector<Steiner> steiner;
    for (auto v = cdt.finite_vertices_begin(); v != cdt.finite_vertices_end(); ++v) {
      if (v->info().id >= 0) continue;
      const auto known = on_edges.find(v);
      const Vec3 p3 = known != on_edges.end() ? known->second : frame.to3(v->point());
      int best = -1;
      double best_d = std::numeric_limits<double>::infinity(), best_t = 0.0;
      for (size_t s : my_segments) {
        const Vec3 A = positions_[static_cast<size_t>(segments_[s].a)];
        const Vec3 B = positions_[static_cast<size_t>(segments_[s].b)];
        const double t = std::clamp(glm::dot(p3 - A, B - A) / glm::dot(B - A, B - A), 0.0, 1.0);
        const double d = glm::length(p3 - (A + t * (B - A)));
        if (d < best_d) {
          best_d = d;
          best = static_cast<int>(s);
          best_t = t;
        }
      }
      const int g = static_cast<int>(positions_.size());
      if (best >= 0 && best_d <= near_ && is_on_constraint(cdt, v)) {
        const Vec3 A = positions_[static_cast<size_t>(segments_[static_cast<size_t>(best)].a)];
        const Vec3 B = positions_[static_cast<size_t>(segments_[static_cast<size_t>(best)].b)];
        positions_.push_back(A + best_t * (B - A));
        pending_.push_back({static_cast<size_t>(best), g, p});
      } else {
        positions_.push_back(p3);
        steiner.push_back({g, v->point(), is_on_constraint(cdt, v)});
      }
      v->info().id = g;
    }

    if (refine) steiner_[p] = std::move(steiner);
  }

  // The points the mesher added on constrained edges (the outline and the
  // lines), each at its 3-D place: a run of them between two input points
  // lies on the snapped image of the edge between those points, and each
  // goes to the same fraction of the way along the edge itself, so that
  // the outline and lines stay where they are (a midpoint exactly at the
  // middle). Points where constraints cross are left to Frame::to3.
  std::map<CDT::Vertex_handle, Vec3> constrained_positions(CDT& cdt) const {
    auto constrained_neighbours = [&](CDT::Vertex_handle v) {
      std::vector<CDT::Vertex_handle> out;
      auto e = cdt.incident_edges(v), end = e;
      if (e == nullptr) return out;
      do {
        if (cdt.is_constrained(*e)) {
          const CDT::Vertex_handle a = e->first->vertex(CDT::cw(e->second)), b = e->first->vertex(CDT::ccw(e->second));
          out.push_back(a == v ? b : a);
        }
      } while (++e != end);
      return out;
    };
    auto in_run = [&](CDT::Vertex_handle v) { return v->info().id < 0 && constrained_neighbours(v).size() == 2; };
    std::map<CDT::Vertex_handle, Vec3> placed;
    for (auto v = cdt.finite_vertices_begin(); v != cdt.finite_vertices_end(); ++v) {
      if (v->info().id < 0) continue;
      for (CDT::Vertex_handle first : constrained_neighbours(v)) {
        if (cdt.is_infinite(first) || !in_run(first)) continue;
        std::vector<CDT::Vertex_handle> run = {first};
        CDT::Vertex_handle prev = v, cur = first;
        for (;;) {
          const std::vector<CDT::Vertex_handle> nb = constrained_neighbours(cur);
          const CDT::Vertex_handle next = nb[0] == prev ? nb[1] : nb[0];
          prev = cur;
          cur = next;
          if (cdt.is_infinite(cur) || !in_run(cur)) break;
          run.push_back(cur);
        }
        // Each run once, from its end with the smaller id.
        if (cdt.is_infinite(cur) || cur->info().id < 0 || cur->info().id < v->info().id) continue;
        const Vec3 A = positions_[static_cast<size_t>(v->info().id)], B = positions_[static_cast<size_t>(cur->info().id)];
        const double length = std::sqrt(CGAL::squared_distance(v->point(), cur->point()));
        for (CDT::Vertex_handle r : run)
          placed[r] = A + (std::sqrt(CGAL::squared_distance(v->point(), r->point())) / length) * (B - A);
      }
    }
    return placed;
  }

  // Constrained edges with the domain on both sides lie on discontinuity
  // lines; those on contact lines (the value jumps) become feature edges.
  void collect_features(const CDT& cdt, int p, const std::vector<std::pair<K::Segment_2, int>>& lines2,
                        const SegmentsHolding& line_pieces) {
    // The kind of discontinuity line an edge lies on, or -1 for none.
    auto line_kind = [&](const Point2& p0, const Point2& p1) {
      const int i = line_pieces.first_holding(p0, p1);
      return i < 0 ? -1 : lines2[static_cast<size_t>(i)].second;
    };
    auto& features = features_[p];
    features.clear();
    for (auto e = cdt.finite_edges_begin(); e != cdt.finite_edges_end(); ++e) {
      if (!cdt.is_constrained(*e)) continue;
      const CDT::Face_handle f = e->first, g = f->neighbor(e->second);
      if (!f->is_in_domain() || cdt.is_infinite(g) || !g->is_in_domain()) continue;
      const auto [p0, p1] = edge_points(*e);
      if (line_kind(p0, p1) != 0) continue;
      const int a = f->vertex(CDT::cw(e->second))->info().id, b = f->vertex(CDT::ccw(e->second))->info().id;
      features.push_back({std::min(a, b), std::max(a, b)});
    }
  }

  // The triangles inside the patch, by global ids.
  std::vector<std::array<int, 3>> patch_triangles(const CDT& cdt, const Patch& patch) const {
    std::vector<std::array<int, 3>> tris;
    for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
      if (!f->is_in_domain()) continue;
      tris.push_back({f->vertex(0)->info().id, f->vertex(1)->info().id, f->vertex(2)->info().id});
    }
    if (tris.empty()) throw GeometryError(internal::no_triangles_error(scene_, patch, kFarForItsSize));
    return tris;
  }

  // Whether refining the patch would cut an edge or line into more than
  // kNarrowPoints pieces below the separation floor, as it cuts a
  // sliver's long edges about its width apart: a hole narrower than the
  // floor (twice its area over its perimeter) and more than kNarrowPoints
  // times longer, or a vertex nearer than the floor to a constrained edge,
  // more than kNarrowPoints times as far from both its ends, and joined to
  // neither end by a constrained edge (a box standing 1e-5 from a wall:
  // its footprint line beside the floor's edge; joined ones make small
  // angles, which CGAL's mesher handles). Such a vertex is an apex of a
  // triangle on the edge (one lies in the edge's diametral circle
  // whenever any visible vertex does). Refined, the floor's edge along that
  // box would be cut 1e-5 apart (10^5 points to insert in the next round),
  // and a vertex 1e-10 from a thin hole's edge crashes CGAL's
  // mesher; at 1e-3 from the wall the floor is refined (10^3 points along
  // the box).
  static constexpr double kNarrowPoints = 1e4;
  static constexpr double kTinyPiece = 1e-6;  // of the scene's diagonal (see refinable)
  // A patch whose refinement makes more than kDense x the points its size
  // and edges ask for, + kDenseMin, is left as the triangulation of its
  // outline and lines (unless MeshingOptions::refine_narrow_strips): CGAL's
  // mesher cuts two constrained edges running side by side about their gap
  // apart along them, and each element made there takes its own links (a
  // carpet 1 mm above a floor, touching the walls, would take the
  // hierarchical solve past its memory). kDense lies above what ordinary
  // faces make (and lines side by side that CGAL leaves alone: a panel 1 mm
  // from a wall, a partition 1 mm thick) and far below what such strips
  // make (docs/decisions.md).
  static constexpr double kDense = 15.0, kDenseMin = 100.0;
  static constexpr size_t kCollinearRun = 1000;  // see insert_boundary
  // What makes it narrow, or "".
  std::string narrow(const CDT& cdt, const Patch& patch, const Frame& frame, double floor) const {
    for (const auto& h : patch.holes) {
      const std::vector<Vec3> pts = scene_.loop_points(h);
      const double perimeter = loop_length(pts);
      const double width = glm::length(newell_normal(pts)) / perimeter;  // twice the area over the perimeter
      if (width < floor && perimeter > kNarrowPoints * width)
        return "a hole " + format_number(width) + " wide and " + format_number(perimeter) +
               " around (a face lying in it) is narrower than the separation floor " + format_number(floor);
    }
    auto joined = [&](CDT::Vertex_handle v, CDT::Vertex_handle w) {
      CDT::Face_handle f;
      int i = 0;
      return cdt.is_edge(v, w, f, i) && cdt.is_constrained(CDT::Edge(f, i));
    };
    for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f)
      for (int i = 0; i < 3; ++i) {
        if (!cdt.is_constrained(CDT::Edge(f, i))) continue;
        const CDT::Vertex_handle v = f->vertex(i), a = f->vertex(CDT::cw(i)), b = f->vertex(CDT::ccw(i));
        // In 3-D, at the input points' own places (not snapped).
        auto at3 = [&](CDT::Vertex_handle w) {
          return w->info().id >= 0 ? positions_[static_cast<size_t>(w->info().id)] : frame.to3(w->point());
        };
        const Vec3 at = at3(v), A = at3(a), ab = at3(b) - A;
        const double length = glm::length(ab), along = glm::dot(at - A, ab) / length;
        const double off = glm::length(glm::cross(ab, at - A)) / length;
        if (off < floor && std::min(along, length - along) > kNarrowPoints * off && !joined(v, a) && !joined(v, b)) {
          return "a vertex at (" + format_number(at.x) + ", " + format_number(at.y) + ", " + format_number(at.z) +
                 ") lies " + format_number(off) + " from one of its edges or lines, " +
                 format_number(std::min(along, length - along)) + " from that edge's nearer end";
        }
      }
    return "";
  }

  static bool is_on_constraint(CDT& cdt, CDT::Vertex_handle v) {
    auto e = cdt.incident_edges(v), end = e;
    if (e == nullptr) return false;
    do {
      if (cdt.is_constrained(*e)) return true;
    } while (++e != end);
    return false;
  }

  MeshingOptions opt_;
  bool refine_ = true;
  std::set<int> dense_;  // patches refinement made too dense (kDense): unrefined in later rounds
  struct Pending {
    size_t segment;
    int vertex;
    int patch;  // the patch whose mesher created it
  };
  std::vector<Pending> pending_;
  std::map<int, int> alias_;  // duplicate boundary point -> the one kept
  std::map<size_t, std::vector<std::array<int, 3>>> constraints_;  // per patch: (a, b, kind) line pieces
  std::map<int, std::vector<std::array<int, 2>>> features_;  // per patch: discontinuity edges
  int contact_count_ = 0, shadow_count_ = 0, crossings_ = 0;
  std::map<int, int> rounding_crossings_;
  double point_budget_ = 0.0;  // points the mesher may add to the patch being meshed
  std::set<int> thin_;         // patches too thin to refine (refinable, refine_patch)
  std::vector<std::string> warnings_;  // MeshReport::warnings
  struct Steiner {
    int id;
    Point2 q;
    bool on_line;  // on a discontinuity line
  };
  std::map<int, std::vector<Steiner>> steiner_;  // per patch: interior points of its last refinement
  ShadowReport shadow_report_;
  std::vector<DiscontinuitySegment> discontinuities_;
};

}  // namespace

Mesh mesh_scene(const Scene& scene, const MeshingOptions& options, MeshReport* report) {
  const MeshingOptions opt = resolve_meshing_options(scene, options);
  SceneMesher mesher(scene, opt, true);
  Mesh mesh = mesher.run(report);
  refuse_coplanar_overlaps(scene, mesh);
  return mesh;
}

Mesh triangulate_patches(const Scene& scene) {
  SceneMesher mesher(scene, MeshingOptions{}, false);
  return mesher.run(nullptr);
}

}  // namespace radmesh
