// The classic full-matrix method as an entry of the method table.

#include "radmesh/method.h"
#include "radmesh/run.h"
#include "radmesh/solve.h"

namespace radmesh {

namespace {

constexpr const char* kName = "matrix";

// No options of its own.
const OptionTable<MatrixOptions>& matrix_option_table() {
  static const OptionTable<MatrixOptions> table("method matrix");
  return table;
}

}  // namespace

Method make_matrix_method() {
  Method m = make_method<MatrixOptions>(
      kName, "every element pair of the initial mesh (the classic full-matrix method)", matrix_option_table(),
      [](const Scene& scene, const Mesh& mesh, const SolveOptions& so, const MatrixOptions&, const SolveCallbacks& cb) {
        MethodResult r;
        r.mesh = mesh;
        r.solution = solve_matrix(scene, mesh, so, cb.progress);
        const SolveStats& st = r.solution.stats;
        r.counters = {count_series("iterations",
                                   {static_cast<double>(st.iterations[0]), static_cast<double>(st.iterations[1]),
                                    static_cast<double>(st.iterations[2])}),
                      count("channels_solved", st.channels_solved)};
        r.seconds = {{"form_factors", st.seconds_form_factors}, {"solve", st.seconds_solve}};
        return r;
      });
  m.meshing = [](const Scene&) {
    MeshingOptions mo;  // the meshing defaults: diagonal / 12, full discontinuity meshing
    // Its elements are its unknowns: a face left coarse beside a narrow
    // strip (a carpet's edge 1 mm up a wall) would come out dark.
    mo.refine_narrow_strips = true;
    return mo;
  };
  return m;
}

Result solve(const Scene& scene, const MatrixOptions& options, const SolveOptions& common,
             const SolveCallbacks& callbacks) {
  return solve(scene, find_method(kName), MethodOptions::checked(matrix_option_table(), options), common, callbacks);
}

}  // namespace radmesh
