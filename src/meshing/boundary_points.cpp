// The scene mesher's bookkeeping that needs no CGAL (see boundary_points.h):
// the patches' boundary segments and the global points on them, the ids of
// discontinuity line ends, the compaction of the finished mesh and the
// messages of faces left unrefined. Compiled without CGAL's flags: plain
// double arithmetic in round-to-nearest, as in the mesher's own file.

#include "meshing/boundary_points.h"

#include "radmesh/errors.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace radmesh::internal {

BoundaryPoints::BoundaryPoints(const Scene& scene) : scene_(scene) {
  positions_ = scene.vertices;
  diagonal_ = std::max(scene.diagonal(), std::numeric_limits<double>::min());
  eps_ = 1e-9 * diagonal_;
  near_ = 100.0 * eps_;
  collect_segments();
}

void BoundaryPoints::collect_segments() {
  patch_segments_.assign(1, 0);
  for (int p = 0; p < static_cast<int>(scene_.patches.size()); ++p) {
    const Patch& patch = scene_.patches[static_cast<size_t>(p)];
    auto add_loop = [&](const std::vector<int>& loop) {
      for (size_t i = 0; i < loop.size(); ++i) segments_.push_back({p, loop[i], loop[(i + 1) % loop.size()]});
    };
    add_loop(patch.outer);
    for (const auto& h : patch.holes) add_loop(h);
    patch_segments_.push_back(static_cast<int>(segments_.size()));
  }
  seg_points_.resize(segments_.size());
  overlaps_.resize(segments_.size());
}

void BoundaryPoints::find_overlaps() {
  const size_t n = segments_.size();
  std::vector<Vec3> lo(n), hi(n);
  for (size_t s = 0; s < n; ++s) {
    const Vec3 A = positions_[static_cast<size_t>(segments_[s].a)];
    const Vec3 B = positions_[static_cast<size_t>(segments_[s].b)];
    lo[s] = glm::min(A, B) - Vec3(eps_);
    hi[s] = glm::max(A, B) + Vec3(eps_);
  }
  std::vector<Box3> boxes(n);
  for (size_t s = 0; s < n; ++s) {
    boxes[s].lo = lo[s];
    boxes[s].hi = hi[s];
  }
  const BoxTree tree(boxes);
  std::vector<int> near;
  for (size_t s = 0; s < n; ++s) {
    near.clear();
    tree.overlapping(boxes[s], 0.0, [&](int r) {
      if (static_cast<size_t>(r) > s) near.push_back(r);
      return true;
    });
    std::sort(near.begin(), near.end());
    for (int ri : near) {
      const size_t r = static_cast<size_t>(ri);
      double ta, tb;
      if (!on_line(s, positions_[static_cast<size_t>(segments_[r].a)], &ta) ||
          !on_line(s, positions_[static_cast<size_t>(segments_[r].b)], &tb))
        continue;
      const double len = glm::length(positions_[static_cast<size_t>(segments_[s].b)] -
                                     positions_[static_cast<size_t>(segments_[s].a)]);
      const double overlap = std::min(1.0, std::max(ta, tb)) - std::max(0.0, std::min(ta, tb));
      if (overlap * len <= eps_) continue;
      overlaps_[s].push_back(static_cast<int>(r));
      overlaps_[r].push_back(static_cast<int>(s));
    }
  }
}

int BoundaryPoints::find_point(size_t s, const Vec3& p) const {
  auto near = [&](int g) { return glm::length(positions_[static_cast<size_t>(g)] - p) <= eps_; };
  if (near(segments_[s].a)) return segments_[s].a;
  if (near(segments_[s].b)) return segments_[s].b;
  double t;
  on_line(s, p, &t);
  const uint64_t c = cell_key(s, t), first = cell_key(s, 0.0);
  for (uint64_t k = std::max(c, first + 1) - 1; k <= c + 1; ++k) {
    const auto [from, to] = seg_cells_.equal_range(k);
    for (auto it = from; it != to; ++it)
      if (near(it->second)) return it->second;
  }
  return -1;
}

// The points of segment s by cells of 2 eps_ along it (seg_cells_): a point
// within eps_ of p lies in p's cell or a neighbour, where a scan of the
// segment's list for every point added would be quadratic in the points on
// one edge (10^5 where a narrow gap runs along it, see the mesher's narrow()).
uint64_t BoundaryPoints::cell_key(size_t s, double t) const {
  const double len = glm::length(positions_[static_cast<size_t>(segments_[s].b)] -
                                 positions_[static_cast<size_t>(segments_[s].a)]);
  const double cell = std::clamp(std::floor(t * len / (2.0 * eps_)), 0.0, 4e9);
  return (static_cast<uint64_t>(s) << 32) + static_cast<uint64_t>(cell);
}

void BoundaryPoints::add_point(size_t s, int g, std::vector<int>* touched) {
  auto put = [&](size_t seg) {
    double t;
    if (!strictly_inside(seg, positions_[static_cast<size_t>(g)], &t)) return;
    const uint64_t key = cell_key(seg, t);
    const auto [from, to] = seg_cells_.equal_range(key);
    for (auto it = from; it != to; ++it)
      if (it->second == g) return;
    seg_cells_.emplace(key, g);
    seg_points_[seg].push_back(g);
    if (touched) touched->push_back(segments_[seg].patch);
  };
  put(s);
  for (int r : overlaps_[s]) put(static_cast<size_t>(r));
}

void BoundaryPoints::seed_points(double max_edge) {
  for (size_t s = 0; s < segments_.size(); ++s) {
    for (int r : overlaps_[s]) {
      add_point(s, segments_[static_cast<size_t>(r)].a, nullptr);
      add_point(s, segments_[static_cast<size_t>(r)].b, nullptr);
    }
  }
  // Vertices of non-collinear patches touching a segment's interior.
  std::vector<Box3> points(scene_.vertices.size());
  for (size_t v = 0; v < points.size(); ++v) points[v].add(scene_.vertices[v]);
  const BoxTree vertex_tree(points);
  std::vector<int> near;
  for (size_t s = 0; s < segments_.size(); ++s) {
    const Vec3 A = positions_[static_cast<size_t>(segments_[s].a)];
    const Vec3 B = positions_[static_cast<size_t>(segments_[s].b)];
    Box3 box;
    box.add(A);
    box.add(B);
    near.clear();
    vertex_tree.overlapping(box, eps_, [&](int v) {
      near.push_back(v);
      return true;
    });
    std::sort(near.begin(), near.end());  // in vertex order, as a scan would find them
    for (int v : near) add_point(s, v, nullptr);
  }
  // Even pre-split of every segment to the maximum edge length; points are
  // created once per distinct segment (shared by the segments overlapping it
  // through add_point).
  std::map<std::pair<int, int>, bool> done;
  for (size_t s = 0; s < segments_.size(); ++s) {
    const int a = segments_[s].a, b = segments_[s].b;
    if (done.count({std::min(a, b), std::max(a, b)})) continue;
    done[{std::min(a, b), std::max(a, b)}] = true;
    const Vec3 A = positions_[static_cast<size_t>(std::min(a, b))];
    const Vec3 B = positions_[static_cast<size_t>(std::max(a, b))];
    // Existing points on the segment split it already; pre-split each gap.
    std::vector<double> ts = {0.0, 1.0};
    for (int g : seg_points_[s]) {
      double t;
      on_line(s, positions_[static_cast<size_t>(g)], &t);
      ts.push_back(a < b ? t : 1.0 - t);
    }
    std::sort(ts.begin(), ts.end());
    const double len = glm::length(B - A);
    for (size_t i = 0; i + 1 < ts.size(); ++i) {
      const double gap = (ts[i + 1] - ts[i]) * len;
      const int parts = static_cast<int>(std::ceil(gap / max_edge - 1e-9));
      for (int k = 1; k < parts; ++k) {
        const double t = ts[i] + (ts[i + 1] - ts[i]) * k / parts;
        const int g = static_cast<int>(positions_.size());
        positions_.push_back(A + t * (B - A));
        add_point(s, g, nullptr);
      }
    }
  }
}

namespace {

std::vector<Box3> vertex_boxes(const std::vector<Vec3>& positions, size_t scene_vertices) {
  std::vector<Box3> boxes(scene_vertices);
  for (size_t v = 0; v < boxes.size(); ++v) boxes[v].add(positions[v]);
  return boxes;
}

}  // namespace

LinePoints::LinePoints(std::vector<Vec3>& positions, size_t scene_vertices, double eps, double near)
    : positions_(positions), eps_(eps), near_(near) {
  const std::vector<Box3> boxes = vertex_boxes(positions, scene_vertices);
  vertex_tree_ = BoxTree(boxes);
  // Cells counted from the scene's lowest corner (a scene far from the
  // origin would overflow the cell numbers otherwise), clamped all the same.
  cell_ = 4.0 * eps_;
  Box3 bounds;
  for (const Box3& b : boxes) bounds.add(b);
  origin_ = bounds.empty() ? Vec3(0.0) : bounds.lo;
}

std::array<long long, 3> LinePoints::cell_of(const Vec3& p) const {
  const double cell = cell_;
  const Vec3 origin = origin_;
  auto index = [cell](double x) { return static_cast<long long>(std::clamp(std::floor(x / cell), -1e18, 1e18)); };
  return std::array<long long, 3>{index(p.x - origin.x), index(p.y - origin.y), index(p.z - origin.z)};
}

int LinePoints::own_corner(const Vec3& p, const std::vector<int>& own) const {
  Box3 at;
  at.add(p);
  int best = -1;
  double best_d = near_;
  vertex_tree_.overlapping(at, near_, [&](int v) {
    const double d = glm::length(positions_[static_cast<size_t>(v)] - p);
    if (std::binary_search(own.begin(), own.end(), v) && (d < best_d || (d == best_d && v < best))) {
      best = v;
      best_d = d;
    }
    return true;
  });
  return best;
}

int LinePoints::id_of(const Vec3& p) {
  Box3 at;
  at.add(p);
  int best = -1;
  vertex_tree_.overlapping(at, eps_, [&](int v) {
    if (glm::length(positions_[static_cast<size_t>(v)] - p) <= eps_ && (best < 0 || v < best)) best = v;
    return true;
  });
  if (best >= 0) return best;
  const auto c = cell_of(p);
  for (long long dx = -1; dx <= 1; ++dx)
    for (long long dy = -1; dy <= 1; ++dy)
      for (long long dz = -1; dz <= 1; ++dz) {
        const auto it = extra_.find({c[0] + dx, c[1] + dy, c[2] + dz});
        if (it == extra_.end()) continue;
        for (int g : it->second)
          if (glm::length(positions_[static_cast<size_t>(g)] - p) <= eps_ && (best < 0 || g < best)) best = g;
      }
  if (best >= 0) return best;
  const int g = static_cast<int>(positions_.size());
  positions_.push_back(p);
  extra_[c].push_back(g);
  return g;
}

void compact(Mesh& mesh) {
  std::vector<int> remap(mesh.positions.size(), -1);
  std::vector<Vec3> pos;
  for (auto& t : mesh.triangles)
    for (int& v : t) {
      if (remap[static_cast<size_t>(v)] < 0) {
        remap[static_cast<size_t>(v)] = static_cast<int>(pos.size());
        pos.push_back(mesh.positions[static_cast<size_t>(v)]);
      }
      v = remap[static_cast<size_t>(v)];
    }
  for (auto& e : mesh.feature_edges) {
    for (int& v : e) v = remap[static_cast<size_t>(v)];
    if (e[0] > e[1]) std::swap(e[0], e[1]);
  }
  mesh.positions = std::move(pos);
}

std::string dense_warning(const Patch& patch, double h, double dense, double k_dense, double asked,
                          double k_dense_min) {
  return where(patch.file, patch.line) + "face '" + patch.name + "': refining it to --max-edge " +
         format_number(h) + " made more than " + format_number(std::floor(dense)) + " points (" +
         format_number(k_dense) + " x the " + format_number(std::ceil(asked)) +
         " its size and edges ask for, + " + format_number(k_dense_min) +
         "): edges or lines on it run side by side far closer than --max-edge (a carpet's edge 1 "
         "mm up a wall), and it was cut about as finely along them: left as the triangulation of its "
         "outline and lines (the hierarchical method still splits it where its links ask)";
}

std::string budget_error(const Patch& patch, double h, double budget, double point_budget, double asked,
                         double max_elements) {
  std::ostringstream m;
  m << where(patch.file, patch.line) << "face '" << patch.name << "': refining its mesh to max_edge "
    << format_number(h) << " takes more than " << format_number(std::max(0.0, std::floor(budget)))
    << " points"
    << (budget < point_budget ? " (1000 x the " + format_number(std::ceil(asked)) +
                                    " its size and edges ask for, + 100000)"
                              : " (what the other faces leave of " + format_number(max_elements) +
                                    " elements in all)")
    << ": lines, edges or vertices on it lie much closer together than the edge length (a sliver face, "
       "near-coincident faces or shadow lines); check the geometry near it, or try discontinuity "
       "contacts or off";
  return m.str();
}

std::string no_triangles_error(const Scene& scene, const Patch& patch, double far_for_its_size) {
  std::ostringstream m;
  m << where(patch.file, patch.line) << "face '" << patch.name
    << "': triangulation produced no triangles (self-intersecting outline?)";
  // Far from the origin for its size, double precision is the likelier
  // cause (the Cornell box moved 1e12 away fails here).
  Box3 box;
  for (const Vec3& q : scene.loop_points(patch.outer)) box.add(q);
  const double size = glm::length(box.hi - box.lo), far = glm::length(0.5 * (box.lo + box.hi));
  if (far > far_for_its_size * size)
    m << "; it lies " << format_number(far) << " from the origin, " << format_number(far / size)
      << " times its size, where double precision resolves its geometry to only " << format_number(far * 1e-16 / size)
      << " of its size: move the scene nearer the origin";
  return m.str();
}

}  // namespace radmesh::internal
