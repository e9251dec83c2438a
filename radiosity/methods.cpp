// The table of radiosity methods and the option machinery they share.

#include "radiosity/method.h"

#include "meshing/errors.h"
#include "radiosity/hierarchical.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

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
  for (const auto& [name, text] : given)
    if (std::none_of(specs.begin(), specs.end(), [&](const OptionSpec& s) { return s.name == name; })) {
      std::string takers;
      for (const Method& m : methods())
        for (const OptionSpec& s : m.options)
          if (s.name == name) takers += (takers.empty() ? "" : ", ") + m.name;
      throw InputError(option_flag(name) + " is not an option of method " + method +
                       (takers.empty() ? std::string(" (no method takes it)")
                                       : " (it applies to --method " + takers + " only)"));
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

// ---- the methods ------------------------------------------------------------

namespace {

Method make_matrix_method() {
  Method m;
  m.name = "matrix";
  m.help = "every element pair of the initial mesh (the classic full-matrix method)";
  m.meshing = [](const Scene&) {
    MeshingOptions mo;  // the meshing defaults: diagonal / 12, full discontinuity meshing
    return mo;
  };
  m.solve = [](const Scene& scene, const Mesh& mesh, const SolveOptions& so, const MethodOptions&,
               const SolveCallbacks& cb) {
    MethodResult r;
    r.mesh = mesh;
    r.solution = solve_matrix(scene, mesh, so, cb.progress);
    const SolveStats& st = r.solution.stats;
    r.counters = {count_series("iterations", {static_cast<double>(st.iterations[0]), static_cast<double>(st.iterations[1]),
                                              static_cast<double>(st.iterations[2])}),
                  count("channels_solved", st.channels_solved)};
    r.seconds = {{"form_factors", st.seconds_form_factors}, {"solve", st.seconds_solve}};
    return r;
  };
  return m;
}

// The links of a hierarchical solution as lines from the receiver's centroid
// to the source's, with the nodes' levels and patches, F x visibility, the
// visible fraction, and the radiosity the link adds to its receiver
// (rho_receiver x F x V x B_source, largest channel).
LineSet link_line_set(const Scene& scene, const HierarchicalSolution& h) {
  LineSet out;
  std::vector<int> rl, sl, rp, sp;
  std::vector<double> ff, vis, transport;
  for (size_t r = 0; r < h.links.size(); ++r) {
    const int rn = static_cast<int>(r);
    const Patch& patch = scene.patches[static_cast<size_t>(h.tree.node(rn).patch)];
    const Rgb& rho = scene.material_of(patch).reflectance;
    for (const HierarchicalLink& l : h.links[r]) {
      out.segments.push_back({h.tree.centroid(rn), h.tree.centroid(l.source)});
      rl.push_back(h.tree.node(rn).level);
      sl.push_back(h.tree.node(l.source).level);
      rp.push_back(h.tree.node(rn).patch);
      sp.push_back(h.tree.node(l.source).patch);
      ff.push_back(l.form_factor);
      vis.push_back(l.visible);
      const Rgb t = rho * h.node_radiosity[static_cast<size_t>(l.source)] * l.form_factor;
      transport.push_back(std::max({t.x, t.y, t.z}));
    }
  }
  out.int_fields = {{"receiver_level", rl}, {"source_level", sl}, {"receiver_patch", rp}, {"source_patch", sp}};
  out.real_fields = {{"form_factor", ff}, {"visible", vis}, {"transport", transport}};
  return out;
}

// The per-cell level, zero_area flag and link count of a hierarchical
// solution's conforming mesh.
std::vector<std::pair<std::string, std::vector<int>>> hierarchical_fields(const HierarchicalSolution& h) {
  std::vector<int> level, zero, links;
  for (int leaf : h.leaf_of) {
    level.push_back(leaf >= 0 ? h.tree.node(leaf).level : -1);
    zero.push_back(leaf < 0 ? 1 : 0);
    links.push_back(leaf >= 0 ? h.node_links[static_cast<size_t>(leaf)] : 0);
  }
  return {{"level", level}, {"zero_area", zero}, {"links", links}};
}

std::vector<double> as_doubles(const auto& v) { return std::vector<double>(v.begin(), v.end()); }

Method make_hierarchical_method() {
  using Kind = OptionSpec::Kind;
  Method m;
  m.name = "hierarchical";
  m.help = "Hanrahan's hierarchical radiosity on an element hierarchy closed by zero-area triangles (also "
           "writes radiosity.pvd, one file per refinement round)";
  const HierarchicalOptions d;
  m.options = {
      {"epsilon", Kind::real, "", "link refinement threshold, relative to the largest reflected radiosity",
       d.epsilon, 1e-9, 1.0, {}},
      {"tvertex", Kind::choice, "",
       "vertex values on a neighbour's unsplit edge: free (from the finer side), anchor (the edge's interpolant, "
       "no shading jump) or split (split neighbours until no T-vertex is left, no zero-area triangles)",
       0.0, 0.0, 0.0, {to_string(d.tvertex), "anchor", "split"}},
      {"min_area", Kind::real, "scene units^2",
       "elements are not split below this area (0 = (scene diagonal / 150)^2 / 2)", d.min_area, 0.0, 1e300, {}},
      {"baum", Kind::real, "",
       "also split a leaf whose vertex values differ by more than this fraction of the largest reflected "
       "radiosity (Baum's criterion; 0 = off)",
       d.baum_relative, 0.0, 1.0, {}},
      {"export_links", Kind::flag, "",
       "also write links.vtu, every link as a line from receiver to source (fields receiver_level, source_level, "
       "receiver_patch, source_patch, form_factor, visible, transport)",
       0.0, 0.0, 1.0, {}},
  };
  m.quick = {{"epsilon", "0.02"}};
  m.meshing = [](const Scene& scene) {
    // Hierarchical radiosity refines by itself: coarse roots, and the shadow
    // lines left to refinement (full lines make many roots, and every pair
    // of roots is linked).
    MeshingOptions mo;
    mo.max_edge = scene.diagonal() / 5.0;
    mo.discontinuity = DiscontinuityMode::contacts;
    return mo;
  };
  m.solve = [](const Scene& scene, const Mesh& mesh, const SolveOptions& so, const MethodOptions& o,
               const SolveCallbacks& cb) {
    HierarchicalOptions ho;
    ho.epsilon = o.number("epsilon");
    ho.tvertex = parse_tvertex_mode(o.text("tvertex"));
    ho.min_area = o.number("min_area");
    ho.baum_relative = o.number("baum");
    std::function<void(const HierarchicalSolution&, int)> on_round;
    if (cb.on_round)
      on_round = [&](const HierarchicalSolution& h, int round) {
        MethodResult snapshot;
        snapshot.mesh = h.mesh;
        snapshot.solution = h.solution;
        snapshot.cell_fields = hierarchical_fields(h);
        cb.on_round(snapshot, round);
      };
    if (cb.progress) cb.progress("hierarchical", 0.0);
    HierarchicalSolution h = solve_hierarchical(scene, mesh, so, ho, on_round);
    if (cb.progress) cb.progress("hierarchical", 1.0);
    MethodResult r;
    r.cell_fields = hierarchical_fields(h);
    if (o.number("export_links") != 0.0) r.line_sets.emplace_back("links", link_line_set(scene, h));
    const HierarchicalStats& hs = h.stats;
    r.counters = {count("rounds", hs.rounds),
                  count("links", static_cast<double>(hs.links)),
                  count_series("links_per_round", as_doubles(hs.links_per_round)),
                  count_series("leaves_per_round", as_doubles(hs.leaves_per_round)),
                  count("leaves", hs.leaves),
                  count("zero_area_triangles", hs.zero_area_triangles),
                  count("leaf_terms", static_cast<double>(hs.leaf_terms)),
                  count("links_examined", static_cast<double>(hs.links_examined)),
                  count("sweeps", hs.sweeps),
                  measure("last_change", hs.last_change),
                  measure("row_sum_min", hs.row_sum_min),
                  measure("row_sum_max", hs.row_sum_max),
                  count("conforming_splits", hs.conforming_splits),
                  measure("max_tvertex_jump", hs.max_tvertex_jump),
                  measure("min_area", hs.min_area, "scene units^2"),
                  count("baum_splits", hs.baum_splits)};
    r.seconds = {{"link", hs.seconds_link}, {"solve", hs.seconds_solve}};
    r.report = std::to_string(hs.leaves) + " leaves, " + std::to_string(hs.links) + " links, " +
               std::to_string(hs.zero_area_triangles) + " zero-area triangles, " + std::to_string(hs.rounds) +
               " rounds";
    r.mesh = std::move(h.mesh);
    r.solution = std::move(h.solution);
    return r;
  };
  return m;
}

}  // namespace

const std::vector<Method>& methods() {
  static const std::vector<Method> table = {
      make_hierarchical_method(),  // the default
      make_matrix_method(),
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

MethodResult run_method(const Method& method, const Scene& scene, const Mesh& mesh, const SolveOptions& options,
                        const OptionValues& given, const SolveCallbacks& callbacks) {
  check_solve_options(options);
  const MethodOptions opts(method.options, given, method.name);
  return method.solve(scene, mesh, options, opts, callbacks);
}

}  // namespace radmesh
