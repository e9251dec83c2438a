#include "meshing/mesh.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace radmesh {

TriangleQuality compute_quality(const Mesh& mesh) {
  TriangleQuality q;
  const int n = mesh.triangle_count();
  q.min_angle.resize(static_cast<size_t>(n));
  q.aspect_ratio.resize(static_cast<size_t>(n));
  for (int t = 0; t < n; ++t) {
    const auto& tri = mesh.triangles[static_cast<size_t>(t)];
    const Vec3 p[3] = {mesh.positions[tri[0]], mesh.positions[tri[1]], mesh.positions[tri[2]]};
    // Edge i is opposite vertex i.
    const double len[3] = {glm::length(p[2] - p[1]), glm::length(p[0] - p[2]),
                           glm::length(p[1] - p[0])};
    double min_angle = 180.0;
    for (int i = 0; i < 3; ++i) {
      const Vec3 u = p[(i + 1) % 3] - p[i];
      const Vec3 v = p[(i + 2) % 3] - p[i];
      // atan2 form is accurate for tiny and near-180 angles alike.
      const double a = std::atan2(glm::length(glm::cross(u, v)), glm::dot(u, v));
      min_angle = std::min(min_angle, a * 180.0 / std::numbers::pi);
    }
    const double area = mesh.area(t);
    const double s = 0.5 * (len[0] + len[1] + len[2]);
    const double longest = std::max({len[0], len[1], len[2]});
    double aspect = std::numeric_limits<double>::infinity();
    if (area > 0.0 && s > 0.0) {
      const double inradius = area / s;
      aspect = longest / (2.0 * std::sqrt(3.0) * inradius);
    }
    q.min_angle[static_cast<size_t>(t)] = min_angle;
    q.aspect_ratio[static_cast<size_t>(t)] = aspect;
  }
  return q;
}

}  // namespace radmesh
