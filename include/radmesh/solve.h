// Radiosity solvers. The classic full-matrix method is the reference.
#pragma once

#include "radmesh/mesh.h"
#include "radmesh/options.h"
#include "radmesh/progress.h"
#include "radmesh/scene.h"
#include "radmesh/form_factor.h"
#include "radmesh/solution.h"

#include <memory>
#include <string>
#include <vector>

namespace radmesh {

enum class NodalMethod { mean, linear_fit };

// How the field users see (per-vertex radiosity) is made from a solution:
// gather (exact direct light and a final gather at every vertex, field.h),
// fit or mean (from the element values, compute_nodal); automatic: gather
// where its cost, (display vertices) x (patches), is within
// kGatherBudget, else fit, saying so (resolve_field_mode).
// own: the method's own field (Method::own_field: the pixmap method's
// bilinear interpolation of texel centres), what automatic keeps for a
// method that has one; not a value to ask for.
enum class FieldMode { automatic, gather, fit, mean, own };
// "auto", "gather", "fit", "mean"; InputError naming the value otherwise.
FieldMode parse_field_mode(const std::string& text);
std::string to_string(FieldMode mode);
// The element-value interpolation a solver uses for its own field: mean for
// `mean`, the linear fit otherwise.
NodalMethod nodal_method(FieldMode mode);

struct SolveOptions {
  // Gauss-Seidel stops when the largest change of a sweep is below
  // tolerance * (largest radiosity); the final residual is reported.
  double tolerance = 1e-6;
  int max_iterations = 100000;
  // Worker threads (0 = all cores). Results do not depend on it.
  int threads = 0;
  // Shadow rays per element pair; rounded up to a perfect square (stratified).
  int rays = 16;
  // Receiver quadrature of the point-to-polygon formula. Level 1 by default:
  // finer levels do not lower the field's error (the mesh's discretization
  // dominates), and level 1 still gives adjacent elements more points.
  QuadratureOptions quadrature{1.0, 1};
  // Memory limit, GiB (0 = half the physical memory): the form-factor matrix
  // (matrix method) or the whole process while it solves (hierarchical
  // method: its resident memory, and its links, leaf terms and clusters as
  // they are made).
  double max_memory = 0.0;
  // Vertex values are averaged only over triangles of one material whose
  // normals differ by less than this angle (degrees).
  double crease_angle = 20.0;
  // How vertex values are made (see FieldMode). run_method applies it to the
  // method's result; a solver's own field (compute_nodal) uses
  // nodal_method(field). automatic by default, which is gather on every
  // scene of up to a few thousand patches: it gives a fraction of the
  // fit's error (docs/decisions.md).
  FieldMode field = FieldMode::automatic;
  // With the gather field: 0 shows the field on the solver's mesh; t > 0
  // refines the display by the field's own interpolation error, splitting
  // a display triangle (into four, T-vertices closed by zero-area
  // triangles) where the field at one of its edge midpoints differs from
  // the mean of the edge's ends by more than t x the largest reflected
  // radiosity (refine_display).
  double display_tolerance = 0.0;
};

// The options a user sets (tolerance, threads, rays, max_memory, field),
// with their ranges: the radmesh program's flags and the library's checks.
const OptionTable<SolveOptions>& solve_option_table();

// Checks option ranges (solve_option_table and the rest); throws InputError
// naming the option and the value.
void check_solve_options(const SolveOptions& options);

// The matrix method has no options of its own (radmesh::solve(scene,
// MatrixOptions{})).
struct MatrixOptions {};

// The memory limit in bytes: max_memory (GiB), or half the physical memory.
double memory_limit_bytes(const SolveOptions& options);

// The calling process's resident memory now, bytes (Linux: /proc/self/statm;
// 0 where the system does not say). The hierarchical solver holds it to the
// limit along with its own count of what it is about to hold.
double resident_memory_bytes();

// Classic radiosity: every element-to-element form factor, then Gauss-Seidel
// per colour channel. Refuses (NumericalError) a mesh whose matrix would not
// fit in memory, before any work starts. The one-off form of MatrixSolver.
Solution solve_matrix(const Scene& scene, const Mesh& mesh, const SolveOptions& options,
                      const ProgressFn& progress = {});

// The matrix method with its state: the form-factor matrix is computed once,
// in the constructor, and each solve() reuses it. solve(materials) relights
// the same geometry with other reflectances and emissions (one Material per
// scene material, same order) without computing a form factor again.
// `scene` must outlive the solver.
class MatrixSolver {
public:
  MatrixSolver(const Scene& scene, const Mesh& mesh, const SolveOptions& options, const ProgressFn& progress = {});
  ~MatrixSolver();
  MatrixSolver(const MatrixSolver&) = delete;
  MatrixSolver& operator=(const MatrixSolver&) = delete;

  Solution solve() const;
  Solution solve(const std::vector<Material>& materials) const;
  // Row-major n x n: F[i*n + j] = F(element i -> j), occlusion included.
  const std::vector<double>& form_factors() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The n x n form-factor matrix, row-major: F[i*n + j] = F(element i -> j),
// occlusion included. Fills the form-factor and ray counters of `stats`.
std::vector<double> form_factor_matrix(const Scene& scene, const Mesh& mesh, const SolveOptions& options,
                                       SolveStats& stats, const ProgressFn& progress = {});

// Bytes the full matrix of n elements needs.
double matrix_bytes(long long n);

// Per-vertex radiosity from per-element values, never averaged across a
// material change, a crease (see SolveOptions::crease_angle) or a
// discontinuity edge. `mean`: area-weighted mean of the elements around the
// vertex; `linear_fit`: least-squares plane through their values at their
// centroids, evaluated at the vertex (falls back to the mean when the
// centroids line up).
NodalField compute_nodal(const Scene& scene, const Mesh& mesh, const std::vector<Rgb>& element,
                         double crease_angle_degrees, NodalMethod method);

}  // namespace radmesh
