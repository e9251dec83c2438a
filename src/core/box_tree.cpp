// The box tree (core/box_tree.h): a bounding-volume hierarchy over boxes,
// built once and queried for the boxes that meet a box or a segment.

#include "core/box_tree.h"

#include <algorithm>

namespace radmesh {

namespace {
constexpr int kLeafSize = 4;
constexpr int kMaxDepth = 60;  // the query stack holds 64: one pending sibling per level
}  // namespace

BoxTree::BoxTree(const std::vector<Box3>& boxes) : boxes_(boxes) {
  if (boxes_.empty()) return;
  order_.resize(boxes_.size());
  for (size_t i = 0; i < order_.size(); ++i) order_[i] = static_cast<int>(i);
  nodes_.reserve(2 * boxes_.size() / kLeafSize + 2);
  nodes_.emplace_back();
  // The centres once, side by side: the splits compare them (the same
  // values Box3::centre gives, so the same tree), and fetching each from
  // its box cost most of the build on a million boxes.
  std::vector<Vec3> centres(boxes_.size());
  for (size_t i = 0; i < centres.size(); ++i) centres[i] = boxes_[i].centre();
  build(0, 0, static_cast<int>(boxes_.size()), 0, centres);
}

void BoxTree::build(int node, int begin, int end, int depth, const std::vector<Vec3>& centre) {
  Box3 box, centres;
  for (int i = begin; i < end; ++i) {
    const size_t k = static_cast<size_t>(order_[static_cast<size_t>(i)]);
    box.add(boxes_[k]);
    centres.add(centre[k]);
  }
  nodes_[static_cast<size_t>(node)].box = box;
  nodes_[static_cast<size_t>(node)].begin = begin;
  nodes_[static_cast<size_t>(node)].end = end;
  if (end - begin <= kLeafSize || depth >= kMaxDepth) return;
  const Vec3 extent = centres.hi - centres.lo;
  const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
  const int mid = begin + (end - begin) / 2;
  std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end, [&](int a, int b) {
    const double ca = centre[static_cast<size_t>(a)][axis], cb = centre[static_cast<size_t>(b)][axis];
    return ca < cb || (ca == cb && a < b);
  });
  const int left = static_cast<int>(nodes_.size());
  nodes_[static_cast<size_t>(node)].left = left;
  nodes_.emplace_back();
  nodes_.emplace_back();
  build(left, begin, mid, depth + 1, centre);
  build(left + 1, mid, end, depth + 1, centre);
}

}  // namespace radmesh
