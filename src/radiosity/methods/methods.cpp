// The table of radiosity methods and the option machinery they share.

#include "radmesh/method.h"

#include "radmesh/errors.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <deque>
#include <new>
#include <set>

namespace radmesh {

Counter count(std::string name, double value, std::string unit) {
  return {std::move(name), {value}, std::move(unit), false, true};
}
Counter measure(std::string name, double value, std::string unit) {
  return {std::move(name), {value}, std::move(unit), false, false};
}
Counter count_series(std::string name, std::vector<double> values, std::string unit) {
  return {std::move(name), std::move(values), std::move(unit), true, true};
}

const Counter* MethodResult::counter(const std::string& name) const {
  for (const Counter& c : counters)
    if (c.name == name) return &c;
  return nullptr;
}

// ---- the table --------------------------------------------------------------

// Each method's declaration, in its own folder.
Method make_hierarchical_method();  // hierarchical/method.cpp
Method make_matrix_method();        // matrix/method.cpp
Method make_pixmap_method();        // pixmap/method.cpp

namespace {

std::deque<Method>& table() {
  // A deque: references to its entries stay valid when add_method appends.
  static std::deque<Method> t = {
      make_hierarchical_method(),  // the default
      make_matrix_method(),
      make_pixmap_method(),
  };
  return t;
}

std::string joined(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

}  // namespace

const std::deque<Method>& methods() { return table(); }

const Method& find_method(const std::string& name) {
  std::vector<std::string> names;
  for (const Method& m : methods()) {
    if (m.name == name) return m;
    names.push_back(m.name);
  }
  throw InputError("unknown method '" + name + "': expected one of " + joined(names), {"method"});
}

void add_method(Method method) {
  for (const Method& m : methods())
    if (m.name == method.name) throw InputError("a method called '" + method.name + "' is in the table already");
  if (!method.parse || !method.meshing || !method.solve)
    throw InputError("method '" + method.name + "' lacks its parse, meshing or solve");
  table().push_back(std::move(method));
}

std::vector<std::pair<OptionSpec, std::vector<std::string>>> all_method_options() {
  std::vector<std::pair<OptionSpec, std::vector<std::string>>> out;
  for (const Method& m : methods())
    for (const OptionSpec& s : m.options) {
      auto it = std::find_if(out.begin(), out.end(), [&](const auto& e) { return e.first.name == s.name; });
      if (it == out.end()) it = out.insert(out.end(), {s, {}});
      it->second.push_back(m.name);
    }
  return out;
}

MethodOptions method_options(const Method& method, const OptionValues& given) {
  for (const auto& entry : given) {
    const std::string& name = entry.first;  // not a binding: the lambda below captures it
    if (std::none_of(method.options.begin(), method.options.end(), [&](const OptionSpec& s) { return s.name == name; })) {
      std::vector<std::string> takers;
      for (const Method& m : methods())
        for (const OptionSpec& s : m.options)
          if (s.name == name) takers.push_back(m.name);
      throw InputError(name + " is not an option of method " + method.name +
                           (takers.empty() ? std::string(" (no method takes it)")
                                           : " (it applies to method " + joined(takers) + " only)"),
                       {name, "method"});
    }
  }
  return method.parse(given);
}

void apply_preset(const Method& method, const std::string& preset, OptionValues& solve, OptionValues& meshing,
                  OptionValues& method_given) {
  const auto& names = preset_names();
  if (std::find(names.begin(), names.end(), preset) == names.end())
    throw InputError("preset " + preset + ": expected one of " + joined(names), {"preset"});
  if (preset == "default") return;
  const auto it = std::find_if(method.presets.begin(), method.presets.end(),
                               [&](const Preset& p) { return p.name == preset; });
  if (it == method.presets.end())
    throw InputError("preset " + preset + ": method " + method.name + " has none", {"preset", "method"});
  for (const auto& [name, value] : it->values) {
    OptionValues& to = solve_option_table().has(name)     ? solve
                       : meshing_option_table().has(name) ? meshing
                                                          : method_given;
    to.emplace(name, value);  // a value given by name stays
  }
}

void check_shared_options(const Method& method, const std::vector<std::string>& given, FieldMode field) {
  for (const std::string& name : given) {
    if (std::find(method.unused.begin(), method.unused.end(), name) == method.unused.end()) continue;
    if ((name == "rays" || name == "display_tolerance") && field == FieldMode::gather) continue;  // the gather's
    std::vector<std::string> users;
    for (const Method& m : methods())
      if (std::find(m.unused.begin(), m.unused.end(), name) == m.unused.end()) users.push_back(m.name);
    throw InputError(name + " is not used by method " + method.name +
                         (users.empty() ? std::string() : " (it applies to method " + joined(users) + " only)"),
                     {name, "method"});
  }
}

namespace {

// The scene emits, yet every element of a surface that reflects (and does
// not emit) came out black: the usual cause is faces turned the wrong way
// (a room whose normals all point out, a lamp facing the ceiling). Empty
// when some such element got light, or when there is none, or when the
// run was stopped before it could light anything.
std::string unlit_warning(const Scene& scene, const MethodResult& r) {
  if (r.interrupted) return {};
  if (!scene.has_emitter()) return {};  // the scene's own warning says so
  std::set<int> reflecting;
  for (int t = 0; t < r.mesh.triangle_count(); ++t) {
    const int p = r.mesh.patch[static_cast<size_t>(t)];
    const Material& m = scene.material_of(scene.patches[static_cast<size_t>(p)]);
    if (max3(m.emission) > 0.0 || max3(m.reflectance) <= 0.0 || r.mesh.zero_area(t)) continue;
    if (max3(r.solution.element[static_cast<size_t>(t)]) > 0.0) return {};
    reflecting.insert(p);
  }
  if (reflecting.empty()) return {};
  return scene.source + ": no light reached any of the " + std::to_string(reflecting.size()) +
         " faces that reflect: every value but the emitters' is 0. A face is lit on its front, the side from "
         "which its vertices run counter-clockwise: check that the faces' fronts point into the room and the "
         "emitters' toward what they light";
}

}  // namespace

namespace {

void check_resumable(const Method& method) {
  if (method.resumable()) return;
  std::vector<std::string> takers;
  for (const Method& m : methods())
    if (m.resumable()) takers.push_back(m.name);
  throw InputError("resume applies to method " + joined(takers) + " only", {"resume", "method"});
}

}  // namespace

std::shared_ptr<const MethodState> read_method_state(const Method& method, const std::string& out_dir) {
  check_resumable(method);
  return method.read_state(out_dir);
}

namespace {

MethodResult solve_and_field(const Method& method, const Scene& scene, const Mesh& mesh, const SolveOptions& options,
                             const MethodOptions& method_options, const SolveCallbacks& callbacks) {
  check_solve_options(options);
  if (callbacks.resume) check_resumable(method);
  const auto start = std::chrono::steady_clock::now();
  MethodResult r = method.solve(scene, mesh, options, method_options, callbacks);
  // What the method's own phases leave out of its wall time (building its
  // structures: visibility, clusters) is its "setup", so that the phases
  // add up to the whole run.
  double phases = 0.0;
  for (const auto& [name, s] : r.seconds) phases += s;
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.seconds.insert(r.seconds.begin(), {"setup", std::max(0.0, wall - phases)});
  if (!method.own_field.empty()) {
    // Its own field stands unless another is asked for by name.
    r.field.mode = options.field == FieldMode::automatic ? FieldMode::own : options.field;
    r.field.own_field = method.own_field;
    if (r.field.mode == FieldMode::fit || r.field.mode == FieldMode::mean)
      r.solution.nodal = compute_nodal(scene, r.mesh, r.solution.element, options.crease_angle, nodal_method(r.field.mode));
  } else {
    r.field.mode = resolve_field_mode(options.field, scene, r.mesh, &r.field.why);
    if (!r.field.why.empty()) r.solution.stats.skips.push_back(r.field.why);
  }
  if (options.display_tolerance > 0.0 && r.field.mode != FieldMode::gather)
    r.solution.stats.skips.push_back("display refinement: the field is " +
                                     (r.field.mode == FieldMode::own ? r.field.own_field : to_string(r.field.mode)) +
                                     ", and only the gather field is refined; the display is the solver's mesh");
  if (r.field.mode == FieldMode::gather && options.display_tolerance > 0.0) {
    std::vector<int> origin;
    r.solution.element_patch_mean = patch_mean_radiosity(scene, r.mesh, r.solution.element);
    r.solution.nodal =
        refine_display(scene, mesh, r.mesh, r.solution.element, origin, options, &r.field, callbacks.progress);
    // The method's per-element fields follow the display's triangles.
    for (auto& [name, values] : r.cell_fields) {
      std::vector<int> shown(origin.size());
      for (size_t t = 0; t < origin.size(); ++t) shown[t] = values[static_cast<size_t>(origin[t])];
      values = std::move(shown);
    }
    r.seconds.emplace_back("direct", r.field.seconds_direct);
    r.seconds.emplace_back("gather", r.field.seconds_gather);
  } else if (r.field.mode == FieldMode::gather) {
    r.solution.nodal = compute_field(scene, r.mesh, r.solution.element, options, &r.field, callbacks.progress);
    r.seconds.emplace_back("direct", r.field.seconds_direct);
    r.seconds.emplace_back("gather", r.field.seconds_gather);
  }
  // Otherwise the solver's own field stands: automatic falls back to the
  // fit, which is what nodal_method(automatic) gave the solver.
  r.warnings.insert(r.warnings.end(), r.solution.stats.warnings.begin(), r.solution.stats.warnings.end());
  if (const std::string w = unlit_warning(scene, r); !w.empty()) r.warnings.push_back(w);
  return r;
}

}  // namespace

MethodResult run_method(const Method& method, const Scene& scene, const Mesh& mesh, const SolveOptions& options,
                        const MethodOptions& method_options, const SolveCallbacks& callbacks) {
  // What the memory limit counts is refused with its own message before it
  // is allocated; an allocation the system refuses beyond that is said
  // here, not left to surface as an internal error.
  try {
    return solve_and_field(method, scene, mesh, options, method_options, callbacks);
  } catch (const std::bad_alloc&) {
    throw NumericalError(scene.source + ": out of memory: the system refused an allocation the " + method.name +
                             " method did not count; lower max_memory (its checks then refuse the run before it "
                             "allocates) or the options that size the run",
                         {"max_memory"});
  }
}

MethodResult run_method(const Method& method, const Scene& scene, const Mesh& mesh, const SolveOptions& options,
                        const OptionValues& given, const SolveCallbacks& callbacks) {
  return run_method(method, scene, mesh, options, method_options(method, given), callbacks);
}

}  // namespace radmesh
