// The time-versus-error benchmark: for every bundled scene with a reference,
// sweep the accuracy settings, and write one CSV row per run plus a log-log
// plot of error against wall time. Adding a method or a scene is adding an
// entry to `methods()` or `scenes()`.
//
//   radmesh_bench [--out DIR] [--scenes a,b] [--quick]
//   radmesh_bench --direct [--out DIR] [--quick]   (meshing study: direct light only)
//   radmesh_bench --make-reference [--scenes S] [--max-edge L] [--rays N] [--reference-out F]   (stored references)
//   radmesh_bench --load-times [--out DIR]   (scene loading per format, 10^6 triangles)
//   radmesh_bench --scaling [--out DIR] [--max-triangles N] [--clusters volume,off] [--time-limit S]
//   radmesh_bench --progressive [--scenes S] [--settings ...:pixmap:NAME=VALUE]   (pixmap: error at every tenth of its shots)
//                 (bench/scaling.h: time, links and memory against input size, one process per run)

#include "bench/mesh_writers.h"
#include "bench/plot.h"
#include "bench/scaling.h"
#include "io/writers/atomic_file.h"
#include "radmesh/obj_reader.h"
#include "radmesh/scene_reader.h"
#include "radmesh/errors.h"
#include "radmesh/direct.h"
#include "radmesh/error_metric.h"
#include "radmesh/field.h"
#include "radmesh/method.h"
#include "radmesh/solve.h"
#include "radiosity/transport/transport.h"

#include <CLI/CLI.hpp>
#include <tbb/parallel_for.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <map>
#include <sstream>

#include <unistd.h>
#include <algorithm>

namespace {

using namespace radmesh;
namespace fs = std::filesystem;

constexpr int kSamples = 2000;  // error-metric points per scene

struct Settings {
  double max_edge;  // scene units (the initial mesh)
  int rays;
  int quad_level;
  DiscontinuityMode discontinuity = DiscontinuityMode::contacts;
  std::string method = "matrix";  // a name in methods()
  OptionValues options = {};      // the method's options (the rest take defaults)
  FieldMode field = FieldMode::automatic;  // "field=MODE" in --settings; auto as in radmesh run
  double display_tolerance = 0.0;          // "display_tolerance=T" in --settings
};

// "epsilon=0.001;tvertex=split": the options of a row, in the CSV and series names.
std::string options_text(const OptionValues& o) {
  std::string t;
  for (const auto& [k, v] : o) t += (t.empty() ? "" : ";") + k + "=" + v;
  return t;
}

struct Scenario {
  std::string name;
  std::string obj;  // relative to the data directory
  // Reference radiosity at the samples. Errors are measured on the reflected
  // part B - E (see reflected_part).
  std::function<std::vector<Rgb>(const Scene&, const std::vector<SurfaceSample>&)> reference;
  std::vector<Settings> sweep, quick;
  // A scene with no closed form keeps its reference in data/<name>/reference.csv,
  // made by --make-reference with this element size (scene units).
  double reference_edge = 0.0;
};

// Per-sample constant E / (1 - rho): the furnace's closed form.
std::vector<Rgb> furnace_reference(const Scene& s, const std::vector<SurfaceSample>& samples) {
  std::vector<Rgb> r;
  for (const auto& p : samples) {
    const Material& m = s.material_of(p.patch);
    r.push_back(m.emission / (Rgb(1.0) - m.reflectance));
  }
  return r;
}

// Parallel plates: the emitter is black, so the receiver gets exactly
// B(x) = rho * E * F(x -> emitter), with Lambert's exact formula.
std::vector<Rgb> plates_reference(const Scene& s, const std::vector<SurfaceSample>& samples) {
  int emitter = -1;
  for (size_t p = 0; p < s.patches.size(); ++p)
    if (s.material_of(p).emission != Rgb(0.0)) emitter = static_cast<int>(p);
  const Patch& e = s.patches[static_cast<size_t>(emitter)];
  const std::vector<Vec3> poly = s.loop_points(e.outer);
  const Rgb E = s.material_of(e).emission;
  std::vector<Rgb> r;
  for (const auto& sp : samples) {
    const Patch& p = s.patches[static_cast<size_t>(sp.patch)];
    const Material& m = s.material_of(p);
    if (sp.patch == emitter) {
      r.push_back(m.emission);
      continue;
    }
    const double f = point_polygon_form_factor(sp.x, p.normal, poly.data(), poly.size(), e.normal);
    r.push_back(m.emission + m.reflectance * E * f);
  }
  return r;
}

// A scene whose light bounces once: E + the exact reflected direct light.
std::vector<Rgb> direct_reference(const Scene& s, const std::vector<SurfaceSample>& samples) {
  const DirectIllumination direct(s);
  std::vector<Rgb> r(samples.size());
  tbb::parallel_for(size_t(0), samples.size(), [&](size_t k) {
    r[k] = s.material_of(samples[k].patch).emission + direct.reflected(samples[k].x, samples[k].patch);
  });
  return r;
}

// A stored converged solution (see data/README.md), at the same samples.
std::vector<Rgb> stored_reference(const std::string& csv, const Scene& s, const std::vector<SurfaceSample>& samples) {
  std::ifstream in(csv);
  if (!in) throw IoError(csv + ": no reference; make it with radmesh_bench --make-reference --scenes NAME");
  std::vector<Rgb> r;
  std::string line;
  int ln = 0;
  while (std::getline(in, line)) {
    ++ln;
    if (line.empty() || line[0] == '#' || line.rfind("patch", 0) == 0) continue;
    std::istringstream ss(line);
    std::string tok;
    std::vector<double> v;
    while (std::getline(ss, tok, ',')) v.push_back(std::stod(tok));
    if (v.size() != 7) throw InputError(where(csv, ln) + "expected 7 values");
    const size_t k = r.size();
    if (k >= samples.size() || static_cast<int>(v[0]) != samples[k].patch ||
        glm::length(Vec3(v[1], v[2], v[3]) - samples[k].x) > 1e-6 * s.diagonal())
      throw InputError(where(csv, ln) + "sample does not match this scene's sample points; remake the reference");
    r.emplace_back(v[4], v[5], v[6]);
  }
  if (r.size() != samples.size())
    throw InputError(csv + ": has " + std::to_string(r.size()) + " samples, expected " + std::to_string(samples.size()));
  return r;
}

std::vector<Scenario> scenes(const std::string& data) {
  std::vector<Scenario> out;
  out.push_back({"furnace_cube", "furnace_cube/furnace_cube.obj", furnace_reference,
                 {{0.5, 16, 1},
                  {0.3, 16, 1},
                  {0.2, 16, 1},
                  {0.12, 16, 1},
                  {0.3, 16, 1, DiscontinuityMode::contacts, "matrix", {}, FieldMode::fit},
                  {0.3, 16, 1, DiscontinuityMode::contacts, "matrix", {}, FieldMode::mean}},
                 {{0.5, 16, 1}, {0.3, 16, 1}}});
  out.push_back({"parallel_plates", "parallel_plates/parallel_plates.obj", plates_reference,
                 {{0.5, 16, 1},
                  {0.25, 16, 1},
                  {0.12, 16, 1},
                  {0.06, 16, 1},
                  {0.04, 16, 1},
                  {0.25, 16, 1, DiscontinuityMode::contacts, "matrix", {}, FieldMode::fit},
                  {0.12, 16, 1, DiscontinuityMode::contacts, "matrix", {}, FieldMode::fit},
                  {0.25, 16, 1, DiscontinuityMode::contacts, "matrix", {}, FieldMode::mean}},
                 {{0.5, 16, 1}, {0.25, 16, 1}}});
  // One bounce under a floating square: rho E times the exactly clipped
  // visible form factor (radmesh/direct.h) on the floor, the emission on
  // the light, nothing on the black occluder. Every field mode, full lines
  // against none: the field's error is the mesh's.
  std::vector<Settings> floating, floating_quick;
  for (DiscontinuityMode lines : {DiscontinuityMode::full, DiscontinuityMode::off})
    for (double edge : {0.8, 0.4, 0.2, 0.1, 0.07}) {
      floating.push_back({edge, 16, 1, lines, "matrix", {}, FieldMode::gather});
      if (edge <= 0.4 && edge >= 0.1) floating.push_back({edge, 16, 1, lines, "matrix", {}, FieldMode::fit});
    }
  floating_quick = {{0.4, 16, 1, DiscontinuityMode::full, "matrix", {}, FieldMode::gather},
                    {0.4, 16, 1, DiscontinuityMode::off, "matrix", {}, FieldMode::gather}};
  out.push_back({"floating_occluder", "floating_occluder/floating_occluder.obj", direct_reference, floating,
                 floating_quick});
  auto stored = [&data](const std::string& name) {
    const std::string csv = data + "/" + name + "/reference.csv";
    return [csv](const Scene& s, const std::vector<SurfaceSample>& sm) { return stored_reference(csv, s, sm); };
  };
  out.push_back({"cornell_box", "cornell_box/cornell_box.obj", stored("cornell_box"),
                 {{160, 16, 1},
                  {120, 16, 1},
                  {90, 16, 1},
                  {70, 16, 1},
                  {55, 16, 1},
                  {45, 16, 1},
                  {38, 16, 1},
                  {32, 16, 1},
                  {160, 16, 1, DiscontinuityMode::off},
                  {120, 16, 1, DiscontinuityMode::off},
                  {90, 16, 1, DiscontinuityMode::off},
                  {70, 16, 1, DiscontinuityMode::off},
                  {55, 16, 1, DiscontinuityMode::off},
                  {45, 16, 1, DiscontinuityMode::off},
                  {38, 16, 1, DiscontinuityMode::off},
                  {70, 4, 2},
                  {70, 64, 2},
                  {70, 16, 0},
                  {70, 16, 2},
                  {70, 16, 3},
                  {45, 16, 0},
                  {45, 16, 2},
                  // Hierarchical radiosity from 200 mm roots.
                  {200, 16, 1, DiscontinuityMode::contacts, "hierarchical", {{"epsilon", "0.01"}}},
                  {200, 16, 1, DiscontinuityMode::contacts, "hierarchical", {{"epsilon", "0.003"}}},
                  {200, 16, 1, DiscontinuityMode::contacts, "hierarchical", {{"epsilon", "0.001"}}},
                  {200, 16, 1, DiscontinuityMode::contacts, "hierarchical", {{"epsilon", "0.0005"}}},
                  {200, 16, 1, DiscontinuityMode::contacts, "hierarchical", {{"epsilon", "0.0002"}}},
                  {200, 16, 1, DiscontinuityMode::contacts, "hierarchical", {{"epsilon", "0.0001"}}},
                  // The same with the field made from the element values.
                  {200, 16, 1, DiscontinuityMode::contacts, "hierarchical", {{"epsilon", "0.003"}}, FieldMode::fit},
                  {200, 16, 1, DiscontinuityMode::contacts, "hierarchical", {{"epsilon", "0.001"}}, FieldMode::fit},
                  {200, 16, 1, DiscontinuityMode::contacts, "hierarchical", {{"epsilon", "0.0002"}}, FieldMode::fit},
                  {200, 16, 1, DiscontinuityMode::contacts, "hierarchical", {{"epsilon", "0.001"}}, FieldMode::mean},
                  {45, 16, 1, DiscontinuityMode::full, "matrix", {}, FieldMode::fit},
                  {45, 16, 1, DiscontinuityMode::full, "matrix", {}, FieldMode::mean},
                  // Pixmap radiosity: texel size (mm) and hemicube resolution;
                  // the initial mesh is not used (its own field: texels).
                  {1000, 16, 1, DiscontinuityMode::off, "pixmap", {{"texel_size", "20"}, {"hemicube_res", "64"}}},
                  {1000, 16, 1, DiscontinuityMode::off, "pixmap", {{"texel_size", "15"}, {"hemicube_res", "64"}}},
                  {1000, 16, 1, DiscontinuityMode::off, "pixmap", {{"texel_size", "15"}, {"hemicube_res", "128"}}},
                  {1000, 16, 1, DiscontinuityMode::off, "pixmap", {{"texel_size", "12"}, {"hemicube_res", "128"}}},
                  {1000, 16, 1, DiscontinuityMode::off, "pixmap", {{"texel_size", "12"}, {"hemicube_res", "256"}}},
                  {1000, 16, 1, DiscontinuityMode::off, "pixmap", {{"texel_size", "10"}, {"hemicube_res", "128"}}}},
                 {{160, 16, 1},
                  {120, 16, 1},
                  {200, 16, 1, DiscontinuityMode::contacts, "hierarchical", {{"epsilon", "0.003"}}},
                  {200, 16, 1, DiscontinuityMode::contacts, "hierarchical", {{"epsilon", "0.003"}}, FieldMode::fit}},
                 28.0});
  // A box on an open floor under a small light: light bounces between the
  // floor and the box's sides (no closed form; a stored reference).
  std::vector<Settings> box_sweep = {
      {0.8, 16, 1, DiscontinuityMode::full},
      {0.5, 16, 1, DiscontinuityMode::full},
      {0.35, 16, 1, DiscontinuityMode::full},
      {0.25, 16, 1, DiscontinuityMode::full},
      {0.8, 16, 1, DiscontinuityMode::contacts, "hierarchical", {{"epsilon", "0.003"}}},
      {0.8, 16, 1, DiscontinuityMode::contacts, "hierarchical", {{"epsilon", "0.001"}}},
      {0.8, 16, 1, DiscontinuityMode::contacts, "hierarchical", {{"epsilon", "0.0003"}}}};
  for (const char* texel : {"0.16", "0.12", "0.08", "0.06"})
    for (const char* res : {"64", "128", "256"})
      box_sweep.push_back({1000, 16, 1, DiscontinuityMode::off, "pixmap", {{"texel_size", texel}, {"hemicube_res", res}}});
  out.push_back({"box_on_floor", "box_on_floor/box_on_floor.obj", stored("box_on_floor"), box_sweep,
                 {{0.5, 16, 1, DiscontinuityMode::full},
                  {1000, 16, 1, DiscontinuityMode::off, "pixmap", {{"texel_size", "0.12"}, {"hemicube_res", "64"}}}},
                 0.1});
  return out;
}

struct Row {
  std::string scene, method;  // method: name, then the options that name a series (choices, flags)
  Settings set;
  long long elements, form_factors, rays;
  double seconds;
  FieldError err;       // the per-vertex linear field (what users see)
  FieldError element;   // the per-element constant field
};

// The series a row belongs to: its method and the choice and flag options
// it sets (tvertex=split is another curve; a number such as epsilon is what
// a curve sweeps).
std::string series_key(const Settings& set) {
  std::string key = set.method + " field=" + to_string(set.field);
  if (set.display_tolerance > 0.0) key += " display_tolerance=" + format_number(set.display_tolerance);
  for (const OptionSpec& spec : find_method(set.method).options) {
    const auto given = set.options.find(spec.name);
    if (given != set.options.end() && (spec.kind == OptionSpec::Kind::choice || spec.kind == OptionSpec::Kind::flag))
      key += " " + spec.name + "=" + given->second;
  }
  return key;
}

// --settings EDGE:RAYS:QUAD_LEVEL[:DISCONTINUITY[:METHOD[:NAME=VALUE]...]]
Settings parse_settings(const std::string& text) {
  std::vector<std::string> f;
  std::stringstream ss(text);
  for (std::string x; std::getline(ss, x, ':');) f.push_back(x);
  auto bad = [&](const std::string& why) {
    return InputError("--settings '" + text + "': " + why +
                      " (expected EDGE:RAYS:QUAD_LEVEL[:off|contacts|full[:METHOD[:NAME=VALUE]...]]; NAME=VALUE a method option "
                      "or field=gather|fit|mean or display_tolerance=T)");
  };
  if (f.size() < 3) throw bad("too few fields");
  Settings set{};
  try {
    set.max_edge = std::stod(f[0]);
    set.rays = std::stoi(f[1]);
    set.quad_level = std::stoi(f[2]);
  } catch (const std::exception&) {
    throw bad("EDGE, RAYS and QUAD_LEVEL must be numbers");
  }
  if (f.size() > 3) set.discontinuity = parse_discontinuity_mode(f[3]);
  if (f.size() > 4) set.method = find_method(f[4]).name;
  for (size_t k = 5; k < f.size(); ++k) {
    const size_t eq = f[k].find('=');
    if (eq == std::string::npos) throw bad("'" + f[k] + "' is not NAME=VALUE");
    std::string name = f[k].substr(0, eq);
    std::replace(name.begin(), name.end(), '-', '_');
    if (name == "field")
      set.field = parse_field_mode(f[k].substr(eq + 1));
    else if (name == "display_tolerance")
      set.display_tolerance = std::stod(f[k].substr(eq + 1));
    else
      set.options[name] = f[k].substr(eq + 1);
  }
  // Checked now, before any run: unknown options and bad values are errors.
  method_options(find_method(set.method), set.options);
  return set;
}

// The solve options of `set` (its rays and quadrature) with the field `field`.
SolveOptions solve_options_of(const Settings& set, FieldMode field) {
  SolveOptions so;
  so.rays = set.rays;
  so.quadrature.max_level = set.quad_level;
  so.field = field;
  return so;
}

// `set`'s run: its method's initial meshing with its edge and lines, solved with `so`.
MethodResult run_settings(const Scene& scene, const Settings& set, const SolveOptions& so) {
  const Method& method = find_method(set.method);
  MeshingOptions mo = method.meshing(scene);
  mo.max_edge = set.max_edge;
  mo.discontinuity = set.discontinuity;
  return run_method(method, scene, mesh_scene(scene, mo), so, set.options);
}

Row run_one(const Scenario& sc, const Scene& scene, const std::vector<SurfaceSample>& samples,
            const std::vector<Rgb>& reference, const Settings& set) {
  const auto t0 = std::chrono::steady_clock::now();
  SolveOptions so = solve_options_of(set, set.field);
  so.display_tolerance = set.display_tolerance;
  const MethodResult r = run_settings(scene, set, so);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const Solution& sol = r.solution;
  const std::vector<Rgb> values = interpolate_nodal(scene, r.mesh, sol.nodal, samples);
  const std::vector<Rgb> flat = element_values(scene, r.mesh, sol.element, samples);
  const auto ref = reflected_part(scene, samples, reference);
  return {sc.name, series_key(set) + "/" + to_string(set.discontinuity), set, sol.stats.elements,
          sol.stats.form_factors, sol.stats.rays_cast, seconds,
          field_error(samples, reflected_part(scene, samples, values), ref),
          field_error(samples, reflected_part(scene, samples, flat), ref)};
}

// The brute-force final gather at surface samples: H = sum over every
// element j of F(x -> j) V(x, j) source_j, Lambert's exact point form factor
// and options.rays shadow rays per element; returns rho H per sample. The
// reference's indirect part, and the yardstick of the tree gather.
std::vector<Rgb> brute_gather(const Scene& scene, const Mesh& mesh, const std::vector<Rgb>& source,
                              const std::vector<SurfaceSample>& samples, const SolveOptions& options) {
  const ElementSet el = make_elements(scene, mesh);
  std::vector<Rgb> out(samples.size());
  run_in_arena(options.threads, [&] {
    const VisibilityEstimator visibility(scene, options.rays);
    tbb::parallel_for(size_t(0), samples.size(), [&](size_t k) {
      const int pp = samples[k].patch;
      const Vec3 n = scene.patches[static_cast<size_t>(pp)].normal;
      const Triangle point = make_triangle(samples[k].x, samples[k].x, samples[k].x, n);
      RayCount rays;
      Rgb h(0.0);
      for (size_t j = 0; j < el.size(); ++j) {
        if (el.patch[j] == pp || el.zero_area[j]) continue;
        const Triangle& tj = el.triangle[j];
        const double f = point_polygon_form_factor(samples[k].x, n, tj.v.data(), 3, tj.normal);
        if (f <= 0.0) continue;
        h += f * visibility.visible_fraction(point, pp, el.size() + k, tj, el.patch[j], j, rays) * source[j];
      }
      out[k] = scene.material_of(pp).reflectance * h;
    });
  });
  return out;
}

// The gather field's noise at its vertices: the same solve's field at the
// setting's rays and at 16 times as many (each part's rays drawn in 16
// times as many strata), the relative difference per lit display vertex
// of a reflecting patch (first channel): its 95th percentile and largest.
int field_noise(const Scenario& sc, const Scene& scene, const Settings& set) {
  const SolveOptions so = solve_options_of(set, FieldMode::gather);
  const MethodResult r = run_settings(scene, set, so);
  SolveOptions many = so;
  many.rays = 16 * set.rays;
  const auto t0 = std::chrono::steady_clock::now();
  const NodalField fine = compute_field(scene, r.mesh, r.solution.element, many);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const NodalField& shown = r.solution.nodal;
  double top = 0.0;
  for (const Rgb& b : fine.radiosity) top = std::max(top, b.x);
  std::vector<double> diff;
  std::vector<int> patch(shown.points.size(), -1);
  for (size_t t = 0; t < r.mesh.triangles.size(); ++t)
    for (int d : shown.corners[t]) patch[static_cast<size_t>(d)] = r.mesh.patch[t];
  for (size_t d = 0; d < shown.points.size(); ++d) {
    const Material& m = scene.material_of(patch[d]);
    const double b = fine.radiosity[d].x;
    if (max3(m.emission) > 0.0 || max3(m.reflectance) <= 0.0 || !(b > 1e-3 * top)) continue;
    diff.push_back(std::abs(shown.radiosity[d].x / b - 1.0));
  }
  std::sort(diff.begin(), diff.end());
  const double p95 = diff.empty() ? 0.0 : diff[static_cast<size_t>(0.95 * static_cast<double>(diff.size() - 1))];
  std::printf("%s: %zu lit vertices, rays %d against %d (%.2f s): relative difference p95 %.3e, median %.3e, "
              "max %.3e\n",
              sc.name.c_str(), diff.size(), so.rays, many.rays, seconds, p95,
              diff.empty() ? 0.0 : diff[diff.size() / 2], diff.empty() ? 0.0 : diff.back());
  return 0;
}

// Where the gather field's error comes from: its direct and indirect parts
// evaluated at the samples themselves (no interpolation), the brute-force
// gather of the same element values beside the tree gather, and the field
// interpolated between vertices; overall, then per patch (first channel),
// then the samples the interpolation misses most.
int field_parts(const Scenario& sc, const Scene& scene, const std::vector<SurfaceSample>& samples,
                const std::vector<Rgb>& reference, const Settings& set) {
  const SolveOptions so = solve_options_of(set, FieldMode::gather);
  const MethodResult r = run_settings(scene, set, so);
  const FieldEvaluator ev(scene, r.mesh, r.solution.element, so);
  const size_t n = samples.size();
  std::vector<Rgb> direct(n), indirect(n), ref_indirect(n), total(n);
  FieldReport rep;
  for (size_t k = 0; k < n; ++k) {
    direct[k] = ev.direct(samples[k].x, samples[k].patch, rep);
    indirect[k] = ev.indirect(samples[k].x, samples[k].patch, k, rep);
    ref_indirect[k] = reference[k] - scene.material_of(samples[k].patch).emission - direct[k];
    total[k] = direct[k] + indirect[k];
  }
  std::vector<Rgb> source(r.solution.element.size());
  for (size_t t = 0; t < source.size(); ++t)
    source[t] = r.solution.element[t] - scene.material_of(r.mesh.patch[t]).emission;
  const std::vector<Rgb> brute = brute_gather(scene, r.mesh, source, samples, so);
  const auto ref = reflected_part(scene, samples, reference);
  const auto interp = reflected_part(scene, samples, interpolate_nodal(scene, r.mesh, r.solution.nodal, samples));
  const FieldError et = field_error(samples, total, ref), ei = field_error(samples, indirect, ref_indirect);
  const FieldError eg = field_error(samples, interp, ref);
  std::printf("%s: at the samples L2 %.3e, worst patch mean %.3e (indirect part alone %.3e, %.3e); "
              "interpolated between vertices L2 %.3e, worst patch mean %.3e\n",
              sc.name.c_str(), et.l2, et.patch_mean, ei.l2, ei.patch_mean, eg.l2, eg.patch_mean);
  std::printf("  %-18s %8s %8s %8s %8s  (patch means against the reference, first channel)\n", "patch", "field",
              "samples", "indirect", "brute");
  for (size_t p = 0; p < scene.patches.size(); ++p) {
    Rgb sums[6] = {Rgb(0.0), Rgb(0.0), Rgb(0.0), Rgb(0.0), Rgb(0.0), Rgb(0.0)};
    for (size_t k = 0; k < n; ++k)
      if (samples[k].patch == static_cast<int>(p)) {
        const double w = samples[k].weight;
        sums[0] += w * interp[k];
        sums[1] += w * total[k];
        sums[2] += w * ref[k];
        sums[3] += w * indirect[k];
        sums[4] += w * brute[k];
        sums[5] += w * ref_indirect[k];
      }
    if (sums[2].x <= 0.0) continue;
    auto rel = [](double a, double b) { return b > 0.0 ? 100.0 * (a / b - 1.0) : 0.0; };
    std::printf("  %-18s %+7.2f%% %+7.2f%% %+7.2f%% %+7.2f%%\n", scene.patches[p].name.c_str(),
                rel(sums[0].x, sums[2].x), rel(sums[1].x, sums[2].x), rel(sums[3].x, sums[5].x),
                rel(sums[4].x, sums[5].x));
  }
  std::vector<std::pair<double, size_t>> worst;
  for (size_t k = 0; k < n; ++k) worst.emplace_back(std::abs(interp[k].x - total[k].x), k);
  std::sort(worst.rbegin(), worst.rend());
  for (size_t i = 0; i < std::min<size_t>(10, n); ++i) {
    const size_t k = worst[i].second;
    std::printf("  sample %zu on %s (%g %g %g): field %.4g, at the sample %.4g (direct %.4g), reference %.4g\n", k,
                scene.patches[static_cast<size_t>(samples[k].patch)].name.c_str(), samples[k].x.x, samples[k].x.y,
                samples[k].x.z, interp[k].x, total[k].x, direct[k].x, ref[k].x);
  }
  return 0;
}

// A stored reference (the Cornell box, the box on the floor): at every
// sample, the exact direct light (radmesh/direct.h: the visible part of
// every emitter, clipped exactly) plus the indirect light gathered from a fine
// matrix solution (its element radiosity less emission, Lambert's point form
// factor to every element and `rays` shadow rays each). Only the indirect
// part carries solver and mesh error, and the final gather smooths that.
int make_reference(const std::string& data, const Scenario& sc, double max_edge, int rays, const std::string& path_out) {
  if (!(sc.reference_edge > 0.0))
    throw InputError("--make-reference: " + sc.name + " has a closed-form reference; nothing to make");
  if (!(max_edge > 0.0)) max_edge = sc.reference_edge;
  const Scene scene = read_obj_scene(data + "/" + sc.obj);
  const auto samples = surface_samples(scene, kSamples);
  MeshingOptions mo;
  mo.max_edge = max_edge;
  mo.discontinuity = DiscontinuityMode::full;
  const Mesh mesh = mesh_scene(scene, mo);
  SolveOptions so;
  so.rays = rays;
  so.quadrature.max_level = 3;
  std::fprintf(stderr, "reference: %d elements\n", mesh.triangle_count());
  const Solution sol = solve_matrix(scene, mesh, so);
  std::vector<Rgb> indirect_source(sol.element.size());
  for (size_t t = 0; t < sol.element.size(); ++t) {
    const Patch& p = scene.patches[static_cast<size_t>(mesh.patch[t])];
    indirect_source[t] = sol.element[t] - scene.material_of(p).emission;
  }
  // E + the exact direct part + the gathered indirect part at every sample.
  const std::vector<Rgb> gathered = brute_gather(scene, mesh, indirect_source, samples, so);
  const DirectIllumination direct(scene);
  std::vector<Rgb> value(samples.size());
  tbb::parallel_for(size_t(0), samples.size(), [&](size_t k) {
    value[k] = scene.material_of(samples[k].patch).emission + gathered[k] +
               direct.reflected(samples[k].x, samples[k].patch);
  });
  const std::string path = path_out.empty() ? data + "/" + sc.name + "/reference.csv" : path_out;
  write_file_atomically(path, [&](std::ostream& out) {
    out << "# " << sc.name << " reference radiosity at the benchmark's " << samples.size()
        << " sample points (radmesh/error_metric.h surface_samples(scene, " << kSamples << ")).\n"
        << "# Made by: radmesh_bench --make-reference --scenes " << sc.name << " --max-edge " << max_edge
        << " --rays " << rays
        << ": exact direct light (radmesh/direct.h) plus the indirect light gathered at each point from a "
           "matrix solve with full discontinuity meshing ("
        << mesh.triangle_count() << " elements, receiver quadrature level 3).\n"
        << "patch,x,y,z,r,g,b\n"
        << std::setprecision(12);
    for (size_t k = 0; k < samples.size(); ++k)
      out << samples[k].patch << ',' << samples[k].x.x << ',' << samples[k].x.y << ',' << samples[k].x.z << ','
          << value[k].x << ',' << value[k].y << ',' << value[k].z << '\n';
  });
  std::printf("%s\n", path.c_str());
  return 0;
}

// The meshing study: the direct light reflected by every surface, exact at
// every triangle corner (radmesh/direct.h) and interpolated linearly, against
// the exact value at the samples. No solver is involved, so the error is the
// mesh's alone. One row per (scene, discontinuity mode, max edge).
int direct_study(const std::string& data, const std::string& out_dir, bool quick) {
  struct Study {
    std::string name, obj;
    std::vector<double> edges;
  };
  std::vector<Study> studies = {
      {"box_on_floor", "box_on_floor/box_on_floor.obj", {0.8, 0.5, 0.35, 0.25, 0.18, 0.12, 0.09, 0.065, 0.045}},
      {"cornell_box", "cornell_box/cornell_box.obj", {160, 110, 80, 55, 40, 28, 20, 14}}};
  if (quick)
    for (Study& s : studies) s.edges.resize(2);
  std::vector<bench::Series> series;
  std::ostringstream csv;
  csv << "scene,discontinuity,max_edge,triangles,lines,mesh_s,l2,linf,patch_mean\n";
  for (const Study& st : studies) {
    const Scene scene = read_obj_scene(data + "/" + st.obj);
    const DirectIllumination direct(scene);
    const auto samples = surface_samples(scene, kSamples);
    std::vector<Rgb> exact(samples.size());
    for (size_t k = 0; k < samples.size(); ++k) exact[k] = direct.reflected(samples[k].x, samples[k].patch);
    for (DiscontinuityMode mode : {DiscontinuityMode::off, DiscontinuityMode::contacts, DiscontinuityMode::full}) {
      bench::Series s{st.name + " " + to_string(mode), {}, {}};
      for (double edge : st.edges) {
        MeshingOptions mo;
        mo.max_edge = edge;
        mo.discontinuity = mode;
        MeshReport rep;
        const auto t0 = std::chrono::steady_clock::now();
        const Mesh mesh = mesh_scene(scene, mo, &rep);
        const double mesh_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        const FieldError e =
            field_error(samples, interpolate_nodal(scene, mesh, direct_field(direct, mesh), samples), exact);
        const size_t lines = rep.discontinuities.size();
        std::fprintf(stderr, "%-13s %-9s edge %-6g %7d triangles %5zu lines  mesh %7.3f s  L2 %.3e  max %.3e  patch %.3e\n",
                     st.name.c_str(), to_string(mode), edge, mesh.triangle_count(), lines, mesh_s, e.l2, e.linf,
                     e.patch_mean);
        csv << st.name << ',' << to_string(mode) << ',' << edge << ',' << mesh.triangle_count() << ',' << lines << ','
            << mesh_s << ',' << e.l2 << ',' << e.linf << ',' << e.patch_mean << '\n';
        s.x.push_back(mesh.triangle_count());
        s.y.push_back(e.l2);
      }
      series.push_back(s);
    }
  }
  fs::create_directories(out_dir);
  const std::string path = (fs::path(out_dir) / "direct.csv").string();
  write_file_atomically(path, [&](std::ostream& out) { out << csv.str(); });
  std::printf("%s\n", path.c_str());
  std::string why;
  const std::string png = (fs::path(out_dir) / "direct.png").string();
  if (bench::plot_error_vs_time(png, "radmesh: direct-light meshing error (linear interpolant vs exact)",
                                "relative L2 error", series, &why, "triangles"))
    std::printf("%s\n", png.c_str());
  else
    std::fprintf(stderr, "plot skipped: %s\n", why.c_str());
  return 0;
}

// Scene loading, read to Scene (read_scene, build_scene included), per
// format: a 10^6-triangle grid written in every format radmesh reads, and a
// quarter of it as binary PLY to see that the time grows linearly. One row
// per file in load.csv.
int load_times(const std::string& out_dir) {
  const fs::path dir = fs::temp_directory_path() / ("radmesh_bench_load_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  auto scene_of = [&](const std::string& file) {
    const fs::path json = dir / (file + ".json");
    std::ofstream(json) << "{\"materials\": {\"grey\": {\"reflectance\": [0.5, 0.5, 0.5], \"emission\": [1, 1, 1]}},"
                           " \"objects\": [{\"file\": \"" << file << "\", \"material\": \"grey\"}]}\n";
    return json.string();
  };
  std::vector<std::pair<std::string, std::string>> runs;  // (label, JSON scene)
  test::write_ply(dir / "quarter_binary.ply", test::grid(354), true);
  runs.emplace_back("quarter_binary.ply", scene_of("quarter_binary.ply"));
  for (const std::string& f : test::write_every_format(dir, test::grid(708), "grid")) runs.emplace_back(f, scene_of(f));
  std::ostringstream csv;
  csv << "file,bytes,patches,vertices,seconds\n";
  for (const auto& [file, json] : runs) {
    const auto t0 = std::chrono::steady_clock::now();
    const Scene s = read_scene(json);
    const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const auto bytes = fs::file_size(dir / file);
    std::fprintf(stderr, "%-20s %10ju bytes %8zu patches %8zu vertices %7.2f s\n", file.c_str(),
                 static_cast<uintmax_t>(bytes), s.patches.size(), s.vertices.size(), sec);
    csv << file << ',' << bytes << ',' << s.patches.size() << ',' << s.vertices.size() << ',' << sec << '\n';
  }
  fs::remove_all(dir);
  fs::create_directories(out_dir);
  const std::string path = (fs::path(out_dir) / "load.csv").string();
  write_file_atomically(path, [&](std::ostream& out) { out << csv.str(); });
  std::printf("%s\n", path.c_str());
  return 0;
}

// Progressive refinement's picture over its run: the pixmap method with the
// options of `set` (its stopping rule), then again with a snapshot at every
// tenth of that run's shots, each snapshot's field measured against the
// reference. The time of a snapshot is the method's wall time up to it, the
// measuring left out.
int progressive_study(const Scenario& sc, const Scene& scene, const std::vector<SurfaceSample>& samples,
                      const std::vector<Rgb>& reference, Settings set, const std::string& out_dir) {
  set.method = "pixmap";
  const Method& method = find_method("pixmap");
  const Mesh mesh = mesh_scene(scene, method.meshing(scene));
  SolveOptions so;
  so.field = FieldMode::automatic;
  const MethodResult full = run_method(method, scene, mesh, so, set.options);
  const long long total = static_cast<long long>(full.counter("shots")->values[0]);
  OptionValues opts = set.options;
  opts["snapshot_every"] = std::to_string(std::max(1LL, total / 10));
  const auto ref = reflected_part(scene, samples, reference);
  struct Point {
    long long shots;
    double seconds, l2, patch_mean;
  };
  std::vector<Point> points;
  double measuring = 0.0;
  const auto t0 = std::chrono::steady_clock::now();
  auto measure = [&](const MethodResult& r, long long shots) {
    const auto m0 = std::chrono::steady_clock::now();
    const double at = std::chrono::duration<double>(m0 - t0).count() - measuring;
    const auto values = reflected_part(scene, samples, interpolate_nodal(scene, r.mesh, r.solution.nodal, samples));
    const FieldError e = field_error(samples, values, ref);
    points.push_back({shots, at, e.l2, e.patch_mean});
    measuring += std::chrono::duration<double>(std::chrono::steady_clock::now() - m0).count();
  };
  SolveCallbacks cb;
  cb.on_round = [&](const MethodResult& r, int shots) { measure(r, shots); };
  const MethodResult last = run_method(method, scene, mesh, so, opts, cb);
  measure(last, total);
  std::ostringstream csv;
  csv << "scene,options,shots,fraction_of_shots,wall_s,l2,patch_mean\n";
  std::fprintf(stderr, "%s, pixmap %s: %lld shots in all\n", sc.name.c_str(), options_text(set.options).c_str(), total);
  for (const Point& p : points) {
    std::fprintf(stderr, "  %6lld shots (%3.0f%%)  %7.3f s  L2 %.3e  worst patch mean %.3e\n", p.shots,
                 100.0 * static_cast<double>(p.shots) / static_cast<double>(total), p.seconds, p.l2, p.patch_mean);
    csv << sc.name << ',' << options_text(set.options) << ',' << p.shots << ','
        << static_cast<double>(p.shots) / static_cast<double>(total) << ',' << p.seconds << ',' << p.l2 << ','
        << p.patch_mean << '\n';
  }
  fs::create_directories(out_dir);
  const std::string path = (fs::path(out_dir) / "progressive.csv").string();
  write_file_atomically(path, [&](std::ostream& out) { out << csv.str(); });
  std::printf("%s\n", path.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"radmesh time-versus-error benchmark"};
  std::string out_dir = "bench-out", data = RADMESH_DATA_DIR, only;
  bool quick = false, reference = false, direct = false;
  double ref_edge = 0.0;
  int ref_rays = 32;
  app.add_option("--out", out_dir, "output directory for bench.csv and bench.png");
  app.add_option("--data", data, "the data directory");
  app.add_option("--scenes", only, "comma-separated scene names (default: all)");
  app.add_flag("--quick", quick, "two settings per scene");
  std::vector<std::string> custom;
  app.add_option("--settings", custom,
                 "run these settings instead of the sweep: "
                 "EDGE:RAYS:QUAD_LEVEL[:off|contacts|full[:METHOD[:NAME=VALUE]...]] (repeatable; METHOD a "
                 "method of radmesh run --method, default matrix; NAME=VALUE its options as in radmesh run, "
                 "e.g. 200:16:1:contacts:hierarchical:epsilon=0.001:tvertex=anchor)");
  app.add_flag("--make-reference", reference,
               "compute data/NAME/reference.csv for the scenes with a stored reference (or those of --scenes) and exit");
  bool loads = false;
  app.add_flag("--load-times", loads,
               "scene loading instead: a 10^6-triangle grid in every format (and a quarter of it), read_scene "
               "timed per file; writes load.csv");
  app.add_flag("--direct", direct,
               "meshing study instead: direct light only, exact at the triangle corners, for discontinuity "
               "off, contacts and full; writes direct.csv and direct.png");
  bool parts = false;
  app.add_flag("--field-parts", parts, "with one --settings: the direct and gathered parts' errors per patch");
  bool noise = false;
  app.add_flag("--field-noise", noise,
               "with one --settings: the gather field's vertex values against the same solve's field at 16 times "
               "the rays (95th percentile and largest relative difference)");
  bool progressive = false;
  app.add_flag("--progressive", progressive,
               "the pixmap method's error at every tenth of its shots (with one --settings: its options); writes "
               "progressive.csv");
  app.add_option("--max-edge", ref_edge, "reference mesh size in scene units (default: the scene's own)");
  app.add_option("--rays", ref_rays, "reference shadow rays per pair");
  std::string ref_out;
  app.add_option("--reference-out", ref_out, "with --make-reference: write here instead of the data directory");
  bool scaling = false;
  bench::ScalingOptions so;
  so.radmesh = RADMESH_CLI;
  std::string modes = "volume,shape,off";
  app.add_flag("--scaling", scaling,
               "scaling benchmark instead: rooms of 10^3 .. --max-triangles input triangles and the bunny (also cut into 4^L x its triangles), each "
               "run by the radmesh program in its own process; writes scaling.csv, scaling_time.png, "
               "scaling_links.png");
  app.add_option("--max-triangles", so.max_triangles, "--scaling: the largest generated scene (input triangles)");
  app.add_option("--clusters", modes, "--scaling: comma-separated --clusters modes of the hierarchical runs");
  app.add_option("--time-limit", so.time_limit, "--scaling: seconds per run before it is stopped and noted");
  app.add_option("--radmesh", so.radmesh, "--scaling: the radmesh program to run");
  CLI11_PARSE(app, argc, argv);
  try {
    if (scaling) {
      so.out_dir = out_dir;
      so.data = data;
      so.modes.clear();
      std::stringstream ms(modes);
      for (std::string m; std::getline(ms, m, ',');) so.modes.push_back(m);
      return bench::scaling_benchmark(so);
    }
    if (reference) {
      std::vector<Scenario> stored;
      for (const Scenario& sc : scenes(data))
        if (sc.reference_edge > 0.0 && (only.empty() || ("," + only + ",").find("," + sc.name + ",") != std::string::npos))
          stored.push_back(sc);
      if (!ref_out.empty() && stored.size() != 1)
        throw InputError("--reference-out needs exactly one scene (--scenes NAME)");
      for (const Scenario& sc : stored) make_reference(data, sc, ref_edge, ref_rays, ref_out);
      return 0;
    }
    if (direct) return direct_study(data, out_dir, quick);
    if (loads) return load_times(out_dir);
    fs::create_directories(out_dir);
    std::vector<Row> rows;
    std::vector<bench::Series> series;
    for (const Scenario& sc : scenes(data)) {
      if (!only.empty() && ("," + only + ",").find("," + sc.name + ",") == std::string::npos) continue;
      const Scene scene = read_obj_scene(data + "/" + sc.obj);
      const auto samples = surface_samples(scene, kSamples);
      const auto ref = sc.reference(scene, samples);
      // One L2 and one patch-mean series per method and mode (rays 16,
      // quadrature level 1), in the order first met.
      std::vector<std::string> keys;
      std::map<std::string, std::pair<bench::Series, bench::Series>> by_method;
      bench::Series l2_off{sc.name + " L2, no contacts", {}, {}};
      std::vector<Settings> sweep = quick ? sc.quick : sc.sweep;
      if (!custom.empty()) {
        sweep.clear();
        for (const std::string& c : custom) sweep.push_back(parse_settings(c));
      }
      if (parts) return field_parts(sc, scene, samples, ref, sweep.at(0));
      if (noise) return field_noise(sc, scene, sweep.at(0));
      if (progressive)
        return progressive_study(sc, scene, samples, ref, custom.empty() ? Settings{} : sweep.at(0), out_dir);
      for (const Settings& set : sweep) {
        const Row r = run_one(sc, scene, samples, ref, set);
        std::fprintf(stderr, "%-16s %-15s edge %-6g rays %-3d q%d: %6lld elements %8.3f s  L2 %.3e  max %.3e  patch %.3e (elements %.3e) (%s)\n",
                     r.scene.c_str(), r.method.c_str(), set.max_edge, set.rays, set.quad_level, r.elements, r.seconds, r.err.l2,
                     r.err.linf, r.err.patch_mean,
                     r.element.patch_mean, (r.err.worst_patch >= 0 ? scene.patches[static_cast<size_t>(r.err.worst_patch)].name + " #" + std::to_string(r.err.worst_patch) : std::string("-")).c_str());
        rows.push_back(r);
        if (set.rays == 16 && set.quad_level == 1 && set.discontinuity == DiscontinuityMode::off &&
            set.method == "matrix") {
          l2_off.x.push_back(r.seconds);
          l2_off.y.push_back(r.err.l2);
        } else if (set.rays == 16 && set.quad_level == 1) {
          if (!by_method.count(r.method)) {
            keys.push_back(r.method);
            by_method[r.method] = {bench::Series{sc.name + " " + r.method + " L2", {}, {}},
                                   bench::Series{sc.name + " " + r.method + " patch mean", {}, {}}};
          }
          auto& [l2, pm] = by_method[r.method];
          l2.x.push_back(r.seconds);
          l2.y.push_back(r.err.l2);
          pm.x.push_back(r.seconds);
          pm.y.push_back(r.err.patch_mean);
        }
      }
      for (const std::string& k : keys) {
        series.push_back(by_method[k].first);
        series.push_back(by_method[k].second);
      }
      if (!l2_off.x.empty()) series.push_back(l2_off);
    }
    const std::string csv = (fs::path(out_dir) / "bench.csv").string();
    write_file_atomically(csv, [&](std::ostream& out) {
      out << "scene,method,discontinuity,max_edge,rays,quad_level,elements,form_factors,rays_cast,wall_s,l2,linf,patch_mean,"
             "element_l2,element_patch_mean,options,field\n";
      for (const Row& r : rows)
        out << r.scene << ',' << r.set.method << ',' << to_string(r.set.discontinuity) << ',' << r.set.max_edge << ','
            << r.set.rays << ',' << r.set.quad_level << ',' << r.elements << ',' << r.form_factors << ',' << r.rays << ','
            << r.seconds << ',' << r.err.l2 << ',' << r.err.linf << ',' << r.err.patch_mean << ',' << r.element.l2 << ','
            << r.element.patch_mean << ',' << options_text(r.set.options) << ',' << to_string(r.set.field) << '\n';
    });
    std::printf("%s\n", csv.c_str());
    std::string why;
    const std::string png = (fs::path(out_dir) / "bench.png").string();
    if (bench::plot_error_vs_time(png, "radmesh: error vs time", "relative error", series, &why))
      std::printf("%s\n", png.c_str());
    else
      std::fprintf(stderr, "plot skipped: %s\n", why.c_str());
  } catch (const radmesh::Error& e) {
    std::fprintf(stderr, "radmesh_bench: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
