// Scene-wide structures that keep every phase near-linear: the box tree, and
// the cluster hierarchy above the polygons.
#include "meshing/box_tree.h"

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
