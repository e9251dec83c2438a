// The radmesh program: subcommands `run` (mesh + solve + write results) and
// `mesh` (mesh and quality only). Every error is caught here, once, and
// printed as one line; the exit status is then non-zero.

#include "radmesh/histogram.h"
#include "radmesh/scene_reader.h"
#include "radmesh/probe_file.h"
#include "radmesh/summary.h"
#include "radmesh/vtk_writer.h"
#include "radmesh/errors.h"
#include "radmesh/mesh.h"
#include "radmesh/method.h"
#include "radmesh/output_batch.h"
#include "radmesh/probe.h"
#include "radmesh/result_files.h"
#include "radmesh/solve.h"
#include "radmesh/version.h"
#include "core/text_syntax.h"
#include "io/writers/atomic_file.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>

#include <atomic>
#include <csignal>
#include <ctime>

#include <unistd.h>

namespace {

using namespace radmesh;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// Options of one table (meshing, solve, a method's) as the command line
// gave them: text per name, flags as bools; only those given are kept.
struct GivenOptions {
  std::map<std::string, std::string> text;
  std::map<std::string, bool> flag;
  OptionValues given;
};

struct Params {
  std::string scene;
  std::string out_dir = "radmesh-out";
  std::string probe_file;
  std::string resume;  // --resume DIR: the -o directory of a run that saved its state
  bool quiet = false;
  bool png = true;
  std::string nodal;  // --nodal fit|mean: the older name of --field fit|mean
  std::string method = methods().front().name;
  std::string preset = "default";  // --preset: Method::presets, filling in what is not given
  GivenOptions scene_given, meshing_given, solve_given, method_given;
  // Read and checked by check_params.
  SceneOptions scene_options;
  MeshingOptions meshing;  // the defaults with what was given on top (mesh, quality)
  SolveOptions solve;
  MethodOptions method_options;
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

// The output directory can be made: it is a directory, or its nearest
// existing ancestor is a writable directory. Checked before any work.
void check_output_dir(const std::string& dir) {
  std::error_code ec;
  fs::path d = fs::absolute(dir, ec);
  if (fs::exists(d, ec) && !fs::is_directory(d, ec)) throw InputError("-o " + dir + ": exists and is not a directory");
  while (!d.empty() && !fs::exists(d, ec)) d = d.parent_path();
  if (d.empty() || !fs::is_directory(d, ec))
    throw InputError("-o " + dir + ": cannot be created (" + d.string() + " is not a directory)");
  if (::access(d.c_str(), W_OK) != 0)
    throw InputError("-o " + dir + ": cannot be created or written (" + d.string() + " is not writable)");
}

// Ctrl-C during a method that can stop early (Method::resumable): the first
// one asks it to stop and save its state, a second one (half a second or
// more later: a signal sent to the process and to its group arrives twice)
// ends the program.
std::atomic<bool> g_interrupted{false};
std::atomic<long long> g_first_interrupt_ns{0};
extern "C" void on_interrupt(int) {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);  // async-signal-safe
  const long long ns = now.tv_sec * 1000000000LL + now.tv_nsec;
  if (!g_interrupted.exchange(true)) {
    g_first_interrupt_ns.store(ns);
  } else if (ns - g_first_interrupt_ns.load() > 500000000LL) {
    std::signal(SIGINT, SIG_DFL);
    std::raise(SIGINT);
  }
}
// What quality writes.
const char* const kQualityOutputs = R"(quality\.csv|quality_(min_angle|aspect_ratio)\.png)";

// The names given on the command line, of a table's options.
std::vector<std::string> names_of(const OptionValues& given) {
  std::vector<std::string> out;
  for (const auto& entry : given) out.push_back(entry.first);
  return out;
}

// Options that can be checked without reading anything: done before any work.
void check_params(Params& p, bool solving) {
  if (!p.nodal.empty()) {
    const auto field = p.solve_given.given.find("field");
    if (field != p.solve_given.given.end() && field->second != "auto" && field->second != p.nodal)
      throw InputError("nodal " + p.nodal + " and field " + field->second + " disagree; give one of them",
                       {"nodal", "field"});
    p.solve_given.given["field"] = p.nodal;
  }
  p.scene_options = scene_option_table().parse(p.scene_given.given);
  if (solving)
    apply_preset(find_method(p.method), p.preset, p.solve_given.given, p.meshing_given.given, p.method_given.given);
  p.meshing = meshing_option_table().parse(p.meshing_given.given);
  if (solving) {
    p.solve = solve_option_table().parse(p.solve_given.given);
    // An option the method does not take, one of the run's it does not
    // use, or a value out of its range is an error here, for every method
    // alike.
    const Method& method = find_method(p.method);
    p.method_options = method_options(method, p.method_given.given);
    std::vector<std::string> shared = names_of(p.solve_given.given);
    for (const std::string& name : names_of(p.meshing_given.given)) shared.push_back(name);
    check_shared_options(method, shared, p.solve.field);
    check_solve_options(p.solve);
  } else if (!p.method_given.given.empty()) {
    throw InputError(p.method_given.given.begin()->first + ": a method option; only run takes it",
                     {p.method_given.given.begin()->first});
  }
  check_output_dir(p.out_dir);
  if (!p.probe_file.empty() && !fs::exists(p.probe_file))
    throw InputError("--probe " + p.probe_file + ": no such file");
}

// The meshing a run starts from: the method's recommendation, with every
// meshing option the user gave on top (mesh and quality: the defaults).
MeshingOptions meshing_for(const Params& p, const Scene& scene, const Method* method) {
  if (!method) return p.meshing;
  MeshingOptions mo = method->meshing(scene);
  meshing_option_table().apply(mo, p.meshing_given.given);
  return mo;
}

// What a run computes before it writes anything.
struct Computed {
  RunInfo info;
  Scene scene;
  Mesh mesh;                          // the initial mesh
  std::optional<MethodResult> result;  // the method's (its own mesh); none for mesh only
  std::vector<MethodResult> rounds;   // one snapshot per refinement round, for the .pvd series
  std::vector<Probe> probes;
  std::vector<ProbeResult> probe_results;
  const Mesh& out_mesh() const { return result ? result->mesh : mesh; }
};

// The method's solve, with progress, Ctrl-C for a method that can stop
// early and resume, and what it says on stderr.
void solve_with(const Params& p, const Method& method, Reporter& rep, Computed& c) {
  rep.begin(method.name);
  SolveCallbacks cb;
  cb.progress = [&](const std::string& phase, double f) { rep.update(phase, f); };
  cb.on_round = [&](const MethodResult& r, int) { c.rounds.push_back(r); };
  if (!p.resume.empty()) cb.resume = read_method_state(method, p.resume);
  if (method.resumable()) {
    struct sigaction sa {};
    sa.sa_handler = on_interrupt;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, nullptr);
    cb.cancelled = [] { return g_interrupted.load(); };
  }
  c.result = run_method(method, c.scene, c.mesh, p.solve, p.method_options, cb);
  if (method.resumable()) std::signal(SIGINT, SIG_DFL);
  rep.end();
  for (const auto& phase : c.result->seconds) c.info.seconds.push_back(phase);
  if (!c.result->report.empty()) rep.note(c.result->report);
  for (const std::string& w : c.result->warnings) rep.note("warning: " + w);
  const FieldReport& f = c.result->field;
  if (!f.why.empty()) rep.note(f.why);
  if (f.mode == FieldMode::gather)
    rep.note("field: gather at " + std::to_string(f.display_vertices) + " vertices; direct light " +
             std::to_string(f.direct.unoccluded) + " unoccluded, " + std::to_string(f.direct.hidden) + " hidden, " +
             std::to_string(f.direct.clipped) + " clipped exactly; " + std::to_string(f.rays_cast) + " gather rays");
}

// Reads, meshes, solves (method may be null: mesh only) and evaluates the probes.
Computed compute(const Params& p, const Method* method, Reporter& rep) {
  Computed c;
  c.info.command = method ? "run" : "mesh";
  c.info.scene_path = p.scene;
  c.info.solve = p.solve;
  rep.begin("read");
  c.scene = read_scene(p.scene, p.scene_options);
  c.info.seconds.push_back({"read", rep.end()});
  for (const std::string& w : c.scene.report.warnings) rep.note("warning: " + w);
  if (!p.probe_file.empty()) c.probes = read_probes(p.probe_file);

  c.info.meshing = resolve_meshing_options(c.scene, meshing_for(p, c.scene, method));
  c.info.method = method ? method->name : "none";
  c.info.method_options = p.method_options.values();
  c.info.preset = p.preset;
  rep.begin("mesh");
  c.mesh = mesh_scene(c.scene, c.info.meshing, &c.info.mesh_report);
  c.info.seconds.push_back({"mesh", rep.end()});
  for (const std::string& w : c.info.mesh_report.warnings) rep.note("warning: " + w);
  rep.note(std::to_string(c.scene.patches.size()) + " patches, " + std::to_string(c.mesh.triangle_count()) +
           " elements (max edge " + std::to_string(c.info.meshing.max_edge) + ")");
  if (!method) return c;
  solve_with(p, *method, rep, c);
  if (!c.probes.empty()) {
    rep.begin("probes");
    c.probe_results = evaluate_probes(c.scene, c.out_mesh(), c.result->solution.element, c.probes, p.solve);
    c.info.seconds.push_back({"probes", rep.end()});
  }
  return c;
}

// The files of a run, once everything is computed: only now is the output
// directory touched (write_run_files: all of them or none). Returns the
// paths written, in order.
std::vector<std::string> write_outputs(const Params& p, Computed& c, Reporter& rep) {
  RunFiles files;
  files.info = c.info;
  files.scene = &c.scene;
  files.mesh = &c.mesh;
  files.result = c.result ? &*c.result : nullptr;
  files.rounds = std::move(c.rounds);
  files.probes = c.probes;
  files.probe_results = c.probe_results;
  files.png = p.png;
  rep.begin("write");
  std::vector<std::string> notes;
  std::vector<std::string> written = write_run_files(p.out_dir, std::move(files), &notes);
  rep.end();
  for (const std::string& n : notes) rep.note(n);
  return written;
}

// One line on stderr: the solve's counts, residual and energy balance.
void print_solve_line(const SolveStats& st) {
  const double bound = std::max({st.error_bound[0], st.error_bound[1], st.error_bound[2]});
  const bool unbounded = std::min({st.error_bound[0], st.error_bound[1], st.error_bound[2]}) < 0.0;
  std::fprintf(stderr,
               "[radmesh] %lld form factors, %lld rays cast, %lld skipped; residual %.2g (error at most %s); "
               "energy imbalance %.2g\n",
               st.form_factors, st.rays_cast, st.rays_skipped, std::max({st.residual[0], st.residual[1], st.residual[2]}),
               unbounded ? "unbounded: rho x row sum reaches 1" : format_number(bound).c_str(),
               st.power_emitted.x > 0 ? (st.power_emitted.x - st.power_absorbed.x - st.power_escaped.x) / st.power_emitted.x
                                      : 0.0);
}

int run(Params& p, bool solving) {
  check_params(p, solving);
  Reporter rep(p.quiet);
  Computed c = compute(p, solving ? &find_method(p.method) : nullptr, rep);
  const std::vector<std::string> written = write_outputs(p, c, rep);
  if (c.result && !p.quiet) print_solve_line(c.result->solution.stats);
  for (const std::string& w : written) std::printf("%s\n", w.c_str());
  if (c.result && c.result->interrupted) {
    std::fprintf(stderr,
                 "[radmesh] interrupted after %s; the state is saved in %s. Continue with the same options and: "
                 "--resume %s\n",
                 c.result->progress.c_str(), p.out_dir.c_str(), p.out_dir.c_str());
    return 130;
  }
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
    const Scene scene = read_scene(p.scene, p.scene_options);
    const MeshingOptions mo = resolve_meshing_options(scene, meshing_for(p, scene, nullptr));
    MeshReport report;
    mesh = mesh_scene(scene, mo, &report);
    lines = report.discontinuities;
    for (const Patch& patch : scene.patches) names.push_back(patch.name);
    if (!p.quiet)
      for (const std::string& w : report.warnings) std::fprintf(stderr, "[radmesh] warning: %s\n", w.c_str());
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
  OutputBatch batch;  // all files or none, as for run
  internal::prepare_output_dir(p.out_dir, kQualityOutputs,
                               {"quality.csv", "quality_min_angle.png", "quality_aspect_ratio.png"});
  const std::string csv = (fs::path(p.out_dir) / "quality.csv").string();
  write_quality_csv(csv, names, rows);
  std::vector<std::string> written = {csv};
  // Histograms of every triangle's smallest angle and aspect ratio.
  const std::pair<const char*, const std::vector<double>*> plots[] = {{"min_angle", &q.min_angle},
                                                                      {"aspect_ratio", &q.aspect_ratio}};
  for (const auto& [name, values] : plots) {
    const std::string png = (fs::path(p.out_dir) / ("quality_" + std::string(name) + ".png")).string();
    std::string why;
    if (plot_histogram(png, std::string("radmesh quality: ") + name, name, *values, 30, &why))
      written.push_back(png);
    else if (!p.quiet)
      std::fprintf(stderr, "[radmesh] histograms skipped: %s\n", why.c_str());
  }
  batch.commit();
  for (const std::string& w : written) std::printf("%s\n", w.c_str());
  return 0;
}

// A value that reads as a number (the range is the option table's to check,
// with a message naming the option): otherwise a usage error.
const CLI::Validator kNumber(
    [](std::string& text) {
      double value = 0.0;
      const std::string why = internal::read_number(text, &value);
      return why.empty() ? std::string() : text + " " + why;
    },
    "NUMBER");

// One option of a table as a flag: its help with its unit, choices, default
// and range, `prefix` first ("with --method pixmap: ").
void add_table_option(CLI::App* cmd, const OptionSpec& spec, GivenOptions& to, const std::string& prefix,
                      const std::string& default_text) {
  std::string help = prefix + spec.help;
  if (!spec.unit.empty()) help += ", in " + spec.unit;
  if (spec.kind == OptionSpec::Kind::flag) {
    cmd->add_flag(spec.flag(), to.flag[spec.name], help);
    return;
  }
  help += " (default " + default_text;
  if (spec.kind == OptionSpec::Kind::real || spec.kind == OptionSpec::Kind::integer)
    help += "; range [" + format_number(spec.min) + ", " + format_number(spec.max) + "]";
  CLI::Option* o = cmd->add_option(spec.flag(), to.text[spec.name], help + ")");
  if (spec.kind == OptionSpec::Kind::choice)
    o->check(CLI::IsMember(spec.choices));
  else
    o->check(kNumber);
}

void add_common(CLI::App* cmd, Params& p, bool solving,
                const char* scene_help =
                    "scene file: .obj (+ .mtl), .ply, .stl, .off, .gltf, .glb, .mgf, or a .json scene") {
  cmd->add_option("SCENE", p.scene, scene_help)->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", p.out_dir, "output directory (created; default radmesh-out)");
  for (const OptionSpec& spec : scene_option_table().specs())
    add_table_option(cmd, spec, p.scene_given, "", spec.default_text());
  for (const OptionSpec& spec : meshing_option_table().specs())
    add_table_option(cmd, spec, p.meshing_given, "",
                     solving && (spec.name == "max_edge" || spec.name == "discontinuity")
                         ? "the method's"
                         : (spec.name == "max_edge" ? "scene diagonal / 12" : spec.default_text()));
  cmd->add_flag("-q,--quiet", p.quiet, "no progress on stderr");
}

// Every option of every method in the table, registered once; which method
// takes it is said in its help, and checked after parsing (check_params).
void add_method_options(CLI::App* cmd, Params& p) {
  std::string list;
  for (const Method& m : methods()) list += "\n  " + m.name + (list.empty() ? " (default)" : "") + ": " + m.help;
  std::vector<std::string> names;
  for (const Method& m : methods()) names.push_back(m.name);
  cmd->add_option("--method", p.method, "solver, one of:" + list)->check(CLI::IsMember(names));
  std::string presets = "options set together (any given by name wins): default (the defaults)";
  for (const Method& m : methods())
    for (const Preset& preset : m.presets) {
      std::string values;
      for (const auto& [name, value] : preset.values) values += (values.empty() ? "" : " ") + option_flag(name) + " " + value;
      presets += "\n  " + preset.name + " (--method " + m.name + "): " + values + "; " + preset.help;
    }
  cmd->add_option("--preset", p.preset, presets)->check(CLI::IsMember(preset_names()));
  for (const auto& [spec, takers] : all_method_options()) {
    std::string who;
    for (const std::string& t : takers) who += (who.empty() ? "" : ", ") + t;
    add_table_option(cmd, spec, p.method_given, "with --method " + who + ": ", spec.default_text());
  }
}

// After parsing: the options of `specs` given on the command line.
void collect_given(CLI::App* cmd, const std::vector<OptionSpec>& specs, GivenOptions& to) {
  for (const OptionSpec& spec : specs)
    if (cmd->get_option_no_throw(spec.flag()) != nullptr && cmd->count(spec.flag()) > 0)
      to.given[spec.name] =
          spec.kind == OptionSpec::Kind::flag ? (to.flag[spec.name] ? "true" : "false") : to.text[spec.name];
}

void collect_given(CLI::App* cmd, Params& p) {
  collect_given(cmd, scene_option_table().specs(), p.scene_given);
  collect_given(cmd, meshing_option_table().specs(), p.meshing_given);
  collect_given(cmd, solve_option_table().specs(), p.solve_given);
  std::vector<OptionSpec> method_specs;
  for (const auto& entry : all_method_options()) method_specs.push_back(entry.first);
  collect_given(cmd, method_specs, p.method_given);
}

// An error's message with the options it names written as flags
// (max_edge -> --max-edge).
std::string as_flags(const Error& e) {
  std::string message = e.what();
  for (const std::string& name : e.options()) {
    const std::string flag = option_flag(name);
    auto word = [&](size_t k) { return k < message.size() && (std::isalnum(static_cast<unsigned char>(message[k])) || message[k] == '_' || message[k] == '-'); };
    for (size_t k = message.find(name); k != std::string::npos; k = message.find(name, k)) {
      if ((k > 0 && word(k - 1)) || word(k + name.size())) {
        k += name.size();
        continue;
      }
      message.replace(k, name.size(), flag);
      k += flag.size();
    }
  }
  return message;
}

}  // namespace

int main(int argc, char** argv) {
  // A file-size limit (ulimit -f) reached is a write that fails, reported
  // like a full disk, not a signal that kills the program mid-write.
  std::signal(SIGXFSZ, SIG_IGN);
  CLI::App app{"radmesh: exact-geometry meshing and radiosity.\n"
               "Lengths are in the scene file's units; emission (Ke) is radiant exitance, and\n"
               "radiosity comes out in the same unit (per unit area of the file's unit). MGF's\n"
               "emission (ed, lux) is divided by 179 lm/W, Radiance's white efficacy."};
  app.require_subcommand(1);
  app.set_version_flag("--version", RADMESH_VERSION);
  Params run_p, mesh_p, quality_p;

  CLI::App* run_cmd = app.add_subcommand("run", "mesh the scene, solve radiosity, write .vtu, .png, summary.json");
  add_common(run_cmd, run_p, true);
  for (const OptionSpec& spec : solve_option_table().specs())
    add_table_option(run_cmd, spec, run_p.solve_given, "", spec.default_text());
  run_cmd->add_option("--probe", run_p.probe_file,
                      "probe file: lines 'label x y z nx ny nz'; writes probes.csv")
      ->check(CLI::ExistingFile);
  run_cmd->add_flag("!--no-png", run_p.png, "do not render radiosity.png");
  std::string resumable;
  for (const Method& m : methods())
    if (m.resumable()) resumable += (resumable.empty() ? "" : ", ") + m.name;
  run_cmd->add_option("--resume", run_p.resume,
                      "continue the run whose -o directory this is, from the state it saved, with the same scene "
                      "and options (--method " + resumable + "; --shots counts the shots made before)")
      ->check(CLI::ExistingDirectory);
  run_cmd->add_option("--nodal", run_p.nodal, "the older name of --field fit|mean")
      ->check(CLI::IsMember({"fit", "mean"}));
  add_method_options(run_cmd, run_p);

  CLI::App* mesh_cmd = app.add_subcommand("mesh", "mesh the scene and report quality; writes mesh.vtu and summary.json");
  add_common(mesh_cmd, mesh_p, false);
  CLI::App* quality_cmd = app.add_subcommand(
      "quality", "mesh the scene; print per-patch and total mesh quality and write quality.csv");
  add_common(quality_cmd, quality_p, false,
             "scene file (.obj, .ply, .stl, .off, .gltf, .glb, .mgf, .json), or a mesh written by radmesh (.vtu)");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // Usage errors (an unknown flag, a bad value, a missing argument) exit
    // with 2; --help and --version with 0.
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  try {
    if (*run_cmd) {
      collect_given(run_cmd, run_p);
      return run(run_p, true);
    }
    if (*quality_cmd) {
      collect_given(quality_cmd, quality_p);
      return quality(quality_p);
    }
    collect_given(mesh_cmd, mesh_p);
    return run(mesh_p, false);
  } catch (const radmesh::Error& e) {
    std::fprintf(stderr, "radmesh: error: %s\n", as_flags(e).c_str());
    return 1;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr,
                 "radmesh: error: out of memory: the system refused an allocation; lower --max-memory (its checks "
                 "then refuse the run before it allocates) or the options that size the run\n");
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "radmesh: internal error: %s\n", e.what());
    return 3;
  }
}
