// The scene mesher's bookkeeping that needs no CGAL (the mesher itself is
// mesher_cgal.cpp, kept the only CGAL translation unit of meshing): every
// patch's boundary segments and the global points on each (scene vertices
// lying on it, the even pre-split, points the mesher adds) shared by every
// segment overlapping it, so that patches along a common edge split it at the
// same points; the global ids of discontinuity line ends and crossings; the
// compaction of the finished mesh; and the messages of faces left unrefined.
// Internal to the meshing module.

#pragma once

#include "core/box_tree.h"
#include "radmesh/mesh.h"

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

namespace radmesh::internal {

// One directed boundary segment of a patch loop, between global vertex ids.
struct Segment {
  int patch;
  int a, b;
};

// The boundary segments of every patch and the global points on them; the
// base of the mesher (SceneMesher in mesher_cgal.cpp), which shares its
// members.
class BoundaryPoints {
protected:
  // The scene's vertices as the first global points, the tolerances from
  // its size, and every patch's segments (collect_segments).
  explicit BoundaryPoints(const Scene& scene);

  void collect_segments();

  // Parameter of p along segment s, and whether p lies on its line.
  bool on_line(size_t s, const Vec3& p, double* t) const {
    const Vec3 A = positions_[static_cast<size_t>(segments_[s].a)];
    const Vec3 B = positions_[static_cast<size_t>(segments_[s].b)];
    const Vec3 d = B - A;
    const double len2 = glm::dot(d, d);
    *t = glm::dot(p - A, d) / len2;
    const Vec3 foot = A + *t * d;
    return glm::length(p - foot) <= eps_;
  }
  bool strictly_inside(size_t s, const Vec3& p, double* t) const {
    if (!on_line(s, p, t)) return false;
    const double len = glm::length(positions_[static_cast<size_t>(segments_[s].b)] -
                                   positions_[static_cast<size_t>(segments_[s].a)]);
    const double tol = eps_ / len;
    return *t > tol && *t < 1.0 - tol;
  }

  // Segments on a common line whose parameter ranges overlap (positive length).
  void find_overlaps();

  // A point of segment s (endpoints included) within eps of p, or -1.
  int find_point(size_t s, const Vec3& p) const;
  // The cell of 2 eps_ along segment s holding parameter t (seg_cells_).
  uint64_t cell_key(size_t s, double t) const;

  // Adds global point id g to segment s (and to every segment overlapping s
  // that contains it). Records the patches whose boundary gained the point.
  void add_point(size_t s, int g, std::vector<int>* touched);

  // Scene vertices on segments (T-junctions), then the even pre-split to
  // max_edge.
  void seed_points(double max_edge);

  const Scene& scene_;
  double diagonal_ = 0.0;  // the scene's
  double eps_ = 0.0;
  // Closer than this, a line end is the point there, and a point is on a
  // line: the mesher would otherwise split towards it without end.
  double near_ = 0.0;
  std::vector<Vec3> positions_;
  std::vector<Segment> segments_;
  std::vector<int> patch_segments_;  // patch p's segments: [patch_segments_[p], patch_segments_[p + 1])
  std::vector<std::vector<int>> seg_points_;
  std::unordered_multimap<uint64_t, int> seg_cells_;  // (segment << 32) + cell of 2 eps_ -> its points (cell_key)
  std::vector<std::vector<int>> overlaps_;
};

// The global ids of discontinuity line ends and crossings. A point is the
// first scene vertex within eps of it, else the first point made so far
// within eps, else a new one (appended to `positions`); scene vertices are
// found through a box tree and the points made in cells of 4 eps, since a
// scan over both for every point is quadratic on a scene of many lines.
class LinePoints {
public:
  // The first `scene_vertices` of `positions` are the scene's vertices.
  LinePoints(std::vector<Vec3>& positions, size_t scene_vertices, double eps, double near);

  // The nearest of `own` (sorted scene vertex ids) within `near` of p, or -1.
  int own_corner(const Vec3& p, const std::vector<int>& own) const;
  // The id of the point at p (see the class).
  int id_of(const Vec3& p);

private:
  std::array<long long, 3> cell_of(const Vec3& p) const;

  std::vector<Vec3>& positions_;
  double eps_, near_;
  double cell_;  // 4 eps
  Vec3 origin_;  // the scene's lowest corner, where the cells are counted from
  BoxTree vertex_tree_;
  std::map<std::array<long long, 3>, std::vector<int>> extra_;  // points made so far, by cell
};

// Drops positions no triangle uses (points of a previous round that a
// re-meshed patch no longer has) and renumbers.
void compact(Mesh& mesh);

// The warning for a patch whose refinement made more than `dense` points
// (kDense x the `asked` its size and edges ask for, + kDenseMin) at edge
// length h.
std::string dense_warning(const Patch& patch, double h, double dense, double k_dense, double asked,
                          double k_dense_min);

// The error for a patch whose refinement passed its point budget.
std::string budget_error(const Patch& patch, double h, double budget, double point_budget, double asked,
                         double max_elements);

// The error for a patch whose triangulation has no triangle, with a hint
// where the patch lies far from the origin for its size.
std::string no_triangles_error(const Scene& scene, const Patch& patch, double far_for_its_size);

}  // namespace radmesh::internal
