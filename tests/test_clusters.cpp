// Scene-wide structures that keep every phase near-linear: the box tree, and
// the cluster hierarchy above the polygons.
#include "bench/mesh_writers.h"
#include "meshing/box_tree.h"
#include "meshing/errors.h"

#include <gtest/gtest.h>

#include <random>
#include <set>

namespace radmesh {
namespace {

TEST(BoxTree, FindsExactlyTheOverlappingBoxes) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 10.0), s(0.0, 0.8);
  std::vector<Box3> boxes(3000);
  for (Box3& b : boxes) {
    const Vec3 c(u(rng), u(rng), u(rng));
    b.add(c);
    b.add(c + Vec3(s(rng), s(rng), s(rng)));
  }
  const BoxTree tree(boxes);
  for (int q = 0; q < 200; ++q) {
    Box3 query;
    const Vec3 c(u(rng), u(rng), u(rng));
    query.add(c);
    query.add(c + Vec3(2.0 * s(rng), 2.0 * s(rng), 2.0 * s(rng)));
    std::set<int> expected, found;
    for (size_t i = 0; i < boxes.size(); ++i)
      if (boxes[i].overlaps(query, 0.0)) expected.insert(static_cast<int>(i));
    tree.overlapping(query, 0.0, [&](int i) {
      EXPECT_TRUE(found.insert(i).second) << "box " << i << " reported twice";
      return true;
    });
    EXPECT_EQ(found, expected);
  }
  // Stopping early: the visitor's false ends the query.
  Box3 everything;
  everything.add(Vec3(-1.0));
  everything.add(Vec3(12.0));
  int visited = 0;
  EXPECT_FALSE(tree.overlapping(everything, 0.0, [&](int) { return ++visited < 5; }));
  EXPECT_EQ(visited, 5);
}

}  // namespace
}  // namespace radmesh

// ---------------------------------------------------------------- clusters

#include "meshing/mesh.h"
#include "meshing/scene.h"
#include "radiosity/hierarchical.h"

#include <array>
#include <cmath>
#include <map>

namespace radmesh {
namespace {

// A closed 4 x 3 x 4 room (walls facing in, rho 0.7) with a 1 x 1 light
// flush in the ceiling (a hole in it, so the room stays closed and every
// face is two-sided where it must be) and an icosphere of 20 x 4^level
// triangles (rho 0.5) floating inside.
Scene sphere_room(int level) {
  std::vector<RawFace> faces;
  auto face = [&](const std::string& name, int material, std::vector<Vec3> pts, std::vector<std::vector<Vec3>> holes = {}) {
    RawFace f;
    f.name = name;
    f.material = material;
    f.points = std::move(pts);
    f.holes = std::move(holes);
    faces.push_back(std::move(f));
  };
  const double X = 4, Y = 3, Z = 4;
  face("floor", 0, {{0, 0, 0}, {0, 0, Z}, {X, 0, Z}, {X, 0, 0}});
  face("ceiling", 0, {{0, Y, 0}, {X, Y, 0}, {X, Y, Z}, {0, Y, Z}},
       {{{1.5, Y, 1.5}, {1.5, Y, 2.5}, {2.5, Y, 2.5}, {2.5, Y, 1.5}}});
  face("light", 2, {{1.5, Y, 1.5}, {2.5, Y, 1.5}, {2.5, Y, 2.5}, {1.5, Y, 2.5}});
  face("walls", 0, {{0, 0, 0}, {X, 0, 0}, {X, Y, 0}, {0, Y, 0}});
  face("walls", 0, {{0, 0, Z}, {0, Y, Z}, {X, Y, Z}, {X, 0, Z}});
  face("walls", 0, {{0, 0, 0}, {0, Y, 0}, {0, Y, Z}, {0, 0, Z}});
  face("walls", 0, {{X, 0, 0}, {X, 0, Z}, {X, Y, Z}, {X, Y, 0}});
  const test::Icosphere sphere = test::icosphere(level);
  auto point = [&](int k) {
    const auto& p = sphere.positions[static_cast<size_t>(k)];
    return Vec3(p[0], p[1], p[2]);
  };
  const Vec3 centre(2.0, 1.2, 2.0);
  for (const auto& [a, b, c] : sphere.triangles)
    face("sphere", 1, {centre + 0.8 * point(a), centre + 0.8 * point(b), centre + 0.8 * point(c)});
  Material wall, grey, lamp;
  wall.name = "wall";
  wall.reflectance = Rgb(0.7);
  grey.name = "grey";
  grey.reflectance = Rgb(0.5);
  lamp.name = "lamp";
  lamp.emission = Rgb(10.0);
  return build_scene(faces, {wall, grey, lamp}, "sphere_room");
}

// Area-weighted mean radiosity (first channel) per patch name.
std::map<std::string, double> object_means(const Scene& s, const HierarchicalSolution& h) {
  std::map<std::string, std::pair<double, double>> acc;
  for (size_t t = 0; t < h.solution.element.size(); ++t) {
    const double a = h.mesh.area(static_cast<int>(t));
    auto& [area, sum] = acc[s.patches[static_cast<size_t>(h.mesh.patch[t])].name];
    area += a;
    sum += a * h.solution.element[t].x;
  }
  std::map<std::string, double> out;
  for (const auto& [name, as] : acc) out[name] = as.second / as.first;
  return out;
}

Mesh initial_mesh(const Scene& s) {
  MeshingOptions o;
  o.max_edge = s.diagonal() / 5.0;  // the hierarchical method's own
  o.discontinuity = DiscontinuityMode::contacts;
  return mesh_scene(s, o);
}

TEST(Clusters, FewerLinksSameObjectMeansAndEnergyInAClosedRoom) {
  const Scene s = sphere_room(2);  // 320 sphere triangles
  const Mesh m = initial_mesh(s);
  HierarchicalOptions off, volume;
  off.clusters = ClusterMode::off;
  volume.clusters = ClusterMode::volume;
  off.epsilon = volume.epsilon = 0.01;
  off.min_area = volume.min_area = 0.02;  // the walls' leaves stay coarse: the roots are what is compared
  off.max_rounds = volume.max_rounds = 1;
  const HierarchicalSolution a = solve_hierarchical(s, m, {}, off), b = solve_hierarchical(s, m, {}, volume);
  std::printf("[clusters] sphere room, %d roots: off %lld links, volume %lld links (%lld with a cluster end), %d clusters\n",
              m.triangle_count(), a.stats.links, b.stats.links, b.stats.cluster_links, b.stats.clusters);
  EXPECT_EQ(a.stats.clusters, 0);
  EXPECT_EQ(b.stats.clusters, m.triangle_count() - 1);  // a binary tree over the roots
  EXPECT_GT(b.stats.cluster_links, 0);
  EXPECT_LT(b.stats.links, a.stats.links);
  const auto ma = object_means(s, a), mb = object_means(s, b);
  for (const auto& [name, mean] : ma) {
    ASSERT_GT(mean, 0.0) << name;
    EXPECT_NEAR(mb.at(name) / mean, 1.0, 0.01) << name;  // the bound: object means within 1%
  }
  // Energy balances as well as without clusters.
  const SolveStats& st = b.solution.stats;
  EXPECT_LT(std::abs(st.power_emitted.x - st.power_absorbed.x - st.power_escaped.x) / st.power_emitted.x, 0.01);
}

TEST(Clusters, OneAndTwoThreadsGiveIdenticalResults) {
  const Scene s = sphere_room(2);
  const Mesh m = initial_mesh(s);
  HierarchicalOptions ho;
  ho.clusters = ClusterMode::volume;
  ho.epsilon = 0.01;
  ho.min_area = 0.02;
  ho.max_rounds = 1;
  SolveOptions one, two;
  one.threads = 1;
  two.threads = 2;
  const HierarchicalSolution a = solve_hierarchical(s, m, one, ho), b = solve_hierarchical(s, m, two, ho);
  ASSERT_GT(a.stats.cluster_links, 0);
  EXPECT_EQ(a.stats.links, b.stats.links);
  ASSERT_EQ(a.solution.element.size(), b.solution.element.size());
  for (size_t t = 0; t < a.solution.element.size(); ++t) ASSERT_EQ(a.solution.element[t], b.solution.element[t]) << t;
}

TEST(Clusters, ParseAndName) {
  EXPECT_EQ(parse_cluster_mode("volume"), ClusterMode::volume);
  EXPECT_EQ(parse_cluster_mode("off"), ClusterMode::off);
  for (ClusterMode c : {ClusterMode::volume, ClusterMode::off}) EXPECT_EQ(parse_cluster_mode(to_string(c)), c);
  EXPECT_THROW(parse_cluster_mode("shape"), InputError);
}

}  // namespace
}  // namespace radmesh
