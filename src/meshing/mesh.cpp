#include "radmesh/mesh.h"

#include <algorithm>

namespace radmesh {

double Mesh::area(int t) const {
  const auto& tri = triangles[static_cast<size_t>(t)];
  return triangle_area(positions[tri[0]], positions[tri[1]], positions[tri[2]]);
}

bool Mesh::zero_area(int t) const {
  const auto& tri = triangles[static_cast<size_t>(t)];
  const Vec3 &a = positions[tri[0]], &b = positions[tri[1]], &c = positions[tri[2]];
  const double longest = std::max({glm::length(b - a), glm::length(c - b), glm::length(a - c)});
  return area(t) <= 1e-12 * longest * longest;
}

Vec3 Mesh::centroid(int t) const {
  const auto& tri = triangles[static_cast<size_t>(t)];
  return (positions[tri[0]] + positions[tri[1]] + positions[tri[2]]) / 3.0;
}

FeatureEdges::FeatureEdges(const Mesh& mesh) {
  keys_.reserve(mesh.feature_edges.size());
  for (const auto& e : mesh.feature_edges) keys_.push_back(undirected_edge_key(e[0], e[1]));
  std::sort(keys_.begin(), keys_.end());
}

bool FeatureEdges::contains(int a, int b) const {
  return std::binary_search(keys_.begin(), keys_.end(), undirected_edge_key(a, b));
}

}  // namespace radmesh
