// radmesh::solve: mesh, solve and field in one call, for any method of the
// table; the typed forms live beside their methods (*/method.cpp).

#include "radmesh/run.h"

#include "radmesh/field.h"

namespace radmesh {

Result solve(const Scene& scene, const Method& method, const MethodOptions& options, const SolveOptions& common,
             const SolveCallbacks& callbacks, const OptionValues& meshing) {
  check_solve_options(common);
  std::vector<std::string> given = solve_option_table().changed(common);
  for (const auto& entry : meshing) given.push_back(entry.first);
  check_shared_options(method, given, common.field);
  Result r;
  r.scene = std::make_shared<const Scene>(scene);
  r.method = method.name;
  r.options = options.values();
  r.solve_options = common;
  MeshingOptions recommended = method.meshing(scene);
  meshing_option_table().apply(recommended, meshing);
  r.meshing = resolve_meshing_options(scene, recommended);
  const Mesh mesh = mesh_scene(scene, r.meshing, &r.mesh_report);
  static_cast<MethodResult&>(r) = run_method(method, *r.scene, mesh, common, options, callbacks);
  return r;
}

Result solve(const Scene& scene, const std::string& method, const OptionValues& options, const SolveOptions& common,
             const SolveCallbacks& callbacks) {
  const Method& m = find_method(method);
  return solve(scene, m, method_options(m, options), common, callbacks);
}

std::vector<Rgb> Result::patch_means() const { return patch_mean_radiosity(*scene, mesh, solution.nodal); }

std::vector<Rgb> Result::element_patch_means() const {
  return radmesh::element_patch_means(*scene, mesh, solution);
}

}  // namespace radmesh
