// A fourth method, defined here and nowhere else: the full matrix solved by
// Gauss-Seidel sweeps in reverse element order (the matrix method sweeps
// forward). It exists to show that the method contract is closed:
// added to the table from outside the library (add_method), with the public
// API alone, it runs every conformance test (test_methods.cpp) with no edit
// there. Linked into test_methods only.

#include "radmesh/method.h"
#include "radmesh/solve.h"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace {

using namespace radmesh;

struct ReverseOptions {
  int max_sweeps = 100000;
};

// B = E + rho F B, each element updated in place, from the last to the
// first. It stops when the a-posteriori bound q / (1 - q) x (the sweep's
// change) on the max-norm error, q the largest rho x row sum, is within the
// tolerance of the largest radiosity.
MethodResult solve_reverse(const Scene& scene, const Mesh& mesh, const SolveOptions& so, const ReverseOptions& o,
                          const SolveCallbacks& cb) {
  const auto start = std::chrono::steady_clock::now();
  MethodResult r;
  r.mesh = mesh;
  SolveStats& st = r.solution.stats;
  const std::vector<double> F = form_factor_matrix(scene, mesh, so, st, cb.progress);
  const size_t n = static_cast<size_t>(mesh.triangle_count());
  std::vector<Rgb> rho(n), emission(n);
  std::vector<double> area(n), row(n, 0.0);
  double q = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const Material& m = scene.material_of(mesh.patch[i]);
    rho[i] = m.reflectance;
    emission[i] = m.emission;
    area[i] = mesh.area(static_cast<int>(i));
    for (size_t j = 0; j < n; ++j) row[i] += F[i * n + j];
    q = std::max(q, max3(rho[i]) * row[i]);
  }
  std::vector<Rgb> B = emission, H(n);
  int sweeps = 0;
  double change = 0.0, top = 0.0;
  for (; sweeps < o.max_sweeps; ++sweeps) {
    change = top = 0.0;
    for (size_t i = n; i-- > 0;) {
      Rgb h(0.0);
      for (size_t j = 0; j < n; ++j) h += F[i * n + j] * B[j];
      H[i] = h;
      const Rgb b = emission[i] + rho[i] * h;
      change = std::max(change, max3(glm::abs(b - B[i])));
      top = std::max(top, max3(b));
      B[i] = b;
    }
    if (q < 1.0 && q / (1.0 - q) * change <= so.tolerance * top) {
      ++sweeps;
      break;
    }
  }
  r.solution.element = B;
  for (size_t c = 0; c < 3; ++c) {
    st.iterations[c] = sweeps;
    st.residual[c] = top > 0.0 ? change / top : 0.0;
    st.error_bound[c] = q < 1.0 ? q / (1.0 - q) * st.residual[c] : -1.0;
  }
  // Emitted = absorbed + escaped: what arrives is absorbed but its
  // reflected part; what leaves an element beyond its row sum escapes.
  for (size_t i = 0; i < n; ++i) {
    st.power_emitted += area[i] * emission[i];
    st.power_absorbed += area[i] * (Rgb(1.0) - rho[i]) * H[i];
    st.power_escaped += area[i] * B[i] * (1.0 - row[i]);
  }
  st.elements = static_cast<long long>(n);
  r.solution.nodal = compute_nodal(scene, mesh, B, so.crease_angle, nodal_method(so.field));
  r.counters = {count("sweeps", sweeps)};
  r.seconds = {{"solve", std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()}};
  return r;
}

Method make_reverse_method() {
  static const OptionTable<ReverseOptions> table =
      OptionTable<ReverseOptions>("method reverse_sweeps")
          .integer("max_sweeps", &ReverseOptions::max_sweeps, "", "most sweeps", 1, 1e6);
  Method m = make_method<ReverseOptions>("reverse_sweeps", "the full matrix solved by Gauss-Seidel sweeps in reverse order (a test)", table,
                                        solve_reverse);
  m.meshing = [](const Scene&) {
    MeshingOptions mo;
    mo.refine_narrow_strips = true;
    return mo;
  };
  return m;
}

[[maybe_unused]] const bool registered = (add_method(make_reverse_method()), true);

}  // namespace
