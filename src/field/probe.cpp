// Probes: radiosity at points the user names, each on a surface that faces
// the probe's normal (a probe on none is an error, found before any work),
// evaluated as the gather field evaluates a vertex (FieldEvaluator).

#include "radmesh/probe.h"

#include "radmesh/errors.h"
#include "radmesh/field.h"
#include "core/text_syntax.h"
#include "field/field_impl.h"
#include "radiosity/transport/transport.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace radmesh {

namespace {

// |p - q|, without overflow where its square would pass double's range.
double distance(const Vec3& p, const Vec3& q) {
  const Vec3 d = p - q;
  const double m = std::max({std::abs(d.x), std::abs(d.y), std::abs(d.z)});
  return m > 0.0 && std::isfinite(m) ? m * glm::length(d / m) : m;
}

}  // namespace

std::vector<ProbeResult> evaluate_probes(const Scene& scene, const Mesh& mesh,
                                         const std::vector<Rgb>& element_radiosity,
                                         const std::vector<Probe>& probes, const SolveOptions& options) {
  check_solve_options(options);
  const double diag = scene.diagonal(), off_plane = 1e-6 * diag;
  const int n = mesh.triangle_count();
  // Locating a probe costs O(log n), not a pass over the mesh (many probes
  // on a large mesh).
  const BoxTree tree = internal::triangle_boxes(mesh);
  std::vector<ProbeResult> out(probes.size());
  // Locate every probe first, so that a bad one fails before any work.
  for (size_t k = 0; k < probes.size(); ++k) {
    const Probe& pr = probes[k];
    Box3 at;
    at.add(pr.point);
    int first = n;  // the first triangle the probe lies on, facing its way
    tree.overlapping(at, off_plane, [&](int t) {
      const auto& tri = mesh.triangles[static_cast<size_t>(t)];
      const Patch& patch = scene.patches[static_cast<size_t>(mesh.patch[static_cast<size_t>(t)])];
      const Vec3& a = mesh.positions[tri[0]];
      if (t < first && std::abs(glm::dot(pr.point - a, patch.normal)) <= off_plane &&
          glm::dot(pr.normal, patch.normal) >= 0.99 &&
          internal::inside_triangle(pr.point, a, mesh.positions[tri[1]], mesh.positions[tri[2]], 1e-9))
        first = t;
      return true;
    });
    if (first < n) {
      out[k].patch = mesh.patch[static_cast<size_t>(first)];
      continue;
    }
    double nearest = std::numeric_limits<double>::infinity();
    for (int t = 0; t < n; ++t) nearest = std::min(nearest, distance(pr.point, mesh.centroid(t)));
    std::ostringstream m;
    m << where(pr.file, pr.line) << "probe '" << internal::shown(pr.label) << "' at (" << pr.point.x << " "
      << pr.point.y << " " << pr.point.z << ") with normal (" << pr.normal.x << " " << pr.normal.y << " "
      << pr.normal.z << ") lies on no surface facing that way (nearest element centre " << nearest << " away)";
    throw InputError(m.str());
  }

  const FieldEvaluator field(scene, mesh, element_radiosity, options);
  run_in_arena(options.threads, [&] {
    tbb::parallel_for(size_t(0), probes.size(), [&](size_t k) {
      FieldReport report;
      // Seeds above any display vertex's: the probes' streams are their own.
      out[k].radiosity = field.radiosity(probes[k].point, out[k].patch, (uint64_t{1} << 40) + k, report);
    });
  });
  return out;
}

}  // namespace radmesh
