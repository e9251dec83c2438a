// Radiosity at user-given surface points, evaluated as the gather field is.
#pragma once

#include "radmesh/mesh.h"
#include "radmesh/scene.h"
#include "radmesh/solve.h"

#include <string>
#include <vector>

namespace radmesh {

struct Probe {
  std::string label;
  Vec3 point{0.0};
  Vec3 normal{0.0};  // unit; must agree with the surface's normal
  std::string file;  // where it was read (for messages)
  int line = 0;
};

struct ProbeResult {
  int patch = -1;      // the patch the point lies on
  Rgb radiosity{0.0};  // B = E + rho * (gathered irradiance)
};

// For each probe: finds the patch under it (InputError naming the probe's
// file:line when it lies on no surface facing its normal), then evaluates B
// there as the gather field does (FieldEvaluator: emission, exact direct
// light, and the indirect light gathered from the element radiosity).
std::vector<ProbeResult> evaluate_probes(const Scene& scene, const Mesh& mesh,
                                         const std::vector<Rgb>& element_radiosity,
                                         const std::vector<Probe>& probes, const SolveOptions& options);

}  // namespace radmesh
