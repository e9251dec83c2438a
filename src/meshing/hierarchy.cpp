// The element tree of hierarchical radiosity: the initial mesh's
// triangles as roots, split into four at edge midpoints shared between
// neighbours, and the conforming mesh of its leaves with zero-area
// triangles closing every T-vertex.

#include "radmesh/hierarchy.h"

#include "radmesh/errors.h"

#include <algorithm>
#include <functional>

namespace radmesh {

ElementTree::ElementTree(const Mesh& mesh) : features_(mesh.feature_edges) {
  positions_ = mesh.positions;
  initial_vertices_ = static_cast<int>(mesh.positions.size());
  for (int t = 0; t < mesh.triangle_count(); ++t) {
    Node n;
    n.v = mesh.triangles[static_cast<size_t>(t)];
    n.patch = mesh.patch[static_cast<size_t>(t)];
    n.root = t;
    nodes_.push_back(n);
  }
  roots_ = mesh.triangle_count();
}

std::array<double, 2> ElementTree::barycentric(int root, int vertex) const {
  const auto& c = nodes_[static_cast<size_t>(root)].v;
  auto corner = [&](int id) -> std::array<double, 2> {
    if (id == c[1]) return {1.0, 0.0};
    if (id == c[2]) return {0.0, 1.0};
    if (id == c[0]) return {0.0, 0.0};
    throw GeometryError("element tree: vertex " + std::to_string(id) + " is not a corner of root " +
                        std::to_string(root));
  };
  if (vertex < initial_vertices_) return corner(vertex);
  const Made& m = made_[static_cast<size_t>(vertex - initial_vertices_)];
  if (m.root < 0) {  // on an initial edge (p, q) of this root
    const auto bp = corner(m.p), bq = corner(m.q);
    return {(1.0 - m.t) * bp[0] + m.t * bq[0], (1.0 - m.t) * bp[1] + m.t * bq[1]};
  }
  if (m.root != root)
    throw GeometryError("element tree: vertex " + std::to_string(vertex) + " is inside another root");
  return {m.u, m.v};
}

int ElementTree::make_midpoint(int root, int a, int b) {
  const auto ba = barycentric(root, a), bb = barycentric(root, b);
  const double u = 0.5 * (ba[0] + bb[0]), v = 0.5 * (ba[1] + bb[1]);  // exact: dyadic
  const auto& c = nodes_[static_cast<size_t>(root)].v;
  // On an edge of the root (u = 0, v = 0 or u + v = 1): a parameter along
  // that initial edge, oriented from its smaller vertex id, so that both
  // roots sharing the edge would compute the same point.
  int p = -1, q = -1;
  double t = 0.0;
  if (v == 0.0) {
    p = c[0], q = c[1], t = u;
  } else if (u == 0.0) {
    p = c[0], q = c[2], t = v;
  } else if (u + v == 1.0) {
    p = c[1], q = c[2], t = v;
  }
  const MidpointKey key = midpoint_key(root, a, b, ba, bb);
  if (auto it = midpoints_.find(key); it != midpoints_.end()) return it->second;
  Made m;
  Vec3 x;
  if (p >= 0) {
    if (p > q) {
      std::swap(p, q);
      t = 1.0 - t;  // exact: t is dyadic in (0, 1)
    }
    m.p = p;
    m.q = q;
    m.t = t;
    const Vec3& P = positions_[static_cast<size_t>(p)];
    const Vec3& Q = positions_[static_cast<size_t>(q)];
    x = P + t * (Q - P);
  } else {
    m.root = root;
    m.u = u;
    m.v = v;
    const Vec3& A = positions_[static_cast<size_t>(c[0])];
    const Vec3& B = positions_[static_cast<size_t>(c[1])];
    const Vec3& C = positions_[static_cast<size_t>(c[2])];
    x = A + u * (B - A) + v * (C - A);
  }
  const int id = static_cast<int>(positions_.size());
  positions_.push_back(x);
  made_.push_back(m);
  midpoints_[key] = id;
  return id;
}

int ElementTree::split(int n) {
  if (!is_leaf(n)) throw GeometryError("element tree: node " + std::to_string(n) + " is already split");
  const Node parent = nodes_[static_cast<size_t>(n)];
  if (parent.level >= 52) throw NumericalError("element tree: node " + std::to_string(n) + " is at level 52");
  const int a = parent.v[0], b = parent.v[1], c = parent.v[2];
  const int ab = make_midpoint(parent.root, a, b), bc = make_midpoint(parent.root, b, c),
            ca = make_midpoint(parent.root, c, a);
  const int first = static_cast<int>(nodes_.size());
  const std::array<std::array<int, 3>, 4> kids = {{{a, ab, ca}, {ab, b, bc}, {ca, bc, c}, {bc, ca, ab}}};
  for (const auto& v : kids) {
    Node k;
    k.v = v;
    k.patch = parent.patch;
    k.root = parent.root;
    k.parent = n;
    k.level = parent.level + 1;
    nodes_.push_back(k);
  }
  nodes_[static_cast<size_t>(n)].child = first;
  return first;
}

std::vector<int> ElementTree::leaves() const {
  std::vector<int> out;
  for (int n = 0; n < static_cast<int>(nodes_.size()); ++n)
    if (is_leaf(n)) out.push_back(n);
  return out;
}

double ElementTree::area(int n) const {
  const auto& v = nodes_[static_cast<size_t>(n)].v;
  return triangle_area(positions_[static_cast<size_t>(v[0])], positions_[static_cast<size_t>(v[1])],
                       positions_[static_cast<size_t>(v[2])]);
}

Vec3 ElementTree::centroid(int n) const {
  const auto& v = nodes_[static_cast<size_t>(n)].v;
  return (positions_[static_cast<size_t>(v[0])] + positions_[static_cast<size_t>(v[1])] +
          positions_[static_cast<size_t>(v[2])]) /
         3.0;
}

ElementTree::MidpointKey ElementTree::midpoint_key(int root, int a, int b, const std::array<double, 2>& ba,
                                                  const std::array<double, 2>& bb) {
  // Both ends on one edge of the root (v = 0, u = 0 or u + v = 1 at both:
  // exact, the coordinates are dyadic): the midpoint is on that edge.
  const bool on_edge = (ba[1] == 0.0 && bb[1] == 0.0) || (ba[0] == 0.0 && bb[0] == 0.0) ||
                       (ba[0] + ba[1] == 1.0 && bb[0] + bb[1] == 1.0);
  return {on_edge ? -1 : root, std::min(a, b), std::max(a, b)};
}

int ElementTree::midpoint(int root, int a, int b) const {
  const MidpointKey key = root >= 0 ? midpoint_key(root, a, b, barycentric(root, a), barycentric(root, b))
                                    : MidpointKey{-1, std::min(a, b), std::max(a, b)};
  auto it = midpoints_.find(key);
  return it == midpoints_.end() ? -1 : it->second;
}

std::vector<int> ElementTree::edge_points(int a, int b, int root) const {
  std::vector<int> out;
  std::function<void(int, int)> walk = [&](int x, int y) {
    const int m = midpoint(root, x, y);
    if (m < 0) return;
    walk(x, m);
    out.push_back(m);
    walk(m, y);
  };
  walk(a, b);
  return out;
}

int ElementTree::split_until_conforming() {
  int splits = 0;
  for (bool changed = true; changed;) {
    changed = false;
    for (int n = 0; n < static_cast<int>(nodes_.size()); ++n) {
      if (!is_leaf(n)) continue;
      const auto v = nodes_[static_cast<size_t>(n)].v;
      const int root = nodes_[static_cast<size_t>(n)].root;
      bool hanging = false;
      for (int k = 0; k < 3 && !hanging; ++k)
        hanging = midpoint(root, v[static_cast<size_t>(k)], v[static_cast<size_t>((k + 1) % 3)]) >= 0;
      if (hanging) {
        split(n);
        ++splits;
        changed = true;
      }
    }
  }
  return splits;
}

Mesh ElementTree::conforming_mesh(std::vector<int>* leaf_of) const {
  Mesh out;
  out.positions = positions_;
  if (leaf_of) leaf_of->clear();
  for (int n : leaves()) {
    const Node& node = nodes_[static_cast<size_t>(n)];
    out.triangles.push_back(node.v);
    out.patch.push_back(node.patch);
    if (leaf_of) leaf_of->push_back(n);
    // Each T-vertex run along an edge a->b of the leaf gets a fan from a:
    // (b, a, m_k), (m_k, a, m_k-1), ..., (m_2, a, m_1); every directed edge
    // then has its opposite once, and the fan has no area.
    for (int k = 0; k < 3; ++k) {
      const int a = node.v[static_cast<size_t>(k)], b = node.v[static_cast<size_t>((k + 1) % 3)];
      const std::vector<int> m = edge_points(a, b, node.root);
      if (m.empty()) continue;
      int prev = b;
      for (size_t i = m.size(); i-- > 0;) {
        out.triangles.push_back({prev, a, m[i]});
        out.patch.push_back(node.patch);
        if (leaf_of) leaf_of->push_back(-1);
        prev = m[i];
      }
    }
  }
  // Feature edges of the initial mesh, cut at the vertices splits put on them.
  for (const auto& e : features_) {
    int prev = e[0];
    for (int m : edge_points(e[0], e[1], -1)) {
      out.feature_edges.push_back({std::min(prev, m), std::max(prev, m)});
      prev = m;
    }
    out.feature_edges.push_back({std::min(prev, e[1]), std::max(prev, e[1])});
  }
  return out;
}

}  // namespace radmesh
