// The element hierarchy of hierarchical radiosity: every triangle of the
// initial mesh is the root of a tree, and a split makes four children at the
// edge midpoints. The leaves, closed by zero-area triangles at every
// T-vertex, form a conforming mesh.
#pragma once

#include "radmesh/geometry.h"
#include "radmesh/mesh.h"

#include <array>
#include <map>
#include <tuple>
#include <utility>
#include <vector>

namespace radmesh {

class ElementTree {
public:
  struct Node {
    std::array<int, 3> v{};  // vertex ids, counter-clockwise around the patch normal
    int patch = -1;
    int root = -1;           // the initial-mesh triangle this node descends from
    int parent = -1;
    int child = -1;          // first of four consecutive children, -1 for a leaf
    int level = 0;
  };

  // One root per triangle of `mesh`; vertex ids 0 .. mesh.positions.size()-1
  // are the mesh's.
  explicit ElementTree(const Mesh& mesh);

  // Splits leaf n into four at its edge midpoints; returns the first child.
  // Children 0..2 sit at corners v[0], v[1], v[2]; child 3 is the middle
  // one. A midpoint already made by a neighbour is reused. Midpoints are
  // computed from the root's corners with dyadic barycentric coordinates,
  // which are exact in double down to level 52, so a deep split still puts
  // them exactly halfway (in those coordinates) and never drifts.
  int split(int n);

  const std::vector<Node>& nodes() const { return nodes_; }
  const Node& node(int n) const { return nodes_[static_cast<size_t>(n)]; }
  bool is_leaf(int n) const { return nodes_[static_cast<size_t>(n)].child < 0; }
  std::vector<int> leaves() const;
  int root_count() const { return roots_; }

  const std::vector<Vec3>& positions() const { return positions_; }
  // Barycentric coordinates (weights of corners 1 and 2) of a vertex in root
  // triangle `root`, which must contain it. Exact dyadic numbers.
  std::array<double, 2> barycentric(int root, int vertex) const;
  double area(int n) const;
  Vec3 centroid(int n) const;

  // The midpoint vertex of edge (a, b) of a node of root `root` (-1: an
  // edge of the initial mesh), or -1 when it was not split.
  int midpoint(int root, int a, int b) const;
  // The vertices strictly inside edge (a, b) of a node of root `root` (-1:
  // an edge of the initial mesh) made by splits (T-vertices), in order
  // from a to b.
  std::vector<int> edge_points(int a, int b, int root) const;

  // The conventional closure: splits leaves until no leaf edge has a
  // T-vertex. Returns the number of splits it made.
  int split_until_conforming();

  // The conforming mesh of the leaves: every leaf, then for every T-vertex a
  // fan of zero-area triangles along the unsplit edge. `leaf_of` (per output
  // triangle) is the leaf it belongs to, or -1 for a zero-area triangle.
  Mesh conforming_mesh(std::vector<int>* leaf_of = nullptr) const;

private:
  // Where a vertex made by a split lies: on an edge (p, q) of the initial
  // mesh (p < q) at parameter t, or inside root `root` at (u, v).
  struct Made {
    int p = -1, q = -1;
    double t = 0.0;
    int root = -1;
    double u = 0.0, v = 0.0;
  };
  int make_midpoint(int root, int a, int b);
  std::vector<std::array<int, 2>> features_;  // the initial mesh's feature edges
  std::vector<Node> nodes_;
  int roots_ = 0;
  int initial_vertices_ = 0;
  std::vector<Vec3> positions_;
  std::vector<Made> made_;  // per vertex made by a split (index - initial_vertices_)
  // A midpoint's key: its edge's ends (min id, max id) and, for a point
  // inside a root, that root (-1 for one on an initial edge, which the
  // roots sharing that edge share). Two roots on the same three corners
  // (the two sides of a panel, two blocks' faces in contact) share their
  // edges' points but not their insides.
  using MidpointKey = std::tuple<int, int, int>;
  // The key of the midpoint of (a, b) of root `root`, from their
  // barycentric coordinates ba, bb in it.
  static MidpointKey midpoint_key(int root, int a, int b, const std::array<double, 2>& ba,
                                  const std::array<double, 2>& bb);
  std::map<MidpointKey, int> midpoints_;
};

}  // namespace radmesh
