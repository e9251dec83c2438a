// Mesh quality for mesh studies: per triangle its smallest and largest
// angles and aspect ratio, per patch their summaries and the
// discontinuity segments and zero-area triangles it holds.

#include "radmesh/mesh.h"

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
  q.max_angle.resize(static_cast<size_t>(n));
  q.zero_area.resize(static_cast<size_t>(n));
  for (int t = 0; t < n; ++t) {
    const auto& tri = mesh.triangles[static_cast<size_t>(t)];
    const Vec3 p[3] = {mesh.positions[tri[0]], mesh.positions[tri[1]], mesh.positions[tri[2]]};
    // Edge i is opposite vertex i.
    const double len[3] = {glm::length(p[2] - p[1]), glm::length(p[0] - p[2]),
                           glm::length(p[1] - p[0])};
    double min_angle = 180.0, max_angle = 0.0;
    for (int i = 0; i < 3; ++i) {
      const Vec3 u = p[(i + 1) % 3] - p[i];
      const Vec3 v = p[(i + 2) % 3] - p[i];
      // atan2 form is accurate for tiny and near-180 angles alike.
      const double a = std::atan2(glm::length(glm::cross(u, v)), glm::dot(u, v));
      min_angle = std::min(min_angle, a * 180.0 / std::numbers::pi);
      max_angle = std::max(max_angle, a * 180.0 / std::numbers::pi);
    }
    const double area = mesh.area(t);
    const double s = 0.5 * (len[0] + len[1] + len[2]);
    const double longest = std::max({len[0], len[1], len[2]});
    double aspect = std::numeric_limits<double>::infinity();
    if (area > 0.0 && s > 0.0) {
      const double inradius = area / s;
      aspect = longest / (2.0 * std::sqrt(3.0) * inradius);
    }
    q.zero_area[static_cast<size_t>(t)] = mesh.zero_area(t);
    if (q.zero_area[static_cast<size_t>(t)]) {  // no shape worth the name: 0 and 180 degrees, aspect 0 (never inf in a file)
      min_angle = 0.0;
      max_angle = 180.0;
      aspect = 0.0;
    }
    q.min_angle[static_cast<size_t>(t)] = min_angle;
    q.max_angle[static_cast<size_t>(t)] = max_angle;
    q.aspect_ratio[static_cast<size_t>(t)] = aspect;
  }
  return q;
}

double percentile(std::vector<double> v, double q) {
  v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return !std::isfinite(x); }), v.end());
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double rank = std::ceil(q * static_cast<double>(v.size()));
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(std::max(rank, 1.0)) - 1);
  return v[k];
}

std::vector<PatchQuality> patch_quality(int patch_count, const Mesh& mesh, const TriangleQuality& quality,
                                        const std::vector<DiscontinuitySegment>& discontinuities) {
  const size_t np = static_cast<size_t>(std::max(patch_count, 0));
  std::vector<std::vector<int>> tris(np + 1);  // last: all
  for (int t = 0; t < mesh.triangle_count(); ++t) {
    tris[static_cast<size_t>(mesh.patch[static_cast<size_t>(t)])].push_back(t);
    tris[np].push_back(t);
  }
  std::vector<PatchQuality> rows(np + 1);
  auto count = [](PatchQuality& r, int kind) {
    ++(kind == 0 ? r.contact_segments : kind == 1 ? r.d1_segments : r.d2_segments);
  };
  for (const DiscontinuitySegment& d : discontinuities) {  // segment counts per patch and in total
    if (d.patch >= 0 && static_cast<size_t>(d.patch) < np) count(rows[static_cast<size_t>(d.patch)], d.kind);
    count(rows[np], d.kind);
  }
  for (size_t p = 0; p <= np; ++p) {
    PatchQuality& r = rows[p];
    r.patch = p < np ? static_cast<int>(p) : -1;
    r.triangles = static_cast<int>(tris[p].size());
    std::vector<double> aspect;
    double min_angle = 180.0;
    for (int t : tris[p]) {
      const size_t u = static_cast<size_t>(t);
      if (quality.zero_area[u]) {  // counted apart: they have no shape to speak of
        ++r.zero_area;
        continue;
      }
      min_angle = std::min(min_angle, quality.min_angle[u]);
      r.max_angle = std::max(r.max_angle, quality.max_angle[u]);
      aspect.push_back(quality.aspect_ratio[u]);
    }
    r.min_angle = aspect.empty() ? 0.0 : min_angle;  // no triangle with area: nothing to report
    r.aspect_p50 = percentile(aspect, 0.5);
    r.aspect_p95 = percentile(aspect, 0.95);
    r.aspect_max = percentile(aspect, 1.0);
  }
  return rows;
}

}  // namespace radmesh
