// The error metric tests and benchmarks share: stratified sample points
// on every surface, the per-vertex field (or the element values) at them,
// and the area-weighted relative L2, L-infinity and per-patch errors of the
// reflected part B - E against a reference.

#include "radmesh/error_metric.h"

#include "radmesh/errors.h"
#include "radiosity/transport/sampling.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace radmesh {

std::vector<SurfaceSample> surface_samples(const Scene& scene, int count) {
  const Mesh coarse = triangulate_patches(scene);
  double total = 0.0;
  for (int t = 0; t < coarse.triangle_count(); ++t) total += coarse.area(t);
  std::vector<SurfaceSample> out;
  for (int t = 0; t < coarse.triangle_count(); ++t) {
    const double a = coarse.area(t);
    if (a <= 0.0) continue;
    const int side = std::max(1, static_cast<int>(std::lround(std::sqrt(count * a / total))));
    const auto& tri = coarse.triangles[static_cast<size_t>(t)];
    const Vec3& p0 = coarse.positions[static_cast<size_t>(tri[0])];
    const Vec3& p1 = coarse.positions[static_cast<size_t>(tri[1])];
    const Vec3& p2 = coarse.positions[static_cast<size_t>(tri[2])];
    SplitMix rng(pair_seed(0x5A3Du, static_cast<uint64_t>(t)));
    for (int i = 0; i < side; ++i)
      for (int j = 0; j < side; ++j) {
        // Jittered strata, kept away from the edges by the jitter range.
        const double u = (i + 0.1 + 0.8 * rng.uniform()) / side;
        const double v = (j + 0.1 + 0.8 * rng.uniform()) / side;
        out.push_back({coarse.patch[static_cast<size_t>(t)], triangle_point(p0, p1, p2, u, v),
                       a / (side * side)});
      }
  }
  return out;
}

namespace {

struct Location {
  int triangle;
  double u, v;  // barycentric weights of the triangle's first two corners
};

// The mesh triangle of each sample's patch that contains it.
std::vector<Location> locate(const Scene& scene, const Mesh& mesh, const std::vector<SurfaceSample>& samples) {
  std::vector<std::vector<int>> by_patch(scene.patches.size());
  for (int t = 0; t < mesh.triangle_count(); ++t)
    if (!mesh.zero_area(t))  // no area, so no sample lies on it (its corners are a leaf's)
      by_patch[static_cast<size_t>(mesh.patch[static_cast<size_t>(t)])].push_back(t);
  std::vector<Location> out(samples.size());
  for (size_t k = 0; k < samples.size(); ++k) {
    const SurfaceSample& s = samples[k];
    Location best{-1, 0.0, 0.0};
    double best_out = 1e300;
    for (int t : by_patch[static_cast<size_t>(s.patch)]) {
      const auto& tri = mesh.triangles[static_cast<size_t>(t)];
      const Vec3& a = mesh.positions[static_cast<size_t>(tri[0])];
      const Vec3& b = mesh.positions[static_cast<size_t>(tri[1])];
      const Vec3& c = mesh.positions[static_cast<size_t>(tri[2])];
      const Vec3 n = glm::cross(b - a, c - a);
      const double nn = glm::dot(n, n);
      if (nn <= 0.0) continue;
      const double u = glm::dot(glm::cross(c - b, s.x - b), n) / nn;  // weight of a
      const double v = glm::dot(glm::cross(a - c, s.x - c), n) / nn;  // weight of b
      const double outside = std::max({0.0, -u, -v, -(1.0 - u - v)});
      if (outside < best_out) {
        best_out = outside;
        best = {t, u, v};
      }
      if (outside == 0.0) break;
    }
    if (best.triangle < 0 || best_out > 1e-6)
      throw GeometryError("error metric: sample point lies on no triangle of patch " + std::to_string(s.patch));
    out[k] = best;
  }
  return out;
}

}  // namespace

std::vector<Rgb> interpolate_nodal(const Scene& scene, const Mesh& mesh, const NodalField& nodal,
                                   const std::vector<SurfaceSample>& samples) {
  std::vector<Rgb> out;
  for (const Location& l : locate(scene, mesh, samples)) {
    const auto& c = nodal.corners[static_cast<size_t>(l.triangle)];
    out.push_back(l.u * nodal.radiosity[static_cast<size_t>(c[0])] + l.v * nodal.radiosity[static_cast<size_t>(c[1])] +
                  (1.0 - l.u - l.v) * nodal.radiosity[static_cast<size_t>(c[2])]);
  }
  return out;
}

std::vector<Rgb> element_values(const Scene& scene, const Mesh& mesh, const std::vector<Rgb>& element,
                                const std::vector<SurfaceSample>& samples) {
  std::vector<Rgb> out;
  for (const Location& l : locate(scene, mesh, samples)) out.push_back(element[static_cast<size_t>(l.triangle)]);
  return out;
}

FieldError field_error(const std::vector<SurfaceSample>& samples, const std::vector<Rgb>& values,
                       const std::vector<Rgb>& reference) {
  FieldError e;
  double num = 0.0, den = 0.0, max_diff = 0.0, max_ref = 0.0;
  struct Mean {
    Rgb v{0.0}, r{0.0};
    double w = 0.0;
  };
  std::map<int, Mean> means;  // per patch: sums of w v, w r and w
  for (size_t k = 0; k < samples.size(); ++k) {
    const Rgb d = values[k] - reference[k];
    num += samples[k].weight * glm::dot(d, d);
    den += samples[k].weight * glm::dot(reference[k], reference[k]);
    for (int c = 0; c < 3; ++c) {
      max_diff = std::max(max_diff, std::abs(d[c]));
      max_ref = std::max(max_ref, std::abs(reference[k][c]));
    }
    auto& m = means[samples[k].patch];
    m.v += samples[k].weight * values[k];
    m.r += samples[k].weight * reference[k];
    m.w += samples[k].weight;
  }
  e.l2 = den > 0.0 ? std::sqrt(num / den) : std::sqrt(num);
  e.linf = max_ref > 0.0 ? max_diff / max_ref : max_diff;
  for (const auto& [p, m] : means)
    for (int c = 0; c < 3; ++c)
      if (std::abs(m.r[c]) > 1e-9 * max_ref * m.w) {  // skip black patches
        const double rel = std::abs(m.v[c] / m.r[c] - 1.0);
        if (rel > e.patch_mean) {
          e.patch_mean = rel;
          e.worst_patch = p;
        }
      }
  return e;
}

}  // namespace radmesh

namespace radmesh {

std::vector<Rgb> reflected_part(const Scene& scene, const std::vector<SurfaceSample>& samples,
                                std::vector<Rgb> radiosity) {
  for (size_t k = 0; k < samples.size(); ++k)
    radiosity[k] -= scene.material_of(samples[k].patch).emission;
  return radiosity;
}

}  // namespace radmesh
