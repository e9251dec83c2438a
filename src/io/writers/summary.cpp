// summary.json (the run's options, counts, times, quality, warnings, skips,
// per-object and per-patch means, the solver's counters, the energy
// balance and the field) and the CSV tables beside it.

#include "radmesh/summary.h"

#include "io/writers/atomic_file.h"
#include "io/writers/json_file.h"
#include "radmesh/version.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

namespace radmesh {

namespace {

nlohmann::json rgb(const Rgb& c) { return nlohmann::json::array({c.x, c.y, c.z}); }

// The shadow lines' counts (discontinuity full).
void add_shadow_lines(nlohmann::json& doc, const RunInfo& info) {
  const ShadowReport& sh = info.mesh_report.shadow;
  doc["shadow_lines"] = {{"d1_segments", sh.d1},
                         {"d2_segments", sh.d2},
                         {"emitters", sh.emitters},
                         {"weak_emitters_skipped", sh.weak_emitters_skipped},
                         {"pairs", sh.pairs},
                         {"back_facing_pairs_skipped", sh.back_facing_pairs_skipped},
                         {"no_occluder_pairs_skipped", sh.no_occluder_pairs_skipped},
                         {"non_silhouette_skipped", sh.non_silhouette_skipped},
                         {"hidden_pieces_dropped", sh.hidden_pieces_dropped},
                         {"near_duplicates_dropped", sh.near_duplicates_dropped},
                         {"budget_receivers", sh.budget_receivers},
                         {"lines_dropped_by_budget", sh.lines_dropped_by_budget},
                         {"max_lines_per_receiver", info.meshing.shadow.max_lines_per_receiver},
                         {"left_out", "EEE events (critical surfaces of three edges) are not computed"}};
}

// Objects (patches grouped by name) and patches (or the file that lists
// them), with their mean radiosities where there is a solution.
void add_objects_and_patches(nlohmann::json& doc, const Scene& scene, const Mesh& mesh, const Solution* solution) {
  using nlohmann::json;
  std::vector<Rgb> mean, element_mean;
  if (solution) {
    mean = patch_mean_radiosity(scene, mesh, solution->nodal);
    element_mean = element_patch_means(scene, mesh, *solution);
  }
  // Objects: patches grouped by name, in order of first appearance.
  std::vector<std::string> names;
  std::map<std::string, std::tuple<long long, double, Rgb, Rgb>> objects;  // count, area, sums
  for (size_t p = 0; p < scene.patches.size(); ++p) {
    const std::string& name = scene.patches[p].name;
    auto [it, fresh] = objects.try_emplace(name, 0, 0.0, Rgb(0.0), Rgb(0.0));
    if (fresh) names.push_back(name);
    auto& [count, area, m, em] = it->second;
    const double a = scene.patch_area(static_cast<int>(p));
    ++count;
    area += a;
    if (solution) {
      m += a * mean[p];
      em += a * element_mean[p];
    }
  }
  json objs = json::array();
  for (const std::string& name : names) {
    const auto& [count, area, m, em] = objects.at(name);
    json j = {{"name", name}, {"patches", count}, {"area", area}};
    if (solution && area > 0.0) {
      j["mean_radiosity"] = rgb(m / area);
      j["element_mean_radiosity"] = rgb(em / area);
    }
    objs.push_back(j);
  }
  doc["objects"] = objs;
  if (!patches_in_summary(scene)) {
    doc["patches_csv"] = "patches.csv";
    return;
  }
  json patches = json::array();
  for (size_t p = 0; p < scene.patches.size(); ++p) {
    const Patch& patch = scene.patches[p];
    json j = {{"id", p},
              {"name", patch.name},
              {"material", scene.material_of(patch).name},
              {"area", scene.patch_area(static_cast<int>(p))}};
    if (solution) {
      j["mean_radiosity"] = rgb(mean[p]);  // of the field users see
      j["element_mean_radiosity"] = rgb(element_mean[p]);  // of the solver's elements
    }
    patches.push_back(j);
  }
  doc["patches"] = patches;
}

// The solution's counts, the solver's figures (its options and counters),
// the energy balance and the skips.
void add_solver(nlohmann::json& doc, const RunInfo& info, const MethodResult& result) {
  using nlohmann::json;
  const SolveStats& st = result.solution.stats;
  doc["counts"]["form_factors"] = st.form_factors;
  doc["counts"]["form_factors_skipped"] = st.form_factors_skipped;
  doc["counts"]["receiver_points"] = st.receiver_points;
  doc["counts"]["rays_cast"] = st.rays_cast;
  doc["counts"]["rays_skipped"] = st.rays_skipped;
  doc["counts"]["pairs_unoccludable"] = st.pairs_unoccludable;
  // error_bound: per channel, null where the scene gives no bound (-1).
  json bound = json::array();
  for (const double b : st.error_bound) bound.push_back(b >= 0.0 ? json(b) : json(nullptr));
  doc["solver"] = {{"method", info.method},
                   {"residual", st.residual},
                   {"error_bound", bound},
                   {"extrapolations", st.extrapolations},
                   {"convex_enclosure", st.convex_enclosure}};
  // Numbers as numbers, flags as booleans, choices as written.
  for (const OptionValue& v : info.method_options) {
    if (v.kind == OptionSpec::Kind::choice)
      doc["solver"][v.name] = v.text;
    else if (v.kind == OptionSpec::Kind::flag)
      doc["solver"][v.name] = v.number != 0.0;
    else
      doc["solver"][v.name] = v.number;
  }
  json units = json::object();
  for (const Counter& c : result.counters) {
    json values = json::array();
    for (double v : c.values) values.push_back(c.integral ? json(static_cast<long long>(v)) : json(v));
    doc["solver"][c.name] = c.series ? values : values.at(0);
    if (!c.unit.empty()) units[c.name] = c.unit;
  }
  if (!units.empty()) doc["solver"]["units"] = units;
  const Rgb imbalance = st.power_emitted - st.power_absorbed - st.power_escaped;
  Rgb rel(0.0);
  for (int c = 0; c < 3; ++c)
    rel[c] = st.power_emitted[c] > 0.0 ? imbalance[c] / st.power_emitted[c] : 0.0;
  doc["energy"] = {{"emitted", rgb(st.power_emitted)},
                   {"absorbed", rgb(st.power_absorbed)},
                   {"escaped", rgb(st.power_escaped)},
                   {"relative_imbalance", rgb(rel)}};
  doc["skips"] = st.skips;
}

// How the display field was made.
void add_field(nlohmann::json& doc, const FieldReport& f) {
  doc["field"] = {{"mode", f.mode == FieldMode::own ? f.own_field : to_string(f.mode)}};
  if (!f.why.empty()) doc["field"]["why"] = f.why;
  if (f.mode == FieldMode::gather) {
    doc["field"]["display_vertices"] = f.display_vertices;
    doc["field"]["on_other_surface"] = f.on_other_surface;
    doc["field"]["direct"] = {{"unoccluded", f.direct.unoccluded},
                              {"clipped", f.direct.clipped},
                              {"dark", f.direct.dark},
                              {"hidden", f.direct.hidden},
                              {"behind", f.direct.behind},
                              {"seconds", f.seconds_direct}};
    doc["field"]["gather"] = {{"sources", f.gather_sources},
                              {"nodes", f.gather_nodes},
                              {"clustered", f.clustered},
                              {"clusters", f.gather_clusters},
                              {"triangles", f.gather_triangles},
                              {"rays_cast", f.rays_cast},
                              {"opening", FieldEvaluator::kOpening},
                              {"seconds", f.seconds_gather}};
    if (f.display_rounds > 0)
      doc["field"]["display_refinement"] = {
          {"rounds", f.display_rounds}, {"midpoints", f.display_midpoints}, {"splits", f.display_splits}};
  }
}

}  // namespace

nlohmann::json make_summary(const RunInfo& info, const Scene& scene, const Mesh& mesh,
                            const TriangleQuality& quality, const MethodResult* result) {
  const Solution* solution = result ? &result->solution : nullptr;
  using nlohmann::json;
  json doc;
  doc["radmesh_version"] = RADMESH_VERSION;
  doc["command"] = info.command;
  doc["scene"] = info.scene_path;
  doc["options"] = {{"max_edge", info.meshing.max_edge},
                    {"min_angle", info.meshing.min_angle},
                    {"discontinuity", to_string(info.meshing.discontinuity)},
                    {"tolerance", info.solve.tolerance},
                    {"rays", info.solve.rays},
                    {"threads", info.solve.threads},
                    {"crease_angle", info.solve.crease_angle},
                    {"field", to_string(info.solve.field)},
                    {"nodal", to_string(nodal_method(info.solve.field) == NodalMethod::mean ? FieldMode::mean
                                                                                          : FieldMode::fit)}};
  if (info.method != "none") doc["options"]["preset"] = info.preset;
  doc["counts"] = {{"faces_read", scene.report.faces_read},
                   {"patches", scene.patches.size()},
                   {"materials", scene.materials.size()},
                   {"vertices_welded", scene.report.vertices_welded},
                   {"zero_area_faces_dropped", scene.report.zero_area_faces_dropped},
                   {"nonplanar_faces_split", scene.report.nonplanar_faces_split},
                   {"faces_cut_out", scene.report.faces_cut_out},
                   {"mesh_vertices", mesh.positions.size()},
                   {"elements", mesh.triangles.size()},
                   {"boundary_rounds", info.mesh_report.boundary_rounds},
                   {"contact_segments", info.mesh_report.contact_segments},
                   {"shadow_segments", info.mesh_report.shadow_segments},
                   {"line_crossings", info.mesh_report.crossings},
                   {"rounding_crossings", info.mesh_report.rounding_crossings},
                   {"thin_faces_unrefined", info.mesh_report.thin_faces_unrefined},
                   {"feature_edges", mesh.feature_edges.size()}};
  json seconds = json::object();
  double total = 0.0;
  for (const auto& [phase, s] : info.seconds) {
    seconds[phase] = s;
    total += s;
  }
  seconds["total"] = total;
  doc["time_seconds"] = seconds;
  doc["mesh_quality"] = {{"min_angle_min", percentile(quality.min_angle, 0.0)},
                         {"min_angle_p05", percentile(quality.min_angle, 0.05)},
                         {"min_angle_median", percentile(quality.min_angle, 0.5)},
                         {"aspect_ratio_median", percentile(quality.aspect_ratio, 0.5)},
                         {"aspect_ratio_p95", percentile(quality.aspect_ratio, 0.95)},
                         {"aspect_ratio_max", percentile(quality.aspect_ratio, 1.0)}};
  doc["warnings"] = scene.report.warnings;
  for (const std::string& w : info.mesh_report.warnings) doc["warnings"].push_back(w);
  if (result)
    for (const std::string& w : result->warnings) doc["warnings"].push_back(w);
  if (info.meshing.discontinuity == DiscontinuityMode::full) add_shadow_lines(doc, info);

  add_objects_and_patches(doc, scene, mesh, solution);

  if (solution) {
    add_solver(doc, info, *result);
    add_field(doc, result->field);
  }
  return doc;
}

std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\r\n") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

bool patches_in_summary(const Scene& scene) { return scene.patches.size() <= kSummaryPatches; }

void write_patches_csv(const std::string& path, const Scene& scene, const Mesh& mesh, const Solution* solution) {
  std::vector<Rgb> mean, element_mean;
  if (solution) {
    mean = patch_mean_radiosity(scene, mesh, solution->nodal);
    element_mean = element_patch_means(scene, mesh, *solution);
  }
  write_file_atomically(path, [&](std::ostream& out) {
    out << "id,name,material,area";
    if (solution) out << ",mean_r,mean_g,mean_b,element_mean_r,element_mean_g,element_mean_b";
    out << '\n';
    out.precision(17);
    for (size_t p = 0; p < scene.patches.size(); ++p) {
      const Patch& patch = scene.patches[p];
      out << p << ',' << csv_field(patch.name) << ',' << csv_field(scene.material_of(patch).name) << ','
          << scene.patch_area(static_cast<int>(p));
      if (solution)
        for (const Rgb& v : {mean[p], element_mean[p]}) out << ',' << v.x << ',' << v.y << ',' << v.z;
      out << '\n';
    }
  });
}

void write_quality_csv(const std::string& path, const std::vector<std::string>& patch_names,
                       const std::vector<PatchQuality>& rows) {
  write_file_atomically(path, [&](std::ostream& out) {
    out << "patch_id,name,triangles,min_angle,max_angle,aspect_p50,aspect_p95,aspect_max,contact_segments,"
           "d1_segments,d2_segments,zero_area\n";
    out.precision(8);
    for (const PatchQuality& r : rows)
      out << r.patch << ',' << (r.patch < 0 ? std::string("total") : patch_names.at(static_cast<size_t>(r.patch)))
          << ',' << r.triangles << ',' << r.min_angle << ',' << r.max_angle << ',' << r.aspect_p50 << ','
          << r.aspect_p95 << ',' << r.aspect_max << ',' << r.contact_segments << ',' << r.d1_segments << ','
          << r.d2_segments << ',' << r.zero_area << '\n';
  });
}

void write_summary(const std::string& path, const RunInfo& info, const Scene& scene, const Mesh& mesh,
                   const TriangleQuality& quality, const MethodResult* result) {
  write_json(path, make_summary(info, scene, mesh, quality, result));
}

RunInfo run_info(const Result& result) {
  RunInfo info;
  info.command = "run";
  info.scene_path = result.scene->source;
  info.meshing = result.meshing;
  info.solve = result.solve_options;
  info.mesh_report = result.mesh_report;
  info.seconds = result.seconds;
  info.method = result.method;
  info.method_options = result.options;
  info.preset = result.preset;
  return info;
}

namespace {

// Bytes that are not UTF-8 (a name from a file in another encoding) are
// written as U+FFFD instead of failing.
std::string json_text(const nlohmann::json& doc) {
  return doc.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + '\n';
}

}  // namespace

void write_summary(const std::string& path, const Result& result) {
  write_summary(path, run_info(result), *result.scene, result.mesh, compute_quality(result.mesh), &result);
}

std::string summary_text(const Result& result) {
  return json_text(make_summary(run_info(result), *result.scene, result.mesh, compute_quality(result.mesh), &result));
}

void write_json(const std::string& path, const nlohmann::json& doc) {
  write_file_atomically(path, [&](std::ostream& out) { out << json_text(doc); });
}

}  // namespace radmesh
