#include "meshing/mesh.h"

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

}  // namespace radmesh
