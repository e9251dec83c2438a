// The error metric shared by tests and benchmarks: the per-vertex linear
// field users see, compared with a reference field at fixed stratified points
// on every surface.
#pragma once

#include "radmesh/mesh.h"
#include "radmesh/scene.h"
#include "radmesh/solution.h"

#include <vector>

namespace radmesh {

struct SurfaceSample {
  int patch = -1;
  Vec3 x{0.0};
  double weight = 0.0;  // the area it stands for
};

// About `count` stratified points over all patches, proportional to area (at
// least one per triangle of each patch's coarse triangulation). Deterministic:
// the same scene gives the same points.
std::vector<SurfaceSample> surface_samples(const Scene& scene, int count);

// The per-vertex linear interpolant of `nodal` at every sample (on the mesh
// triangle of the sample's patch that contains it). Throws GeometryError when
// a sample lies on no triangle of its patch.
std::vector<Rgb> interpolate_nodal(const Scene& scene, const Mesh& mesh, const NodalField& nodal,
                                   const std::vector<SurfaceSample>& samples);

// The piecewise-constant element field at every sample (the element containing it).
std::vector<Rgb> element_values(const Scene& scene, const Mesh& mesh, const std::vector<Rgb>& element,
                                const std::vector<SurfaceSample>& samples);

struct FieldError {
  double l2 = 0.0;          // sqrt(sum w |v - r|^2) / sqrt(sum w |r|^2), all channels
  double linf = 0.0;        // max |v - r| / max |r|
  double patch_mean = 0.0;  // worst relative error of a patch's mean (patches with a non-zero mean)
  int worst_patch = -1;     // the patch with that error
};

// B - E at every sample: the reflected part, which is what a solver computes
// (E is input, exact). Benchmarks measure errors on it, so that a bright
// emitter does not dominate the norms.
std::vector<Rgb> reflected_part(const Scene& scene, const std::vector<SurfaceSample>& samples,
                                std::vector<Rgb> radiosity);

FieldError field_error(const std::vector<SurfaceSample>& samples, const std::vector<Rgb>& values,
                       const std::vector<Rgb>& reference);

}  // namespace radmesh
