// The table of radiosity methods and the option machinery they share.

#include "radmesh/method.h"

#include "radmesh/errors.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <set>

namespace radmesh {

// ---- options ----------------------------------------------------------------

std::string option_flag(const std::string& name) {
  std::string f = "--" + name;
  std::replace(f.begin(), f.end(), '_', '-');
  return f;
}

std::string OptionSpec::flag() const { return option_flag(name); }

std::string OptionSpec::default_text() const {
  switch (kind) {
    case Kind::choice: return choices.empty() ? std::string() : choices.front();
    case Kind::flag: return default_value != 0.0 ? "true" : "false";
    case Kind::integer: return std::to_string(static_cast<long long>(default_value));
    case Kind::real: return format_number(default_value);
  }
  return {};
}

namespace {

// Parses the text of option `s` as its kind wants; InputError naming the
// flag, the method and the value otherwise.
double parse_value(const OptionSpec& s, const std::string& text, const std::string& method) {
  auto bad = [&](const std::string& why) -> double {
    throw InputError(s.flag() + " " + text + " (method " + method + "): " + why);
  };
  switch (s.kind) {
    case OptionSpec::Kind::flag:
      if (text == "true" || text == "1" || text.empty()) return 1.0;
      if (text == "false" || text == "0") return 0.0;
      return bad("expected true or false");
    case OptionSpec::Kind::choice: {
      const auto it = std::find(s.choices.begin(), s.choices.end(), text);
      if (it == s.choices.end()) {
        std::string list;
        for (const std::string& c : s.choices) list += (list.empty() ? "" : ", ") + c;
        return bad("expected one of " + list);
      }
      return static_cast<double>(it - s.choices.begin());
    }
    case OptionSpec::Kind::integer:
    case OptionSpec::Kind::real: {
      char* end = nullptr;
      const double v = std::strtod(text.c_str(), &end);
      if (text.empty() || end == nullptr || *end != '\0') return bad("not a number");
      if (!std::isfinite(v)) return bad("not a finite number");
      if (s.kind == OptionSpec::Kind::integer && v != std::floor(v)) return bad("not an integer");
      if (v < s.min || v > s.max)
        return bad("out of range [" + format_number(s.min) + ", " + format_number(s.max) + "]" +
                   (s.unit.empty() ? "" : " " + s.unit));
      return v;
    }
  }
  return 0.0;
}

}  // namespace

MethodOptions::MethodOptions(const std::vector<OptionSpec>& specs, const OptionValues& given,
                             const std::string& method)
    : specs_(specs) {
  for (const auto& entry : given) {
    const std::string& name = entry.first;  // not a binding: the lambda below captures it
    if (std::none_of(specs.begin(), specs.end(), [&](const OptionSpec& s) { return s.name == name; })) {
      std::string takers;
      for (const Method& m : methods())
        for (const OptionSpec& s : m.options)
          if (s.name == name) takers += (takers.empty() ? "" : ", ") + m.name;
      throw InputError(option_flag(name) + " is not an option of method " + method +
                       (takers.empty() ? std::string(" (no method takes it)")
                                       : " (it applies to --method " + takers + " only)"));
    }
  }
  for (const OptionSpec& s : specs) {
    const auto it = given.find(s.name);
    const std::string text = it != given.end() ? it->second : s.default_text();
    numbers_[s.name] = parse_value(s, text, method);
    items_.emplace_back(s.name, s.kind == OptionSpec::Kind::flag ? (numbers_[s.name] != 0.0 ? "true" : "false") : text);
  }
}

const OptionSpec& MethodOptions::spec(const std::string& name) const {
  for (const OptionSpec& s : specs_)
    if (s.name == name) return s;
  throw InputError("option '" + name + "' is not declared by this method");
}

double MethodOptions::number(const std::string& name) const {
  spec(name);
  return numbers_.at(name);
}

const std::string& MethodOptions::text(const std::string& name) const {
  spec(name);
  for (const auto& [n, t] : items_)
    if (n == name) return t;
  throw InputError("option '" + name + "' has no value");
}

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

// Each method's declaration, in its own file.
Method make_hierarchical_method();  // hierarchical_method.cpp
Method make_matrix_method();        // matrix_method.cpp
Method make_pixmap_method();        // pixmap_method.cpp

const std::vector<Method>& methods() {
  static const std::vector<Method> table = {
      make_hierarchical_method(),  // the default
      make_matrix_method(),
      make_pixmap_method(),
  };
  return table;
}

const Method& find_method(const std::string& name) {
  std::string names;
  for (const Method& m : methods()) {
    if (m.name == name) return m;
    names += (names.empty() ? "" : ", ") + m.name;
  }
  throw InputError("unknown method '" + name + "': expected one of " + names);
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

MethodResult run_method(const Method& method, const Scene& scene, const Mesh& mesh, const SolveOptions& options,
                        const OptionValues& given, const SolveCallbacks& callbacks) {
  check_solve_options(options);
  const MethodOptions opts(method.options, given, method.name);
  if (callbacks.resume && !method.resumable) throw InputError("--resume applies to --method pixmap only");
  const auto start = std::chrono::steady_clock::now();
  MethodResult r = method.solve(scene, mesh, options, opts, callbacks);
  // What the method's own phases leave out of its wall time (building its
  // structures: visibility, clusters) is its "setup", so that the phases
  // add up to the whole run.
  double phases = 0.0;
  for (const auto& [name, s] : r.seconds) phases += s;
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.seconds.insert(r.seconds.begin(), {"setup", std::max(0.0, wall - phases)});
  if (method.texel_field) {
    // Its own field stands unless another is asked for by name.
    r.field.mode = options.field == FieldMode::automatic ? FieldMode::texels : options.field;
    if (r.field.mode == FieldMode::fit || r.field.mode == FieldMode::mean)
      r.solution.nodal = compute_nodal(scene, r.mesh, r.solution.element, options.crease_angle, nodal_method(r.field.mode));
  } else {
    r.field.mode = resolve_field_mode(options.field, scene, r.mesh, &r.field.why);
    if (!r.field.why.empty()) r.solution.stats.skips.push_back(r.field.why);
  }
  if (r.field.mode == FieldMode::gather) {
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

}  // namespace radmesh
