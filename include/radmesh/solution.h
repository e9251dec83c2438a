// What a radiosity solve produces: per-element and per-vertex radiosity plus counters.
#pragma once

#include "radmesh/geometry.h"
#include "radmesh/mesh.h"
#include "radmesh/scene.h"

#include <array>
#include <string>
#include <vector>

namespace radmesh {

// Radiosity at the vertices of the display mesh. The display mesh is the
// solver's mesh with vertices duplicated where the surface has a crease or the
// material changes, so that values are never averaged across them.
struct NodalField {
  std::vector<Vec3> points;                  // display vertices
  std::vector<int> source_vertex;            // per display vertex: index into Mesh::positions
  std::vector<std::array<int, 3>> corners;   // per triangle: display vertex indices
  std::vector<Rgb> radiosity;                // per display vertex
  // Per triangle, when the field was also sampled inside the triangles (a
  // refined display: the midpoints of their edges), each triangle's mean
  // by a rule exact for quadratic fields, which patch means integrate;
  // empty otherwise (patch means integrate the vertex values' linear
  // interpolation).
  std::vector<Rgb> triangle_mean;
};

struct SolveStats {
  long long elements = 0;
  long long form_factors = 0;          // entries of F computed (hierarchical: its links)
  long long form_factors_skipped = 0;  // entries never needed (rows of black receivers, ...)
  long long receiver_points = 0;       // quadrature points over all receivers
  long long rays_cast = 0;
  long long rays_skipped = 0;          // shadow rays not cast because nothing can occlude
  long long pairs_unoccludable = 0;    // element pairs that no patch can occlude
  bool convex_enclosure = false;       // the scene is one convex enclosure: no rays at all
  // The matrix method's Gauss-Seidel: distinct channels solved (identical
  // ones are solved once) and iterations per channel. Other methods leave
  // them 0 and publish their own counts (e.g. hierarchical "sweeps").
  int channels_solved = 0;
  std::array<int, 3> iterations{0, 0, 0};
  std::array<double, 3> residual{0, 0, 0};  // final relative residual per channel
  // What the residual guarantees: max |B - B_exact| / max |B| per channel is
  // at most this (residual / (1 - max rho x row sum)); -1 where the scene's
  // rho F gives no bound (a row sum times rho of 1 or more).
  std::array<double, 3> error_bound{0, 0, 0};
  int extrapolations = 0;  // Aitken steps of the iteration (SweepMonitor)
  double seconds_form_factors = 0.0;  // form factors (hierarchical: linking)
  double seconds_solve = 0.0;
  // Energy balance (per channel): emitted = absorbed + escaped, where
  // escaped is what each element radiates but the solve carries to no other
  // element (BalanceAccumulator): in a closed scene, the operator's leak.
  Rgb power_emitted{0.0};
  Rgb power_absorbed{0.0};
  Rgb power_escaped{0.0};
  std::vector<std::string> skips;      // human-readable list of what was skipped and why
  // What the solve found likely wrong with the scene (run_method adds them
  // to MethodResult::warnings): emitters inside closed objects.
  std::vector<std::string> warnings;
};

struct Solution {
  std::vector<Rgb> element;  // per mesh triangle
  NodalField nodal;
  SolveStats stats;
  // Per patch, where the mesh shown is not the solver's (a refined
  // display): the area-weighted mean of the solver's elements; empty
  // otherwise (element_patch_means computes it from `element`).
  std::vector<Rgb> element_patch_mean;
};

}  // namespace radmesh
