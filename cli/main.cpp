// The radmesh program: subcommands `run` (mesh + solve + write results) and
// `mesh` (mesh and quality only). Every error is caught here, once, and
// printed as one line; the exit status is then non-zero.

#include "io/histogram.h"
#include "io/scene_reader.h"
#include "io/png_render.h"
#include "io/probe_file.h"
#include "io/summary.h"
#include "io/vtk_writer.h"
#include "meshing/errors.h"
#include "meshing/mesh.h"
#include "radiosity/hierarchical.h"
#include "radiosity/probe.h"
#include "radiosity/solve.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>

namespace {

using namespace radmesh;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

struct Params {
  std::string scene;
  std::string out_dir = "radmesh-out";
  MeshingOptions meshing;
  SolveOptions solve;
  std::string probe_file;
  bool quiet = false;
  bool png = true;
  bool export_links = false;  // hierarchical: links.vtu
  std::vector<std::string> hierarchical_flags_given;  // hierarchical-only options on the command line
  std::string discontinuity;  // empty: full for matrix, contacts for hierarchical
  std::string nodal = "fit";
  std::string method = "hierarchical";
  std::string tvertex = "free";
  HierarchicalOptions hierarchical;
};

// Progress on stderr for phases longer than a second: phase, percent, elapsed.
class Reporter {
public:
  explicit Reporter(bool quiet) : quiet_(quiet) {}
  void begin(const std::string& phase) {
    phase_ = phase;
    start_ = last_ = Clock::now();
    shown_ = false;
  }
  void update(const std::string& phase, double fraction) {
    if (quiet_) return;
    if (phase != phase_) {  // the library moved on: close the previous phase's line
      end();
      begin(phase);
    }
    const auto now = Clock::now();
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    if (elapsed < 1.0 || std::chrono::duration<double>(now - last_).count() < 0.5) return;
    last_ = now;
    shown_ = true;
    std::fprintf(stderr, "\r[radmesh] %-14s %5.1f%%  %6.1f s", phase.c_str(), 100.0 * fraction, elapsed);
    std::fflush(stderr);
  }
  // Ends a phase; returns its wall time.
  double end() {
    const double s = std::chrono::duration<double>(Clock::now() - start_).count();
    if (!quiet_ && (shown_ || s >= 1.0)) std::fprintf(stderr, "\r[radmesh] %-14s done    %6.1f s\n", phase_.c_str(), s);
    return s;
  }
  void note(const std::string& line) const {
    if (!quiet_) std::fprintf(stderr, "[radmesh] %s\n", line.c_str());
  }

private:
  bool quiet_;
  std::string phase_;
  Clock::time_point start_, last_;
  bool shown_ = false;
};

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
    const Rgb& rho = scene.materials[static_cast<size_t>(patch.material)].reflectance;
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

// Options that can be checked without reading anything: done before any work.
void check_params(Params& p, bool solving) {
  // mesh and quality have no method: full, like run --method matrix.
  if (p.discontinuity.empty()) p.discontinuity = solving && p.method == "hierarchical" ? "contacts" : "full";
  for (const auto& [flag, v] : {std::pair<const char*, double>{"--epsilon", p.hierarchical.epsilon},
                                {"--min-area", p.hierarchical.min_area},
                                {"--baum", p.hierarchical.baum_relative}})
    if (!std::isfinite(v)) throw InputError(std::string(flag) + " " + std::to_string(v) + " is not a finite number");
  if (solving && p.method != "hierarchical")
    for (const std::string& flag : p.hierarchical_flags_given)
      throw InputError(flag + " applies to --method hierarchical only (the method here is " + p.method + ")");

  p.meshing.discontinuity = parse_discontinuity_mode(p.discontinuity);
  p.solve.nodal = p.nodal == "mean" ? NodalMethod::mean : NodalMethod::linear_fit;
  p.hierarchical.tvertex = parse_tvertex_mode(p.tvertex);
  if (p.meshing.max_edge < 0.0 || !std::isfinite(p.meshing.max_edge))
    throw InputError("--max-edge " + std::to_string(p.meshing.max_edge) + " must be > 0 (or 0 for auto)");
  if (solving) check_solve_options(p.solve);
  if (fs::exists(p.out_dir) && !fs::is_directory(p.out_dir))
    throw InputError("-o " + p.out_dir + ": exists and is not a directory");
  if (!p.probe_file.empty() && !fs::exists(p.probe_file))
    throw InputError("--probe " + p.probe_file + ": no such file");
}

int run(Params& p, bool solving) {
  check_params(p, solving);
  Reporter rep(p.quiet);
  RunInfo info;
  info.command = solving ? "run" : "mesh";
  info.scene_path = p.scene;
  info.solve = p.solve;

  rep.begin("read");
  const Scene scene = read_scene(p.scene);
  info.seconds.push_back({"read", rep.end()});
  for (const std::string& w : scene.report.warnings) rep.note("warning: " + w);
  std::vector<Probe> probes;
  if (!p.probe_file.empty()) probes = read_probes(p.probe_file);

  // Hierarchical radiosity refines by itself: its roots start coarser.
  if (solving && p.method == "hierarchical" && p.meshing.max_edge == 0.0) p.meshing.max_edge = scene.diagonal() / 5.0;
  info.meshing = resolve_meshing_options(scene, p.meshing);
  info.method = solving ? p.method : "none";
  rep.begin("mesh");
  const Mesh mesh = mesh_scene(scene, info.meshing, &info.mesh_report);
  const TriangleQuality quality = compute_quality(mesh);
  info.seconds.push_back({"mesh", rep.end()});
  for (const std::string& w : info.mesh_report.shadow.warnings) rep.note("warning: " + w);
  rep.note(std::to_string(scene.patches.size()) + " patches, " + std::to_string(mesh.triangle_count()) +
           " elements (max edge " + std::to_string(info.meshing.max_edge) + ")");

  std::optional<Solution> sol;
  std::vector<ProbeResult> probe_results;
  // Hierarchical: the conforming mesh (leaves and zero-area fans) replaces
  // the initial one, with per-cell level, zero_area and links; one snapshot
  // per refinement round for the .pvd series.
  std::optional<Mesh> solved_mesh;
  std::vector<std::pair<std::string, std::vector<int>>> cell_fields;
  struct Snapshot {
    Mesh mesh;
    Solution solution;
    std::vector<std::pair<std::string, std::vector<int>>> fields;
  };
  std::vector<Snapshot> rounds;
  std::optional<LineSet> link_lines;
  auto fields_of = [](const HierarchicalSolution& h) {
    std::vector<int> level, zero, links;
    for (int leaf : h.leaf_of) {
      level.push_back(leaf >= 0 ? h.tree.node(leaf).level : -1);
      zero.push_back(leaf < 0 ? 1 : 0);
      links.push_back(leaf >= 0 ? h.node_links[static_cast<size_t>(leaf)] : 0);
    }
    return std::vector<std::pair<std::string, std::vector<int>>>{{"level", level}, {"zero_area", zero}, {"links", links}};
  };
  if (solving && p.method == "hierarchical") {
    rep.begin("hierarchical");
    const HierarchicalSolution h = solve_hierarchical(scene, mesh, p.solve, p.hierarchical,
                                                      [&](const HierarchicalSolution& r, int) {
                                                        rounds.push_back({r.mesh, r.solution, fields_of(r)});
                                                      });
    sol = h.solution;
    solved_mesh = h.mesh;
    if (p.export_links) link_lines = link_line_set(scene, h);
    cell_fields = fields_of(h);
    info.seconds.push_back({"link", h.stats.seconds_link});
    info.seconds.push_back({"solve", h.stats.seconds_solve});
    rep.end();
    const HierarchicalStats& hs = h.stats;
    info.solver_extra = {{"epsilon", p.hierarchical.epsilon},
                         {"rounds", hs.rounds},
                         {"links", hs.links},
                         {"links_per_round", hs.links_per_round},
                         {"leaves_per_round", hs.leaves_per_round},
                         {"leaves", hs.leaves},
                         {"zero_area_triangles", hs.zero_area_triangles},
                         {"leaf_terms", hs.leaf_terms},
                         {"sweeps", hs.sweeps},
                         {"rays_cast", hs.rays_cast},
                         {"last_change", hs.last_change},
                         {"row_sum_min", hs.row_sum_min},
                         {"row_sum_max", hs.row_sum_max},
                         {"tvertex", p.tvertex},
                         {"conforming_splits", hs.conforming_splits},
                         {"max_tvertex_jump", hs.max_tvertex_jump},
                         {"baum", p.hierarchical.baum_relative},
                         {"min_area", hs.min_area},
                         {"baum_splits", hs.baum_splits}};
    rep.note(std::to_string(hs.leaves) + " leaves, " + std::to_string(hs.links) + " links, " +
             std::to_string(hs.zero_area_triangles) + " zero-area triangles, " + std::to_string(hs.rounds) +
             " rounds");
  } else if (solving) {
    rep.begin("form factors");
    sol = solve_matrix(scene, mesh, p.solve, [&](const std::string& ph, double f) { rep.update(ph, f); });
    info.seconds.push_back({"form_factors", sol->stats.seconds_form_factors});
    info.seconds.push_back({"solve", sol->stats.seconds_solve});
    rep.end();
  }
  const Mesh& out_mesh = solved_mesh ? *solved_mesh : mesh;
  const TriangleQuality out_quality = solved_mesh ? compute_quality(out_mesh) : quality;
  if (solving && !probes.empty()) {
    rep.begin("probes");
    probe_results = evaluate_probes(scene, out_mesh, sol->element, probes, p.solve);
    info.seconds.push_back({"probes", rep.end()});
  }

  // Everything is computed: only now is the output directory touched.
  fs::create_directories(p.out_dir);
  rep.begin("write");
  std::vector<std::string> written;
  const std::string vtu = (fs::path(p.out_dir) / (solving ? "radiosity.vtu" : "mesh.vtu")).string();
  if (solving)
    write_vtu(vtu, scene, out_mesh, out_quality, *sol, cell_fields);
  else
    write_mesh_vtu(vtu, scene, mesh, quality);
  written.push_back(vtu);
  if (!rounds.empty()) {
    // One file per refinement round and a .pvd collection to step through them.
    std::vector<std::string> names;
    for (size_t r = 0; r < rounds.size(); ++r) {
      const std::string name = "radiosity_round_" + std::to_string(r) + ".vtu";
      const Snapshot& snap = rounds[r];
      write_vtu((fs::path(p.out_dir) / name).string(), scene, snap.mesh,
                compute_quality(snap.mesh), snap.solution, snap.fields);
      names.push_back(name);
    }
    const std::string pvd = (fs::path(p.out_dir) / "radiosity.pvd").string();
    write_pvd(pvd, names);
    written.push_back(pvd);
  }
  if (link_lines) {
    const std::string path = (fs::path(p.out_dir) / "links.vtu").string();
    write_lines_vtu(path, *link_lines);
    written.push_back(path);
  }
  if (!info.mesh_report.discontinuities.empty()) {
    const std::string lines = (fs::path(p.out_dir) / "discontinuities.vtu").string();
    write_discontinuities_vtu(lines, info.mesh_report.discontinuities);
    written.push_back(lines);
  }
  if (!probes.empty()) {
    const std::string csv = (fs::path(p.out_dir) / "probes.csv").string();
    write_probe_csv(csv, scene, probes, probe_results);
    written.push_back(csv);
  }
  if (solving && p.png) {
    const std::string png = (fs::path(p.out_dir) / "radiosity.png").string();
    std::string why;
    if (render_png(png, scene, out_mesh, *sol, RenderOptions{}, &why))
      written.push_back(png);
    else
      rep.note("PNG skipped: " + why);
  }
  info.seconds.push_back({"write", rep.end()});
  const std::string summary = (fs::path(p.out_dir) / "summary.json").string();
  write_json(summary, make_summary(info, scene, out_mesh, out_quality, sol ? &*sol : nullptr));
  written.push_back(summary);

  if (!p.quiet) {
    if (sol) {
      const auto& st = sol->stats;
      std::fprintf(stderr, "[radmesh] %lld form factors, %lld rays cast, %lld skipped; residual %.2g; energy imbalance %.2g\n",
                   st.form_factors, st.rays_cast, st.rays_skipped,
                   std::max({st.residual[0], st.residual[1], st.residual[2]}),
                   st.power_emitted.x > 0 ? (st.power_emitted.x - st.power_absorbed.x - st.power_escaped.x) / st.power_emitted.x : 0.0);
    }
  }
  for (const std::string& w : written) std::printf("%s\n", w.c_str());
  return 0;
}

// radmesh quality: the mesh study table on stdout and in quality.csv. The
// input is a scene (meshed here with the given options) or a mesh written by
// radmesh (mesh.vtu or radiosity.vtu; the discontinuities.vtu beside it, when
// there is one, gives the line counts).
int quality(Params& p) {
  check_params(p, false);
  Mesh mesh;
  std::vector<DiscontinuitySegment> lines;
  std::vector<std::string> names;
  if (fs::path(p.scene).extension() == ".vtu") {
    mesh = read_mesh_vtu(p.scene);
    const fs::path beside = fs::path(p.scene).parent_path() / "discontinuities.vtu";
    if (fs::exists(beside)) lines = read_discontinuities_vtu(beside.string());
    int np = 0;
    for (int q : mesh.patch) np = std::max(np, q + 1);
    for (int q = 0; q < np; ++q) names.push_back("patch_" + std::to_string(q));
  } else {
    const Scene scene = read_scene(p.scene);
    const MeshingOptions mo = resolve_meshing_options(scene, p.meshing);
    MeshReport report;
    mesh = mesh_scene(scene, mo, &report);
    lines = report.discontinuities;
    for (const Patch& patch : scene.patches) names.push_back(patch.name);
    if (!p.quiet)
      for (const std::string& w : report.shadow.warnings) std::fprintf(stderr, "[radmesh] warning: %s\n", w.c_str());
  }
  const TriangleQuality q = compute_quality(mesh);
  const auto rows = patch_quality(static_cast<int>(names.size()), mesh, q, lines);
  std::printf("%-4s %-20s %9s %8s %8s %8s %8s %8s %7s %7s %7s %9s\n", "id", "patch", "triangles", "min_ang",
              "max_ang", "asp_p50", "asp_p95", "asp_max", "D0_segs", "D1_segs", "D2_segs", "zero_area");
  for (const PatchQuality& r : rows)
    std::printf("%-4d %-20s %9d %8.2f %8.2f %8.3f %8.3f %8.3f %7d %7d %7d %9d\n", r.patch,
                (r.patch < 0 ? std::string("total") : names[static_cast<size_t>(r.patch)]).c_str(), r.triangles,
                r.min_angle, r.max_angle, r.aspect_p50, r.aspect_p95, r.aspect_max, r.contact_segments,
                r.d1_segments, r.d2_segments, r.zero_area);
  fs::create_directories(p.out_dir);
  const std::string csv = (fs::path(p.out_dir) / "quality.csv").string();
  write_quality_csv(csv, names, rows);
  std::printf("%s\n", csv.c_str());
  // Histograms of every triangle's smallest angle and aspect ratio.
  const std::pair<const char*, const std::vector<double>*> plots[] = {{"min_angle", &q.min_angle},
                                                                      {"aspect_ratio", &q.aspect_ratio}};
  for (const auto& [name, values] : plots) {
    const std::string png = (fs::path(p.out_dir) / ("quality_" + std::string(name) + ".png")).string();
    std::string why;
    if (plot_histogram(png, std::string("radmesh quality: ") + name, name, *values, 30, &why))
      std::printf("%s\n", png.c_str());
    else if (!p.quiet)
      std::fprintf(stderr, "[radmesh] histograms skipped: %s\n", why.c_str());
  }
  return 0;
}

void add_common(CLI::App* cmd, Params& p,
                const char* scene_help = "scene file: .obj (+ .mtl), .ply, .stl, .off, .gltf, .glb, or a .json scene") {
  cmd->add_option("SCENE", p.scene, scene_help)->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", p.out_dir, "output directory (created; default radmesh-out)");
  cmd->add_option("--max-edge", p.meshing.max_edge,
                  "longest mesh edge, in scene units (default 0 = scene diagonal / 12; for run with the "
                  "hierarchical method, the roots: scene diagonal / 5)")
      ->check(CLI::Range(0.0, 1e300));
  cmd->add_option("--min-angle", p.meshing.min_angle, "smallest triangle angle wanted, degrees (default 20)")
      ->check(CLI::Range(0.0, 30.0));
  cmd->add_option("--discontinuity", p.discontinuity,
                  "discontinuity lines built into the initial mesh: off, contacts (where patches meet) or "
                  "full (contacts and the D1/D2 shadow boundaries of every emitter). Default: contacts for "
                  "run (hierarchical refines across shadows by itself), full for mesh, quality and run "
                  "--method matrix")
      ->check(CLI::IsMember({"off", "contacts", "full"}));
  cmd->add_option("--max-shadow-lines", p.meshing.shadow.max_lines_per_receiver,
                  "with --discontinuity full: shadow-line segments kept per receiving patch (default 400)")
      ->check(CLI::Range(0, 1000000));
  cmd->add_flag("-q,--quiet", p.quiet, "no progress on stderr");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"radmesh: exact-geometry meshing and radiosity.\n"
               "Lengths are in the scene file's units; emission (Ke) is radiant exitance, and\n"
               "radiosity comes out in the same unit (per unit area of the file's unit)."};
  app.require_subcommand(1);
  Params run_p, mesh_p, quality_p;

  CLI::App* run_cmd = app.add_subcommand("run", "mesh the scene, solve radiosity, write .vtu, .png, summary.json");
  add_common(run_cmd, run_p);
  run_cmd->add_option("--tolerance", run_p.solve.tolerance,
                      "Gauss-Seidel stops when a sweep changes radiosity by less than this fraction of the "
                      "largest value (default 1e-6)")
      ->check(CLI::Range(1e-15, 0.999));
  run_cmd->add_option("--threads", run_p.solve.threads, "worker threads, 0 = all cores (default 0)")
      ->check(CLI::Range(0, 4096));
  run_cmd->add_option("--rays", run_p.solve.rays, "shadow rays per element pair (default 16)")
      ->check(CLI::Range(1, 4096));
  run_cmd->add_option("--max-memory", run_p.solve.max_memory_gb,
                      "GiB the form-factor matrix (matrix) or the links and leaf terms (hierarchical) may use "
                      "(default 0 = half the memory)")
      ->check(CLI::Range(0.0, 1e6));
  run_cmd->add_option("--probe", run_p.probe_file,
                      "probe file: lines 'label x y z nx ny nz'; writes probes.csv")
      ->check(CLI::ExistingFile);
  run_cmd->add_flag("!--no-png", run_p.png, "do not render radiosity.png");
  run_cmd->add_option("--method", run_p.method,
                      "solver: hierarchical (Hanrahan's hierarchical radiosity on an element hierarchy closed "
                      "by zero-area triangles, the default; also writes radiosity.pvd, one file per refinement "
                      "round) or matrix (every element pair of the initial mesh)")
      ->check(CLI::IsMember({"matrix", "hierarchical"}));
  run_cmd->add_option("--epsilon", run_p.hierarchical.epsilon,
                      "with --method hierarchical: link refinement threshold, relative to the largest "
                      "reflected radiosity (default 0.001)")
      ->check(CLI::Range(1e-9, 1.0));
  run_cmd->add_option("--tvertex", run_p.tvertex,
                      "with --method hierarchical: vertex values on a neighbour's unsplit edge: anchor (the "
                      "edge's interpolant, no shading jump), free (from the finer side; default), or split "
                      "(split neighbours until no T-vertex is left, no zero-area triangles)")
      ->check(CLI::IsMember({"anchor", "free", "split"}));
  run_cmd->add_option("--min-area", run_p.hierarchical.min_area,
                      "with --method hierarchical: elements are not split below this area, in scene units "
                      "squared (default 0 = (scene diagonal / 150)^2 / 2)")
      ->check(CLI::Range(0.0, 1e300));
  run_cmd->add_flag("--export-links", run_p.export_links,
                    "with --method hierarchical: also write links.vtu, every link as a line from receiver to "
                    "source (fields receiver_level, source_level, receiver_patch, source_patch, form_factor, "
                    "visible, transport)");
  run_cmd->add_option("--baum", run_p.hierarchical.baum_relative,
                      "with --method hierarchical: also split a leaf whose vertex values differ by more than "
                      "this fraction of the largest reflected radiosity (Baum's criterion; default 0 = off)")
      ->check(CLI::Range(0.0, 1.0));
  run_cmd->add_option("--nodal", run_p.nodal,
                      "vertex values from element values: fit (least-squares plane through the elements "
                      "around the vertex, default) or mean (their area-weighted mean)")
      ->check(CLI::IsMember({"fit", "mean"}));

  CLI::App* mesh_cmd = app.add_subcommand("mesh", "mesh the scene and report quality; writes mesh.vtu and summary.json");
  add_common(mesh_cmd, mesh_p);
  CLI::App* quality_cmd = app.add_subcommand(
      "quality", "mesh the scene; print per-patch and total mesh quality and write quality.csv");
  add_common(quality_cmd, quality_p,
             "scene file (.obj, .ply, .stl, .off, .gltf, .glb, .json), or a mesh written by radmesh (.vtu)");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  for (const char* flag : {"--epsilon", "--tvertex", "--baum", "--min-area", "--export-links"})
    if (run_cmd->count(flag) > 0) run_p.hierarchical_flags_given.push_back(flag);
  try {
    if (*run_cmd) return run(run_p, true);
    if (*quality_cmd) return quality(quality_p);
    return run(mesh_p, false);
  } catch (const radmesh::Error& e) {
    std::fprintf(stderr, "radmesh: error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "radmesh: internal error: %s\n", e.what());
    return 3;
  }
}
