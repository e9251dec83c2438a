#include "meshing/mesh.h"

namespace radmesh {

double Mesh::area(int t) const {
  const auto& tri = triangles[static_cast<size_t>(t)];
  return triangle_area(positions[tri[0]], positions[tri[1]], positions[tri[2]]);
}

Vec3 Mesh::centroid(int t) const {
  const auto& tri = triangles[static_cast<size_t>(t)];
  return (positions[tri[0]] + positions[tri[1]] + positions[tri[2]]) / 3.0;
}

}  // namespace radmesh
