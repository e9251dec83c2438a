// A bounding-volume hierarchy of axis-aligned boxes (median splits on the
// longest axis): which of many boxes overlap a query box, in O(log n + hits).
// Used wherever a scene-wide pass would otherwise test every pair of patches.
#pragma once

#include "radmesh/geometry.h"

#include <limits>
#include <vector>

namespace radmesh {

struct Box3 {
  Vec3 lo{std::numeric_limits<double>::infinity()}, hi{-std::numeric_limits<double>::infinity()};
  void add(const Vec3& p) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  void add(const Box3& b) {
    lo = glm::min(lo, b.lo);
    hi = glm::max(hi, b.hi);
  }
  bool empty() const { return lo.x > hi.x; }
  Vec3 centre() const { return 0.5 * (lo + hi); }
  // Overlap, boxes grown by eps on every side.
  bool overlaps(const Box3& o, double eps) const {
    return !(glm::any(glm::lessThan(hi + eps, o.lo)) || glm::any(glm::lessThan(o.hi + eps, lo)));
  }
};

class BoxTree {
public:
  BoxTree() = default;
  // One item per box, numbered as given.
  explicit BoxTree(const std::vector<Box3>& boxes);

  // Calls visit(item) for every item whose box overlaps `query` (grown by
  // eps), until visit returns false. Returns false when stopped that way.
  template <class F>
  bool overlapping(const Box3& query, double eps, F&& visit) const {
    return where([&](const Box3& b) { return b.overlaps(query, eps); }, visit);
  }

  // The same for any test of a box that holds for a box whenever it holds
  // for a box inside it (a shaft, a segment's neighbourhood): calls
  // visit(item) for every item whose box passes `test`, skipping the
  // subtrees whose box fails it.
  template <class Test, class F>
  bool where(Test&& test, F&& visit) const {
    if (nodes_.empty()) return true;
    int stack[64];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& node = nodes_[static_cast<size_t>(stack[--top])];
      if (!test(node.box)) continue;
      if (node.left < 0) {
        for (int i = node.begin; i < node.end; ++i)
          if (test(boxes_[static_cast<size_t>(order_[static_cast<size_t>(i)])]) &&
              !visit(order_[static_cast<size_t>(i)]))
            return false;
      } else {
        stack[top++] = node.left;
        stack[top++] = node.left + 1;
      }
    }
    return true;
  }

  size_t size() const { return boxes_.size(); }
  const Box3& box(int item) const { return boxes_[static_cast<size_t>(item)]; }

private:
  struct Node {
    Box3 box;
    int left = -1;  // children left and left + 1; -1 for a leaf
    int begin = 0, end = 0;
  };
  void build(int node, int begin, int end, int depth, const std::vector<Vec3>& centre);
  std::vector<Box3> boxes_;
  std::vector<int> order_;
  std::vector<Node> nodes_;
};

}  // namespace radmesh
