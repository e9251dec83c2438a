// Small geometric measures shared by every part: triangle area, loop
// length, the distance from a point to a segment.

#include "radmesh/geometry.h"

#include <algorithm>

namespace radmesh {

Vec3 newell_normal(const std::vector<Vec3>& loop) {
  Vec3 n(0.0);
  const size_t k = loop.size();
  for (size_t i = 0; i < k; ++i) {
    const Vec3& a = loop[i];
    const Vec3& b = loop[(i + 1) % k];
    n.x += (a.y - b.y) * (a.z + b.z);
    n.y += (a.z - b.z) * (a.x + b.x);
    n.z += (a.x - b.x) * (a.y + b.y);
  }
  return n;
}

double loop_length(const std::vector<Vec3>& loop) {
  double length = 0.0;
  for (size_t i = 0; i < loop.size(); ++i) length += glm::length(loop[(i + 1) % loop.size()] - loop[i]);
  return length;
}

double triangle_area(const Vec3& a, const Vec3& b, const Vec3& c) {
  return 0.5 * glm::length(glm::cross(b - a, c - a));
}

double point_segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double t = std::clamp(glm::dot(p - a, ab) / std::max(glm::dot(ab, ab), 1e-300), 0.0, 1.0);
  return glm::length(p - (a + t * ab));
}

}  // namespace radmesh
