// The common case in one call: a scene meshed as the method recommends,
// solved, and its field made. The result holds a copy of its scene, so that
// it can be written (write_vtu(path, result), write_summary(path, result))
// and asked (result.patch_means()) as it is:
//
//   radmesh::HierarchicalOptions options;
//   options.epsilon = 0.01;
//   const radmesh::Result result = radmesh::solve(radmesh::read_scene("room.obj"), options);
//   radmesh::write_vtu("radiosity.vtu", result);
//
// A mesh of one's own, or a method of the table by name with options as
// text, go through run_method (method.h).
#pragma once

#include "radmesh/hierarchical.h"
#include "radmesh/method.h"
#include "radmesh/pixmap.h"
#include "radmesh/solve.h"

#include <memory>
#include <string>
#include <vector>

namespace radmesh {

struct Result : MethodResult {
  std::shared_ptr<const Scene> scene;
  std::string method;                // the method's name in the table
  std::string preset = "default";    // the preset its options were filled from (apply_preset)
  std::vector<OptionValue> options;  // the method's options as solved with
  SolveOptions solve_options;
  MeshingOptions meshing;            // the initial meshing, resolved
  MeshReport mesh_report;            // what the initial meshing did

  // Per patch: the mean of the field users see (the per-vertex values,
  // linear over each triangle), as the summary writes it.
  std::vector<Rgb> patch_means() const;
  // Per patch: the area mean of the element values (what the solver itself computed).
  std::vector<Rgb> element_patch_means() const;
};

// Each method with its own options struct. `common` holds the options every
// method shares; one that the method does not use (SolveOptions::rays with
// the pixmap method) is an InputError when it differs from its default.
Result solve(const Scene& scene, const MatrixOptions& options, const SolveOptions& common = {},
             const SolveCallbacks& callbacks = {});
Result solve(const Scene& scene, const HierarchicalOptions& options, const SolveOptions& common = {},
             const SolveCallbacks& callbacks = {});
Result solve(const Scene& scene, const PixmapOptions& options, const SolveOptions& common = {},
             const SolveCallbacks& callbacks = {});
// A method of the table by name, its options as text (the program's names).
Result solve(const Scene& scene, const std::string& method, const OptionValues& options = {},
             const SolveOptions& common = {}, const SolveCallbacks& callbacks = {});
// Any method with options already read (Method::parse); what the typed
// forms above call. `meshing`: meshing options by name, as text, applied
// on top of the method's recommended meshing, as the radmesh program's
// --max-edge, --discontinuity, ... are.
Result solve(const Scene& scene, const Method& method, const MethodOptions& options, const SolveOptions& common,
             const SolveCallbacks& callbacks, const OptionValues& meshing = {});

}  // namespace radmesh
