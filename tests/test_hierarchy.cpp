// The element hierarchy and its zero-area closure: the leaves with their
// zero-area fans form a conforming mesh (checked with CGAL's Surface_mesh),
// splits stay exact at depth, and the conventional closure leaves no T-vertex.

#include "radmesh/obj_reader.h"
#include "radmesh/hierarchy.h"
#include "radmesh/mesh.h"
#include "tests/test_util.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>

#include <gtest/gtest.h>

#include <array>

#include <cmath>
#include <map>

using namespace radmesh;

namespace {
using radmesh::test::kData;
using SurfaceMesh = CGAL::Surface_mesh<CGAL::Exact_predicates_inexact_constructions_kernel::Point_3>;

std::pair<int, int> key(int a, int b) { return {std::min(a, b), std::max(a, b)}; }

// Splits, in each of `rounds` rounds, the leaves whose centroid is nearest
// to a moving point (a quarter of them) and every leaf touching a contact
// line: uneven refinement with many T-vertices, deterministic.
void refine(ElementTree& tree, const Mesh& mesh, int rounds) {
  std::map<std::pair<int, int>, bool> feature;
  for (const auto& e : mesh.feature_edges) feature[key(e[0], e[1])] = true;
  for (int r = 0; r < rounds; ++r) {
    const std::vector<int> leaves = tree.leaves();
    for (size_t i = 0; i < leaves.size(); ++i) {
      const int n = leaves[i];
      const auto& v = tree.node(n).v;
      bool on_feature = false;
      for (int k = 0; k < 3; ++k) on_feature = on_feature || feature.count(key(v[static_cast<size_t>(k)], v[static_cast<size_t>((k + 1) % 3)]));
      if (on_feature || (i * 7 + static_cast<size_t>(r)) % 4 == 0) tree.split(n);
    }
  }
}

// Checks the conforming property of `out` against the initial mesh:
// every edge of the output lies inside a root (then it has exactly two
// triangles) or on an initial edge (then as many as that edge had).
void check_conforming(const ElementTree& tree, const Mesh& initial, const Mesh& out, const std::string& what) {
  std::map<std::pair<int, int>, int> initial_count, expected, count;
  for (const auto& t : initial.triangles)
    for (int k = 0; k < 3; ++k) ++initial_count[key(t[static_cast<size_t>(k)], t[static_cast<size_t>((k + 1) % 3)])];
  for (const auto& [e, c] : initial_count) {
    int prev = e.first;
    for (int m : tree.edge_points(e.first, e.second, -1)) {
      expected[key(prev, m)] = c;
      prev = m;
    }
    expected[key(prev, e.second)] = c;
  }
  for (const auto& t : out.triangles)
    for (int k = 0; k < 3; ++k) ++count[key(t[static_cast<size_t>(k)], t[static_cast<size_t>((k + 1) % 3)])];
  int bad = 0;
  for (const auto& [e, c] : count) {
    const auto it = expected.find(e);
    const int want = it == expected.end() ? 2 : it->second;
    if (c != want) ++bad;
  }
  EXPECT_EQ(bad, 0) << what;

  // Per patch, with CGAL: every triangle (zero-area ones too) goes into a
  // Surface_mesh without breaking manifoldness, the result is valid, and its
  // border is exactly the patch's boundary cut at the split points.
  std::map<int, std::vector<int>> by_patch;
  for (int t = 0; t < out.triangle_count(); ++t) by_patch[out.patch[static_cast<size_t>(t)]].push_back(t);
  std::map<int, int> boundary_pieces;
  std::map<std::pair<int, int>, std::vector<int>> initial_patch_edges;
  for (int t = 0; t < initial.triangle_count(); ++t)
    for (int k = 0; k < 3; ++k) {
      const auto& tri = initial.triangles[static_cast<size_t>(t)];
      initial_patch_edges[key(tri[static_cast<size_t>(k)], tri[static_cast<size_t>((k + 1) % 3)])].push_back(initial.patch[static_cast<size_t>(t)]);
    }
  for (const auto& [e, patches] : initial_patch_edges)
    for (int p : patches)
      if (std::count(patches.begin(), patches.end(), p) == 1)
        boundary_pieces[p] += static_cast<int>(tree.edge_points(e.first, e.second, -1).size()) + 1;
  for (const auto& [p, tris] : by_patch) {
    SurfaceMesh sm;
    std::map<int, SurfaceMesh::Vertex_index> vid;
    auto vertex = [&](int g) {
      auto it = vid.find(g);
      if (it != vid.end()) return it->second;
      const Vec3& x = out.positions[static_cast<size_t>(g)];
      return vid[g] = sm.add_vertex({x.x, x.y, x.z});
    };
    int refused = 0;
    for (int t : tris) {
      const auto& tri = out.triangles[static_cast<size_t>(t)];
      if (sm.add_face(vertex(tri[0]), vertex(tri[1]), vertex(tri[2])) == SurfaceMesh::null_face()) ++refused;
    }
    EXPECT_EQ(refused, 0) << what << ", patch " << p;
    EXPECT_TRUE(sm.is_valid(false)) << what << ", patch " << p;
    int border = 0;
    for (auto h : sm.halfedges()) border += sm.is_border(h) ? 1 : 0;
    EXPECT_EQ(border, boundary_pieces[p]) << what << ", patch " << p;
  }
}
}  // namespace

TEST(Hierarchy, LeavesWithZeroAreaFansConformOnEveryBundledScene) {
  for (const char* name : {"cornell_box/cornell_box.obj", "box_on_floor/box_on_floor.obj",
                           "furnace_cube/furnace_cube.obj", "parallel_plates/parallel_plates.obj"}) {
    const Scene s = read_obj_scene(kData + "/" + name);
    MeshingOptions o;
    o.discontinuity = DiscontinuityMode::full;
    const Mesh initial = mesh_scene(s, o);
    for (int rounds : {1, 3, 6}) {
      ElementTree tree(initial);
      refine(tree, initial, rounds);
      std::vector<int> leaf_of;
      const Mesh out = tree.conforming_mesh(&leaf_of);
      const std::string what = std::string(name) + " after " + std::to_string(rounds) + " rounds";
      check_conforming(tree, initial, out, what);
      // Zero-area triangles have no area; the leaves keep every patch's area.
      int zero = 0;
      std::vector<double> area(s.patches.size(), 0.0);
      const double scale = s.diagonal() * s.diagonal();
      for (int t = 0; t < out.triangle_count(); ++t) {
        if (leaf_of[static_cast<size_t>(t)] < 0) {
          ++zero;
          EXPECT_LE(out.area(t), 1e-14 * scale) << what;
        } else {
          area[static_cast<size_t>(out.patch[static_cast<size_t>(t)])] += out.area(t);
        }
      }
      EXPECT_GT(zero, 0) << what;  // the uneven refinement left T-vertices
      for (size_t p = 0; p < s.patches.size(); ++p)
        EXPECT_NEAR(area[p], s.patch_area(static_cast<int>(p)), 1e-9 * s.patch_area(static_cast<int>(p))) << what;
    }
  }
}

TEST(Hierarchy, SplittingNeighboursLeavesNoTVertex) {
  const Scene s = read_obj_scene(kData + "/box_on_floor/box_on_floor.obj");
  const Mesh initial = mesh_scene(s, {});
  ElementTree tree(initial);
  refine(tree, initial, 3);
  const int leaves_before = static_cast<int>(tree.leaves().size());
  const int splits = tree.split_until_conforming();
  EXPECT_GT(splits, 0);
  EXPECT_EQ(static_cast<int>(tree.leaves().size()), leaves_before + 3 * splits);
  std::vector<int> leaf_of;
  const Mesh out = tree.conforming_mesh(&leaf_of);
  for (int l : leaf_of) EXPECT_GE(l, 0);  // no zero-area triangle needed
  check_conforming(tree, initial, out, "split closure");
}

TEST(Hierarchy, ALevelTwelveSplitStillHasExactMidpoints) {
  Mesh m;
  m.positions = {{0.1, 0.2, 0.3}, {1.7, 0.25, -0.4}, {0.3, 1.9, 0.8}};
  m.triangles = {{0, 1, 2}};
  m.patch = {0};
  ElementTree tree(m);
  // The same path followed independently: each child's corners as averages
  // of its parent's, in long double (ElementTree's children 0..2 sit at the
  // corners, 3 is the middle one).
  using P = std::array<long double, 3>;
  auto mid = [](const P& x, const P& y) { return P{(x[0] + y[0]) / 2, (x[1] + y[1]) / 2, (x[2] + y[2]) / 2}; };
  std::array<P, 3> path;
  for (int k = 0; k < 3; ++k)
    path[static_cast<size_t>(k)] = {m.positions[static_cast<size_t>(k)].x, m.positions[static_cast<size_t>(k)].y,
                                    m.positions[static_cast<size_t>(k)].z};
  int n = 0;
  for (int level = 0; level < 12; ++level) {
    const int child = level % 2 == 0 ? 3 : 1;  // middle, then corner
    n = tree.split(n) + child;
    const P ab = mid(path[0], path[1]), bc = mid(path[1], path[2]), ca = mid(path[2], path[0]);
    path = child == 3 ? std::array<P, 3>{bc, ca, ab} : std::array<P, 3>{ab, path[1], bc};
  }
  ASSERT_EQ(tree.node(n).level, 12);
  const auto& v = tree.node(n).v;
  const auto& pv = tree.node(tree.node(n).parent).v;
  const double step = std::ldexp(1.0, -12);
  for (int id : v) {
    const auto b = tree.barycentric(0, id);
    for (double c : b) EXPECT_EQ(std::fmod(c, step), 0.0) << "not a multiple of 2^-12";
  }
  // Each corner of the level-12 node is exactly the average of two of its
  // parent's corners, in the root's barycentric coordinates.
  for (int id : v) {
    const auto b = tree.barycentric(0, id);
    bool found = false;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j <= i; ++j) {
        const auto bi = tree.barycentric(0, pv[static_cast<size_t>(i)]), bj = tree.barycentric(0, pv[static_cast<size_t>(j)]);
        found = found || (b[0] == 0.5 * (bi[0] + bj[0]) && b[1] == 0.5 * (bi[1] + bj[1]));
      }
    EXPECT_TRUE(found);
  }
  // And each corner is where twelve halvings in long double put it, to the
  // rounding of one double evaluation (coordinates are below 2).
  for (int k = 0; k < 3; ++k) {
    const Vec3& x = tree.positions()[static_cast<size_t>(v[static_cast<size_t>(k)])];
    const P& e = path[static_cast<size_t>(k)];
    for (int c = 0; c < 3; ++c)
      EXPECT_LE(std::abs(static_cast<long double>(x[c]) - e[static_cast<size_t>(c)]), 8e-16L) << "corner " << k;
  }
  // The node's area is 4^-12 of the root's.
  EXPECT_NEAR(tree.area(n) / tree.area(0), std::ldexp(1.0, -24), 1e-12 * std::ldexp(1.0, -24));
}
