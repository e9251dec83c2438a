// Hierarchical radiosity: closed forms, energy balance, agreement with the
// full-matrix solve, determinism and stress.

#include "radmesh/obj_reader.h"
#include "radmesh/summary.h"
#include "radmesh/errors.h"
#include "radmesh/scene.h"
#include "radmesh/mesh.h"
#include "radmesh/field.h"
#include "radmesh/form_factor.h"
#include "radmesh/hierarchical.h"
#include "radmesh/solve.h"

#include <gtest/gtest.h>

#include "tests/test_util.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <thread>

using namespace radmesh;

namespace {
using radmesh::test::kData;

constexpr double kMiB = 1024.0 * 1024.0, kGiB = 1024.0 * kMiB;

Mesh coarse_mesh(const Scene& s, double edge, DiscontinuityMode mode = DiscontinuityMode::contacts) {
  MeshingOptions o;
  o.max_edge = edge;
  o.discontinuity = mode;
  return mesh_scene(s, o);
}

double relative_imbalance(const SolveStats& st) {
  return (st.power_emitted.x - st.power_absorbed.x - st.power_escaped.x) / st.power_emitted.x;
}
}  // namespace

TEST(Hierarchical, FurnaceIsUniform) {
  const Scene s = read_obj_scene(kData + "/furnace_cube/furnace_cube.obj");
  const Mesh m = coarse_mesh(s, 0.5);
  HierarchicalOptions ho;
  ho.epsilon = 0.02;
  ho.min_area = 2e-3;  // a few thousand leaves: the property does not depend on depth
  const HierarchicalSolution h = solve_hierarchical(s, m, {}, ho);
  const Material& mat = s.material_of(0);
  const double expected = mat.emission.x / (1.0 - mat.reflectance.x);
  double lo = 1e300, hi = 0.0, area = 0.0, mean = 0.0;
  for (size_t t = 0; t < h.solution.element.size(); ++t) {
    const double b = h.solution.element[t].x, a = h.mesh.area(static_cast<int>(t));
    lo = std::min(lo, b);
    hi = std::max(hi, b);
    mean += a * b;
    area += a;
  }
  mean /= area;
  std::printf("[hierarchical] furnace: %d leaves, %lld links, %d rounds; B in [%.4f, %.4f], area mean %.5f (exact %.1f); rows [%.4f, %.4f]\n",
              h.stats.leaves, h.stats.links, h.stats.rounds, lo, hi, mean, expected, h.stats.row_sum_min, h.stats.row_sum_max);
  // Each leaf gathers at its own points from sources that cover the closed
  // cube once: every row sums to 1, so B = E / (1 - rho) at every leaf.
  EXPECT_NEAR(lo, expected, 1e-5 * expected);
  EXPECT_NEAR(hi, expected, 1e-5 * expected);
  EXPECT_NEAR(h.stats.row_sum_min, 1.0, 1e-9);
  EXPECT_NEAR(h.stats.row_sum_max, 1.0, 1e-9);
  EXPECT_GT(h.stats.links, 0);
  EXPECT_GT(h.stats.rounds, 1);
}

TEST(Hierarchical, AreaWeightLinksSmallReceiversMoreCoarselyAndKeepsFurnaceAndBalance) {
  // The oracle's error weighted by (receiver area / mean root area)^1 below
  // the mean root: fewer links where receivers are small, and nothing that
  // physics fixes may move: the furnace stays E / (1 - rho) at every leaf
  // (rows sum to 1 whatever the links), and an open scene's power balances.
  HierarchicalOptions weighted;
  weighted.area_weight = 1.0;
  {
    const Scene s = read_obj_scene(kData + "/furnace_cube/furnace_cube.obj");
    const Mesh m = coarse_mesh(s, 0.5);
    HierarchicalOptions ho = weighted;
    ho.epsilon = 0.02;
    ho.min_area = 2e-3;
    const HierarchicalSolution h = solve_hierarchical(s, m, {}, ho);
    const Material& mat = s.material_of(0);
    const double expected = mat.emission.x / (1.0 - mat.reflectance.x);
    for (const Rgb& b : h.solution.element) EXPECT_NEAR(b.x, expected, 1e-5 * expected);
  }
  const Scene s = read_obj_scene(kData + "/box_on_floor/box_on_floor.obj");
  const Mesh m = coarse_mesh(s, 1.0);
  const HierarchicalSolution plain = solve_hierarchical(s, m, {}, {});
  const HierarchicalSolution h = solve_hierarchical(s, m, {}, weighted);
  std::printf("[hierarchical] area weight 1: %lld links, %d leaves; 0: %lld links, %d leaves\n", h.stats.links,
              h.stats.leaves, plain.stats.links, plain.stats.leaves);
  EXPECT_LT(h.stats.links, plain.stats.links);
  EXPECT_LT(std::abs(relative_imbalance(h.solution.stats)), 1e-4);
  HierarchicalOptions bad;
  bad.area_weight = 3.0;
  EXPECT_THROW(solve_hierarchical(s, m, {}, bad), InputError);
}

TEST(Hierarchical, InputTrianglesBelowTheLinkFloorAreLinkedByTheirShareOfIt) {
  // A receiver smaller than min_area weighs its oracle error by its share
  // of it. The box on the floor meshed at the floor's size and 16 times
  // finer: without the weight every root took as many links as one at the
  // floor (35.8 against 35.9 per root), with it fewer than half as many
  // (14.7 against 33.5); the energy still balances, and a furnace meshed
  // below the floor stays E / (1 - rho) at every leaf (rows sum to 1
  // whatever the links).
  HierarchicalOptions ho;
  ho.min_area = 0.1;
  const Scene s = read_obj_scene(kData + "/box_on_floor/box_on_floor.obj");
  const Mesh at_floor = coarse_mesh(s, 0.5, DiscontinuityMode::off);
  const Mesh finer = coarse_mesh(s, 0.125, DiscontinuityMode::off);
  ASSERT_GT(finer.triangle_count(), 12 * at_floor.triangle_count());
  const HierarchicalSolution a = solve_hierarchical(s, at_floor, {}, ho);
  const HierarchicalSolution b = solve_hierarchical(s, finer, {}, ho);
  const double per_root_a = static_cast<double>(a.stats.links) / at_floor.triangle_count();
  const double per_root_b = static_cast<double>(b.stats.links) / finer.triangle_count();
  std::printf("[hierarchical] links per root: %.1f at the floor, %.1f 16 x finer\n", per_root_a, per_root_b);
  EXPECT_LT(per_root_b, 0.5 * per_root_a);
  EXPECT_LT(std::abs(relative_imbalance(b.solution.stats)), 1e-4);
  const Scene f = read_obj_scene(kData + "/furnace_cube/furnace_cube.obj");
  const Mesh m = coarse_mesh(f, 0.25);
  HierarchicalOptions hf;
  hf.min_area = 0.2;  // above every root
  const HierarchicalSolution h = solve_hierarchical(f, m, {}, hf);
  const Material& mat = f.material_of(0);
  const double expected = mat.emission.x / (1.0 - mat.reflectance.x);
  for (const Rgb& v : h.solution.element) EXPECT_NEAR(v.x, expected, 1e-5 * expected);
}

TEST(Hierarchical, CornellBoxAgreesWithTheMatrixSolveAndBalancesEnergy) {
  const Scene s = read_obj_scene(kData + "/cornell_box/cornell_box.obj");
  const Mesh coarse = coarse_mesh(s, 200.0);
  const auto t0 = std::chrono::steady_clock::now();
  const HierarchicalSolution h = solve_hierarchical(s, coarse, {}, {});
  const double th = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const Mesh fine = coarse_mesh(s, 45.0);
  const auto t1 = std::chrono::steady_clock::now();
  const Solution ref = solve_matrix(s, fine, {});
  const double tm = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
  std::printf("[hierarchical] %d leaves, %lld links, %d rounds, %d sweeps, %lld rays, %.2f s; matrix %d elements %.2f s\n",
              h.stats.leaves, h.stats.links, h.stats.rounds, h.stats.sweeps, h.stats.rays_cast, th,
              fine.triangle_count(), tm);
  const auto mh = patch_mean_radiosity(s, h.mesh, h.solution.element);
  const auto mm = patch_mean_radiosity(s, fine, ref.element);
  for (size_t p = 0; p < s.patches.size(); ++p) {
    const double scale = std::max(mm[p].x, 0.05 * mm[0].x);
    EXPECT_NEAR(mh[p].x, mm[p].x, 0.05 * scale) << s.patches[p].name;
  }
  // Every link takes what its receivers gather out of its sending leaves'
  // radiosity: the balance closes to the sweeps' tolerance.
  EXPECT_LT(std::abs(relative_imbalance(h.solution.stats)), 1e-4);
  EXPECT_GT(h.stats.zero_area_triangles, 0);
}

TEST(Hierarchical, FloorAtTheBlocksFeetGathersWhatItsOwnRaysSee) {
  // The floor leaves next to a block see less of what lies behind the block
  // than the coarse floor nodes whose links they gather over. With one
  // visible fraction per link, the floor within 15 mm of either block came
  // out 6% brighter than the field gathered at the same leaves' centroids
  // (exact direct light, and the indirect light with a point's own rays);
  // with each leaf's own rays on its ancestors' partly visible links, the
  // two estimates of the same light agree to about 1%.
  const Scene s = read_obj_scene(kData + "/cornell_box/cornell_box.obj");
  const HierarchicalSolution h = solve_hierarchical(s, coarse_mesh(s, 192.0), {}, {});
  const FieldEvaluator field(s, h.mesh, h.solution.element, {});
  int floor = -1;
  std::map<std::string, std::vector<Vec3>> feet;  // block -> its corners on the floor
  for (size_t p = 0; p < s.patches.size(); ++p) {
    const Patch& patch = s.patches[p];
    if (patch.name == "floor") floor = static_cast<int>(p);
    if (patch.name.find("block") == std::string::npos) continue;
    for (int v : patch.outer) {
      const Vec3& x = s.vertices[static_cast<size_t>(v)];
      auto& f = feet[patch.name];
      if (x.y == 0.0 && std::find(f.begin(), f.end(), x) == f.end()) f.push_back(x);
    }
  }
  ASSERT_GE(floor, 0);
  ASSERT_EQ(feet.size(), 2u);
  for (auto& [name, f] : feet) {
    ASSERT_EQ(f.size(), 4u) << name;
    const Vec3 c = (f[0] + f[1] + f[2] + f[3]) / 4.0;  // corners in order around the centre (an outline)
    std::sort(f.begin(), f.end(), [&](const Vec3& a, const Vec3& b) {
      return std::atan2(a.z - c.z, a.x - c.x) < std::atan2(b.z - c.z, b.x - c.x);
    });
    double element = 0.0, gathered = 0.0, area = 0.0;
    FieldReport report;
    for (int t = 0; t < h.mesh.triangle_count(); ++t) {
      if (h.mesh.patch[static_cast<size_t>(t)] != floor || h.leaf_of[static_cast<size_t>(t)] < 0) continue;
      const auto& tri = h.mesh.triangles[static_cast<size_t>(t)];
      const Vec3 x = (h.mesh.positions[static_cast<size_t>(tri[0])] + h.mesh.positions[static_cast<size_t>(tri[1])] +
                      h.mesh.positions[static_cast<size_t>(tri[2])]) / 3.0;
      // In the floor's plane: 0 under the block, the distance to its outline outside.
      const double d = distance_to_polygon(x, f, Vec3(0.0, 1.0, 0.0));
      if (!(d > 0.0) || d > 15.0) continue;
      const double a = h.mesh.area(t);
      element += a * h.solution.element[static_cast<size_t>(t)].x;
      gathered += a * field.radiosity(x, floor, static_cast<uint64_t>(t), report).x;
      area += a;
    }
    std::printf("[hierarchical] floor within 15 mm of the %s: %.0f mm^2, element mean %.4f, gathered %.4f (%+.2f%%)\n",
                name.c_str(), area, element / area, gathered / area, 100.0 * (element / gathered - 1.0));
    ASSERT_GT(area, 1e4) << name;
    EXPECT_NEAR(element / gathered, 1.0, 0.035) << name;
  }
}

TEST(Hierarchical, SameResultWithOneAndTwoThreads) {
  const Scene s = read_obj_scene(kData + "/box_on_floor/box_on_floor.obj");
  const Mesh m = coarse_mesh(s, 1.0);
  SolveOptions one, two;
  one.threads = 1;
  two.threads = 2;
  const HierarchicalSolution a = solve_hierarchical(s, m, one, {}), b = solve_hierarchical(s, m, two, {});
  ASSERT_EQ(a.solution.element.size(), b.solution.element.size());
  for (size_t t = 0; t < a.solution.element.size(); ++t) EXPECT_EQ(a.solution.element[t], b.solution.element[t]);
  EXPECT_EQ(a.stats.links, b.stats.links);
}

TEST(HierarchicalStress, ReflectanceNearOneConverges) {
  for (double rho : {0.99, 0.999}) {
    Scene s = read_obj_scene(kData + "/furnace_cube/furnace_cube.obj");
    for (Material& m : s.materials) m.reflectance = Rgb(rho);
    SolveOptions o;
    o.tolerance = 1e-7;
    HierarchicalOptions ho;
    ho.epsilon = 0.05;
    ho.min_area = 1e-2;
    const HierarchicalSolution h = solve_hierarchical(s, coarse_mesh(s, 0.5), o, ho);
    const double e = s.materials[0].emission.x;
    std::printf("[hierarchical] rho %.3f: %d sweeps, B %.6g (closed form %.6g)\n", rho, h.stats.sweeps,
                h.solution.element[0].x, e / (1.0 - rho));
    // Rows sum to 1, so the closed form holds to the solver tolerance
    // amplified by 1 / (1 - rho).
    for (const Rgb& b : h.solution.element) EXPECT_NEAR(b.x, e / (1.0 - rho), 1e-7 / (1.0 - rho) / (1.0 - rho) * e);
  }
}

TEST(Hierarchical, TVertexModes) {
  const Scene s = read_obj_scene(kData + "/box_on_floor/box_on_floor.obj");
  const Mesh m = coarse_mesh(s, 1.0);
  HierarchicalOptions ho;
  ho.epsilon = 0.01;
  ho.baum = 0.0;  // Baum's splits follow the vertex values, which the modes change
  ho.tvertex = TVertexMode::free;
  const HierarchicalSolution free = solve_hierarchical(s, m, {}, ho);
  ho.tvertex = TVertexMode::anchor;
  const HierarchicalSolution anchor = solve_hierarchical(s, m, {}, ho);
  ho.tvertex = TVertexMode::split;
  const HierarchicalSolution split = solve_hierarchical(s, m, {}, ho);
  std::printf("[hierarchical] free: %d leaves + %d zero-area, jump %.3g; split: %d leaves, %d splits to conform\n",
              free.stats.leaves, free.stats.zero_area_triangles, free.stats.max_tvertex_jump, split.stats.leaves,
              split.stats.conforming_splits);
  // Same elements and radiosity for free and anchor; only vertex values differ.
  EXPECT_EQ(free.solution.element, anchor.solution.element);
  EXPECT_GT(free.stats.zero_area_triangles, 0);
  EXPECT_GT(free.stats.max_tvertex_jump, 0.0);
  // Along every unsplit leaf edge (a, b) with T-vertices, where the finer
  // leaves across share the leaf's display vertices at a and b, each finer
  // leaf's value at a T-vertex m is, anchored, the edge's interpolant: no
  // shading jump, whichever of m's display vertices a leaf uses. Free, the
  // largest difference is the reported jump.
  auto jump = [](const HierarchicalSolution& h, int* smooth_points) {
    std::map<std::pair<int, int>, std::pair<size_t, int>> edge;  // (u, w) -> (triangle, corner of u)
    for (size_t t = 0; t < h.leaf_of.size(); ++t)
      if (h.leaf_of[t] >= 0)
        for (int k = 0; k < 3; ++k)
          edge[{h.mesh.triangles[t][static_cast<size_t>(k)], h.mesh.triangles[t][static_cast<size_t>((k + 1) % 3)]}] = {t, k};
    const auto& r = h.solution.nodal.radiosity;
    double top = 0.0, worst = 0.0;
    for (const Rgb& b : r) top = std::max(top, std::max({b.x, b.y, b.z}));
    *smooth_points = 0;
    for (const auto& [uw, tk] : edge) {
      const auto [a, b] = uw;
      std::vector<int> chain = h.tree.edge_points(a, b, h.tree.node(h.leaf_of[tk.first]).root);
      if (chain.empty()) continue;
      const auto& c = h.solution.nodal.corners[tk.first];
      const int da = c[static_cast<size_t>(tk.second)], db = c[static_cast<size_t>((tk.second + 1) % 3)];
      chain.insert(chain.begin(), a);
      chain.push_back(b);
      std::vector<std::pair<size_t, int>> across;
      for (size_t i = 0; i + 1 < chain.size(); ++i) {
        const auto it = edge.find({chain[i + 1], chain[i]});
        if (it == edge.end() || h.mesh.patch[it->second.first] != h.mesh.patch[tk.first]) break;
        across.push_back(it->second);
      }
      if (across.size() + 1 != chain.size()) continue;
      auto display = [&](std::pair<size_t, int> f, int v) {
        for (int j = 0; j < 3; ++j)
          if (h.mesh.triangles[f.first][static_cast<size_t>(j)] == v) return h.solution.nodal.corners[f.first][static_cast<size_t>(j)];
        return -1;
      };
      if (display(across.front(), a) != da || display(across.back(), b) != db) continue;
      const Vec3 A = h.mesh.positions[static_cast<size_t>(a)], B = h.mesh.positions[static_cast<size_t>(b)];
      for (size_t i = 1; i + 1 < chain.size(); ++i) {
        const double u = glm::dot(h.mesh.positions[static_cast<size_t>(chain[i])] - A, B - A) / glm::dot(B - A, B - A);
        const Rgb interp = (1.0 - u) * r[static_cast<size_t>(da)] + u * r[static_cast<size_t>(db)];
        for (const auto& f : {across[i - 1], across[i]}) {
          const Rgb d = glm::abs(r[static_cast<size_t>(display(f, chain[i]))] - interp);
          worst = std::max(worst, std::max({d.x, d.y, d.z}) / top);
        }
        ++*smooth_points;
      }
    }
    return worst;
  };
  int smooth_free = 0, smooth_anchor = 0;
  EXPECT_NEAR(jump(free, &smooth_free), free.stats.max_tvertex_jump, 1e-12);
  EXPECT_LT(jump(anchor, &smooth_anchor), 1e-12);
  EXPECT_GT(smooth_anchor, 0);
  EXPECT_EQ(smooth_anchor, smooth_free);
  // The summary reports the jump free leaves, anchored or not.
  EXPECT_DOUBLE_EQ(anchor.stats.max_tvertex_jump, free.stats.max_tvertex_jump);
  // Split: no T-vertex, no zero-area triangle, and more leaves.
  EXPECT_EQ(split.stats.zero_area_triangles, 0);
  EXPECT_GT(split.stats.conforming_splits, 0);
  EXPECT_GT(split.stats.leaves, free.stats.leaves);
  for (int l : split.leaf_of) EXPECT_GE(l, 0);
}

TEST(HierarchicalStress, ThinPolygonsAndRefinementAtContactLines) {
  // A floor lit from above with a strip 1000 times longer than wide lying
  // across it at half height, and a box standing on it: links refine down to
  // the minimum area next to the box's contact lines and along the strip.
  std::vector<RawFace> faces;
  auto quad = [&](const std::string& name, int material, std::vector<Vec3> pts) {
    test::add_face(faces, name, material, std::move(pts));
  };
  quad("floor", 0, {{0, 0, 0}, {0, 0, 4}, {4, 0, 4}, {4, 0, 0}});
  quad("strip", 0, {{0.5, 1.5, 2.0}, {0.5, 1.5, 2.004}, {3.5, 1.5, 2.004}, {3.5, 1.5, 2.0}});  // 3 x 0.003 (aspect 1000), faces up
  quad("strip_under", 0, {{0.5, 1.5, 2.0}, {3.5, 1.5, 2.0}, {3.5, 1.5, 2.004}, {0.5, 1.5, 2.004}});
  quad("box", 0, {{1, 0, 1}, {1, 0.5, 1}, {1.5, 0.5, 1}, {1.5, 0, 1}});
  quad("box", 0, {{1.5, 0, 1.5}, {1.5, 0.5, 1.5}, {1, 0.5, 1.5}, {1, 0, 1.5}});
  quad("box", 0, {{1, 0, 1.5}, {1, 0.5, 1.5}, {1, 0.5, 1}, {1, 0, 1}});
  quad("box", 0, {{1.5, 0, 1}, {1.5, 0.5, 1}, {1.5, 0.5, 1.5}, {1.5, 0, 1.5}});
  quad("box", 0, {{1, 0.5, 1}, {1, 0.5, 1.5}, {1.5, 0.5, 1.5}, {1.5, 0.5, 1}});
  quad("light", 1, {{1.8, 3, 1.8}, {2.2, 3, 1.8}, {2.2, 3, 2.2}, {1.8, 3, 2.2}});
  Material white, lamp;
  white.name = "white";
  white.reflectance = Rgb(0.6);
  lamp.name = "light";
  lamp.emission = Rgb(20.0);
  const Scene s = build_scene(faces, {white, lamp}, "thin");
  HierarchicalOptions ho;
  ho.epsilon = 0.005;
  const HierarchicalSolution h = solve_hierarchical(s, coarse_mesh(s, 1.0), {}, ho);
  const double min_area = h.stats.min_area;
  EXPECT_DOUBLE_EQ(min_area, 0.5 * std::pow(s.diagonal() / 150.0, 2));  // the documented default
  double smallest = 1e300;
  for (int leaf : h.tree.leaves()) smallest = std::min(smallest, h.tree.area(leaf));
  std::printf("[hierarchical] thin strip + box: %d leaves, %lld links, smallest leaf %.3g (floor %.3g)\n",
              h.stats.leaves, h.stats.links, smallest, min_area);
  for (const Rgb& b : h.solution.element) ASSERT_TRUE(std::isfinite(b.x) && b.x >= 0.0);
  // Links stop at the minimum area, Baum's splits (on by default) one level
  // below it, never further.
  EXPECT_GE(smallest, 0.25 * min_area * (1.0 - 1e-12));
  EXPECT_LT(smallest, 4.0 * 4.0 * min_area);      // but refined down close to it
  EXPECT_LT(std::abs(relative_imbalance(h.solution.stats)), 0.02);
}

TEST(Hierarchical, TwoSidedPanelAndBlocksInContactShareCornersButNotInsides) {
  // A closed room lit from its ceiling holding a panel whose two sides are
  // one quad written twice (both windings) and two blocks with a face in
  // contact: each pair of coincident faces becomes roots on the same three
  // corners, split deep on both sides. The split points inside one root
  // are not the other's (they used to be shared by their ends' ids, and the
  // solve stopped with "vertex ... is inside another root").
  std::vector<RawFace> faces;
  auto quad = [&](const std::string& name, int material, std::vector<Vec3> pts) {
    test::add_face(faces, name, material, std::move(pts));
  };
  auto block = [&](const std::string& name, Vec3 lo, Vec3 hi) {  // faces out
    for (const RawFace& f : test::box_faces(name, 0, lo, hi)) faces.push_back(f);
  };
  quad("room", 0, {{0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0}});  // floor, up
  quad("room", 0, {{0, 1, 0}, {1, 1, 0}, {1, 1, 1}, {0, 1, 1}});  // ceiling, down
  quad("room", 0, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}});
  quad("room", 0, {{0, 0, 1}, {0, 1, 1}, {1, 1, 1}, {1, 0, 1}});
  quad("room", 0, {{0, 0, 0}, {0, 1, 0}, {0, 1, 1}, {0, 0, 1}});
  quad("room", 0, {{1, 0, 0}, {1, 0, 1}, {1, 1, 1}, {1, 1, 0}});
  quad("lamp", 1, {{0.4, 0.999, 0.4}, {0.6, 0.999, 0.4}, {0.6, 0.999, 0.6}, {0.4, 0.999, 0.6}});
  quad("panel_up", 0, {{0.55, 0.6, 0.2}, {0.55, 0.6, 0.8}, {0.95, 0.6, 0.8}, {0.95, 0.6, 0.2}});
  quad("panel_down", 0, {{0.55, 0.6, 0.2}, {0.95, 0.6, 0.2}, {0.95, 0.6, 0.8}, {0.55, 0.6, 0.8}});
  block("block_a", {0.1, 0.0, 0.3}, {0.3, 0.25, 0.6});
  block("block_b", {0.3, 0.0, 0.3}, {0.5, 0.25, 0.6});
  const Scene s =
      build_scene(faces, {test::material("white", Rgb(0.7)), test::material("lamp", Rgb(0.0), Rgb(25.0))}, "two-sided");
  const HierarchicalSolution h = solve_hierarchical(s, coarse_mesh(s, 0.2), {}, {});
  // Both sides of the panel were split inside their roots (level 2 and
  // below has points inside a root), so the test reaches the shared corners.
  std::map<std::string, int> deep;
  for (int leaf : h.tree.leaves())
    if (h.tree.node(leaf).level >= 2) ++deep[s.patches[static_cast<size_t>(h.tree.node(leaf).patch)].name];
  EXPECT_GT(deep["panel_up"], 0);
  EXPECT_GT(deep["panel_down"], 0);
  for (const Rgb& b : h.solution.element) ASSERT_TRUE(std::isfinite(b.x) && b.x >= 0.0);
  EXPECT_LT(std::abs(relative_imbalance(h.solution.stats)), 1e-4);
  const Mesh fine = coarse_mesh(s, 0.1);
  const Solution ref = solve_matrix(s, fine, {});
  for (const std::string name : {"panel_up", "panel_down", "block_a", "block_b", "room"}) {
    double ah = 0.0, am = 0.0, wh = 0.0, wm = 0.0;  // area-weighted over the patches of that name
    for (int t = 0; t < h.mesh.triangle_count(); ++t)
      if (s.patches[static_cast<size_t>(h.mesh.patch[static_cast<size_t>(t)])].name == name) {
        ah += h.mesh.area(t) * h.solution.element[static_cast<size_t>(t)].x;
        wh += h.mesh.area(t);
      }
    for (int t = 0; t < fine.triangle_count(); ++t)
      if (s.patches[static_cast<size_t>(fine.patch[static_cast<size_t>(t)])].name == name) {
        am += fine.area(t) * ref.element[static_cast<size_t>(t)].x;
        wm += fine.area(t);
      }
    std::printf("[hierarchical] two-sided: %s %.4f (matrix %.4f)\n", name.c_str(), ah / wh, am / wm);
    EXPECT_NEAR(ah / wh, am / wm, 0.03 * am / wm) << name;
  }
}

TEST(Hierarchical, BaumCriterionSplitsWhereVertexValuesDiffer) {
  const Scene s = read_obj_scene(kData + "/box_on_floor/box_on_floor.obj");
  const Mesh m = coarse_mesh(s, 1.0);
  HierarchicalOptions ho;
  ho.epsilon = 0.01;
  ho.max_rounds = 30;
  ho.baum = 0.0;
  // The fit: the splits' leaves are solved (with the gather they are not,
  // see BaumLeavesOfAGatheredFieldTakeTheirParentsRadiosity).
  SolveOptions fit;
  fit.field = FieldMode::fit;
  const HierarchicalSolution plain = solve_hierarchical(s, m, fit, ho);
  int within_budget = 0;
  for (double rel : {0.05, 0.1, 0.15, 0.2}) {
    ho.baum = rel;
    const HierarchicalSolution baum = solve_hierarchical(s, m, fit, ho);
    std::printf("[hierarchical] Baum %.0f%%: %d leaves (%d Baum splits, %d rounds) against %d without\n", 100 * rel,
                baum.stats.leaves, baum.stats.baum_splits, baum.stats.rounds, plain.stats.leaves);
    EXPECT_EQ(baum.stats.leaves > plain.stats.leaves, baum.stats.baum_splits > 0);
    ASSERT_LT(baum.stats.rounds, ho.max_rounds + 1);  // stopped because nothing more was split
    // The leaves the splits add stay within half of those the links made.
    const int added = 3 * baum.stats.baum_splits;
    EXPECT_LE(added, 0.5 * (baum.stats.leaves - added)) << rel;
    if (baum.stats.baum_splits == 0 || 3 * (baum.stats.baum_splits + 1) > 0.5 * (baum.stats.leaves - added) - added)
      continue;  // nothing split, or the budget spent
    ++within_budget;
    // Otherwise, when it stops, every leaf that may still be split is within
    // the tolerance (the criterion is checked on the values of the last
    // solve), but for those a round would split that add under 1% of the
    // leaves: such a round is not made (kBaumRound).
    const double min_area = baum.stats.min_area;
    int over = 0;
    double top = 0.0;  // the largest reflected radiosity
    for (size_t n = 0; n < baum.node_radiosity.size(); ++n) {
      const Patch& patch = s.patches[static_cast<size_t>(baum.tree.node(static_cast<int>(n)).patch)];
      top = std::max(top, baum.node_radiosity[n].x - s.material_of(patch).emission.x);
    }
    for (size_t t = 0; t < baum.leaf_of.size(); ++t) {
      const int n = baum.leaf_of[t];
      if (n < 0 || baum.tree.area(n) <= min_area) continue;  // Baum's floor: children of min_area / 4
      double lo = 1e300, hi = -1e300;
      for (int c : baum.solution.nodal.corners[t]) {
        lo = std::min(lo, baum.solution.nodal.radiosity[static_cast<size_t>(c)].x);
        hi = std::max(hi, baum.solution.nodal.radiosity[static_cast<size_t>(c)].x);
      }
      over += hi - lo > rel * top * (1.0 + 1e-9);
    }
    EXPECT_LT(3 * over, 0.01 * baum.stats.leaves) << rel << ": " << over << " leaves over the tolerance";
  }
  EXPECT_GT(within_budget, 0);
}

TEST(Hierarchical, NoRoundForMarginalRefinementsAndItMovesNoPatchPastThem) {
  // A round for links that are all over the oracle's threshold by at most
  // marginal_refinement x is not made: refining one changes its receiver by
  // about its error. So no patch mean may move by more than that factor
  // times the threshold (epsilon x the largest reflected radiosity), and
  // the skipped links are reported.
  const Scene s = read_obj_scene(kData + "/cornell_box/cornell_box.obj");
  const Mesh m = coarse_mesh(s, 200.0);
  HierarchicalOptions every;
  every.marginal_refinement = 1.0;
  const HierarchicalSolution all = solve_hierarchical(s, m, {}, every);
  const HierarchicalSolution h = solve_hierarchical(s, m, {}, {});
  auto skipped = [](const HierarchicalSolution& x) {
    return std::count_if(x.solution.stats.skips.begin(), x.solution.stats.skips.end(),
                         [](const std::string& k) { return k.rfind("refinement: ", 0) == 0; });
  };
  std::printf("[hierarchical] marginal refinement: %d rounds, %lld links, %d leaves; every link refined: %d rounds, %lld links, %d leaves\n",
              h.stats.rounds, h.stats.links, h.stats.leaves, all.stats.rounds, all.stats.links, all.stats.leaves);
  EXPECT_EQ(skipped(all), 0);
  ASSERT_EQ(skipped(h), 1);  // the Cornell box's third round is such a round
  EXPECT_LT(h.stats.rounds, all.stats.rounds);
  EXPECT_LT(h.stats.links, all.stats.links);
  double top = 0.0;  // the largest reflected radiosity, as the oracle's scale
  for (size_t n = 0; n < all.node_radiosity.size(); ++n) {
    const Patch& patch = s.patches[static_cast<size_t>(all.tree.node(static_cast<int>(n)).patch)];
    top = std::max(top, all.node_radiosity[n].x - s.material_of(patch).emission.x);
  }
  const HierarchicalOptions defaults;
  const auto mh = patch_mean_radiosity(s, h.mesh, h.solution.element);
  const auto ma = patch_mean_radiosity(s, all.mesh, all.solution.element);
  for (size_t p = 0; p < s.patches.size(); ++p)
    EXPECT_LE(std::abs(mh[p].x - ma[p].x), defaults.marginal_refinement * defaults.epsilon * top) << s.patches[p].name;
  EXPECT_LT(std::abs(relative_imbalance(h.solution.stats)), 1e-4);
}

TEST(HierarchicalStress, MemoryLimitIsAClearErrorBeforeAnyCrash) {
  // The Cornell box from 200 mm roots (311 of them, 78072 facing root
  // pairs, about 3.5 MiB of first links) needs about 30 MiB of links at
  // epsilon 0.001: a limit below the first links is refused before linking,
  // one between them (on top of what the process holds already) stops the
  // refinement. The margin leaves room for what the process grows by before
  // the first links (a sanitizer's shadow memory: about 8 MiB).
  const Scene s = read_obj_scene(kData + "/cornell_box/cornell_box.obj");
  const Mesh coarse = coarse_mesh(s, 200.0);
  SolveOptions tiny, small;
  tiny.max_memory = 1e-6;
  for (ClusterMode mode : {ClusterMode::off, ClusterMode::volume, ClusterMode::shape}) {
    HierarchicalOptions ho;
    ho.clusters = mode;
    auto message = [&](const SolveOptions& o) {
      try {
        solve_hierarchical(s, coarse, o, ho);
      } catch (const NumericalError& e) {
        return std::string(e.what());
      }
      return std::string("no error");
    };
    const std::string first = message(tiny);
    small.max_memory = (resident_memory_bytes() + 16.0 * kMiB) / kGiB;  // the process grows from one solve to the next
    const std::string later = message(small);
    // Without clusters the root pairs are refused; with them, the clusters.
    EXPECT_NE(first.find(mode == ClusterMode::off ? "pairs to link" : "clusters above"), std::string::npos) << first;
    EXPECT_NE(first.find("cornell_box.obj"), std::string::npos) << first;
    EXPECT_NE(later.find("hierarchical refinement "), std::string::npos) << later;
    EXPECT_EQ(first.find("hierarchical refinement "), std::string::npos) << first;
    EXPECT_NE(later.find("raise epsilon"), std::string::npos) << later;
  }
}

TEST(HierarchicalStress, MemoryLimitCountsTheWholeProcess) {
  // A small solve (its links and terms well under a MiB) under a limit of
  // what the process holds plus 64 MiB fits; with 128 MiB more held
  // elsewhere in the process (a caller's data, a mesh) it is refused with
  // a message that says what the process holds, where a count of the
  // solver's own structures alone let it pass.
  if (resident_memory_bytes() <= 0.0) GTEST_SKIP() << "this system does not report resident memory";
  const Scene s = read_obj_scene(kData + "/box_on_floor/box_on_floor.obj");
  const Mesh coarse = coarse_mesh(s, 1.0);
  HierarchicalOptions ho;
  ho.epsilon = 0.01;
  SolveOptions o;
  o.max_memory = (resident_memory_bytes() + 64.0 * kMiB) / kGiB;
  EXPECT_NO_THROW(solve_hierarchical(s, coarse, o, ho));
  const std::vector<char> held(static_cast<size_t>(128.0 * kMiB), 1);
  try {
    solve_hierarchical(s, coarse, o, ho);
    ADD_FAILURE() << "no error";
  } catch (const NumericalError& e) {
    EXPECT_NE(std::string(e.what()).find("the process holds"), std::string::npos) << e.what();
    EXPECT_EQ(e.options(), (std::vector<std::string>{"max_edge", "max_memory"}));
  }
  EXPECT_EQ(held[held.size() / 2], 1);
}

TEST(Hierarchical, SolverObjectStepsToTheOneOffResult) {
  // The solver object keeps tree, links and radiosity between rounds:
  // stepping it by hand ends where solve_hierarchical ends, round for round
  // (that one without copying its links out).
  const Scene s = read_obj_scene(kData + "/box_on_floor/box_on_floor.obj");
  const Mesh m = coarse_mesh(s, 1.0);
  HierarchicalOptions ho;
  ho.epsilon = 0.01;
  ho.export_links = true;
  std::vector<long long> links_seen;
  HierarchicalOptions without_links = ho;  // changes what is copied out, nothing else
  without_links.export_links = false;
  const HierarchicalSolution once =
      solve_hierarchical(s, m, {}, without_links, [&](const HierarchicalSolution& h, int round) {
        EXPECT_EQ(static_cast<int>(links_seen.size()), round);
        links_seen.push_back(h.stats.links_per_round.back());
      });
  HierarchicalSolver solver(s, m, {}, ho);
  EXPECT_EQ(solver.rounds(), 1);
  while (solver.refine()) {
  }
  EXPECT_FALSE(solver.refine());  // done stays done
  const HierarchicalSolution& stepped = solver.solution();
  ASSERT_GT(stepped.stats.rounds, 1);
  EXPECT_EQ(stepped.stats.rounds, once.stats.rounds);
  EXPECT_EQ(stepped.stats.links_per_round, once.stats.links_per_round);
  EXPECT_EQ(static_cast<long long>(links_seen.size()), once.stats.rounds);
  ASSERT_EQ(stepped.solution.element.size(), once.solution.element.size());
  for (size_t t = 0; t < once.solution.element.size(); ++t)
    EXPECT_EQ(stepped.solution.element[t], once.solution.element[t]);
  long long published = static_cast<long long>(stepped.cluster_links.size());
  for (const auto& l : stepped.links) published += static_cast<long long>(l.size());
  EXPECT_EQ(published, stepped.stats.links);
  EXPECT_EQ(static_cast<long long>(stepped.cluster_links.size()), stepped.stats.cluster_links);
  EXPECT_TRUE(once.links.empty());
  EXPECT_TRUE(once.cluster_links.empty());
  EXPECT_EQ(once.stats.links, stepped.stats.links);
}

TEST(Hierarchical, ReportsProgressFromTheCallingThread) {
  // Phases link, solve and refine, in that order of first appearance, the
  // first linking's fraction rising to 1, every call on the caller's thread.
  const Scene s = read_obj_scene(kData + "/box_on_floor/box_on_floor.obj");
  HierarchicalOptions ho;
  ho.epsilon = 0.01;
  std::vector<std::string> phases;
  double last_link = -1.0;
  bool rising = true, same_thread = true;
  const auto caller = std::this_thread::get_id();
  solve_hierarchical(s, coarse_mesh(s, 1.0), {}, ho, {}, [&](const std::string& phase, double f) {
    same_thread = same_thread && std::this_thread::get_id() == caller;
    if (std::find(phases.begin(), phases.end(), phase) == phases.end()) phases.push_back(phase);
    if (phase == "link") {
      rising = rising && f >= last_link && f <= 1.0;
      last_link = f;
    }
  });
  EXPECT_EQ(phases, (std::vector<std::string>{"link", "solve", "refine"}));
  EXPECT_EQ(last_link, 1.0);
  EXPECT_TRUE(rising);
  EXPECT_TRUE(same_thread);
}

// Where the field is gathered at the vertices, Baum's splits only add display
// vertices: they wait until no link is refined, come in one last round (in
// depth, on the last solve's values), and their leaves take their parent's
// radiosity unsolved. With the fit they are solved like every other leaf.
TEST(Hierarchical, BaumLeavesOfAGatheredFieldTakeTheirParentsRadiosity) {
  const Scene s = read_obj_scene(kData + "/box_on_floor/box_on_floor.obj");
  const Mesh m = coarse_mesh(s, 1.0);
  HierarchicalOptions ho;
  ho.epsilon = 0.01;
  ho.max_rounds = 30;
  ho.baum = 0.05;
  SolveOptions gather, fit;
  gather.field = FieldMode::gather;
  fit.field = FieldMode::fit;
  const HierarchicalSolution g = solve_hierarchical(s, m, gather, ho);
  const HierarchicalSolution f = solve_hierarchical(s, m, fit, ho);
  // Leaves whose radiosity is exactly their parent's.
  auto as_parent = [](const HierarchicalSolution& h) {
    int count = 0;
    for (int t : h.leaf_of) {
      if (t < 0) continue;
      const int parent = h.tree.node(t).parent;
      if (parent >= 0 && h.node_radiosity[static_cast<size_t>(t)] == h.node_radiosity[static_cast<size_t>(parent)]) ++count;
    }
    return count;
  };
  std::printf("[hierarchical] Baum, gathered: %d splits, %d rounds, %d leaves as their parent; fit: %d splits, %d rounds, %d\n",
              g.stats.baum_splits, g.stats.rounds, as_parent(g), f.stats.baum_splits, f.stats.rounds, as_parent(f));
  ASSERT_GT(g.stats.baum_splits, 0);
  ASSERT_GT(f.stats.baum_splits, 0);
  // A split makes 4 leaves of its parent's value; one split again (a leaf
  // is split in depth) is no leaf, but its 4 children are: at least 3 a split.
  EXPECT_GE(as_parent(g), 3 * g.stats.baum_splits);
  EXPECT_LT(as_parent(f), 3 * f.stats.baum_splits);
  // The last round refined no link and added the leaves.
  const auto& links = g.stats.links_per_round;
  const auto& leaves = g.stats.leaves_per_round;
  ASSERT_GE(links.size(), 2u);
  EXPECT_EQ(links.back(), links[links.size() - 2]);
  EXPECT_EQ(leaves.back() - leaves[leaves.size() - 2], 3 * g.stats.baum_splits);
}

TEST(Hierarchical, AFurnaceWithATileLyingInItsFloorStaysUniform) {
  // A tile modelled on the furnace's floor: cut out of the floor, the cube
  // is still covered once and B = E / (1 - rho) everywhere; kept as a
  // second surface over the floor, the walls' rows would count the tile's
  // area twice.
  std::vector<RawFace> faces = test::box_faces("room", 0, {0, 0, 0}, {1, 1, 1}, false);
  test::add_face(faces, "tile", 0, {{0.2, 0, 0.2}, {0.2, 0, 0.5}, {0.5, 0, 0.5}, {0.5, 0, 0.2}});
  const Scene s = build_scene(faces, {test::material("f", Rgb(0.8), Rgb(1.0))}, "furnace with a tile");
  ASSERT_EQ(s.report.faces_cut_out, 1);
  HierarchicalOptions ho;
  ho.epsilon = 0.02;
  ho.min_area = 2e-3;
  const HierarchicalSolution h = solve_hierarchical(s, coarse_mesh(s, 0.5), {}, ho);
  for (const Rgb& b : h.solution.element) ASSERT_NEAR(b.x, 5.0, 5e-5);
  EXPECT_NEAR(h.stats.row_sum_min, 1.0, 1e-9);
  EXPECT_NEAR(h.stats.row_sum_max, 1.0, 1e-9);
}
