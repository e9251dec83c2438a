// Pixmap radiosity (progressive refinement through hemicubes onto texel
// grids) as an entry of the method table.

#include "io/writers/pixmap_io.h"
#include "radiosity/transport/occlusion.h"
#include "radmesh/errors.h"
#include "radmesh/method.h"
#include "radmesh/pixmap.h"
#include "radmesh/run.h"

#include <chrono>
#include <cstdio>

namespace radmesh {

namespace {

// The result of a state: the display mesh with its values, the counts and
// the state itself for the files.
MethodResult result_of(const std::shared_ptr<const PixmapSolver>& solver, const PixmapState& state, bool convex) {
  MethodResult r;
  auto out = std::make_shared<PixmapOutput>();
  out->solver = solver;
  out->state = state;
  out->ambient = solver->ambient(state);
  out->display = solver->display(state, out->ambient);
  std::vector<int> texel;
  solver->display_mesh(out->display, r.mesh, r.solution, texel);
  const PixmapLayout& L = solver->layout();
  std::vector<int> pixmap(r.mesh.triangles.size());
  for (size_t t = 0; t < pixmap.size(); ++t) pixmap[t] = L.pixmap_of_patch[r.mesh.patch[t]];
  r.cell_fields = {{"pixmap", std::move(pixmap)}, {"texel", std::move(texel)}};
  SolveStats& st = r.solution.stats;
  st.elements = L.covered;
  st.convex_enclosure = convex;
  st.power_absorbed = state.power_absorbed * solver->unit();
  // What emitting parts inside closed objects emit goes into the objects:
  // emitted and escaped, as the other methods count it.
  st.power_escaped = state.power_escaped * solver->unit() + solver->power_enclosed();
  st.power_emitted = solver->power_emitted() + solver->power_enclosed();
  st.warnings = solver->warnings();
  // Its state (to resume from) and its lightmaps, beside radiosity.vtu.
  r.files.names = {"lightmapped.obj", "lightmapped.mtl"};
  r.files.write = [out = std::shared_ptr<const PixmapOutput>(std::move(out))](const std::string& dir, const Mesh& mesh) {
    std::vector<std::string> written = write_pixmap_state(dir, *out);
    for (const std::string& f : write_lightmaps(dir, mesh, *out)) written.push_back(f);
    return written;
  };
  return r;
}

constexpr const char* kName = "pixmap";

}  // namespace

const OptionTable<PixmapOptions>& pixmap_option_table() {
  static const OptionTable<PixmapOptions> table = [] {
    OptionTable<PixmapOptions> t("method pixmap");
    using P = PixmapOptions;
    t.real("texel_size", &P::texel_size, "scene units", "texel edge of the pixmaps (0: scene diagonal / 80)", 0.0,
           1e300);
    t.integer("max_texels", &P::max_texels, "", "most texels one pixmap may have (its texels grow to fit)", 1,
              1 << 26);
    t.integer("hemicube_res", &P::hemicube_res, "", "hemicube pixels along the top face's side (even)", 2, 16384);
    t.integer("block", &P::block, "", "a shooter is a block of block x block texels", 1, 256);
    t.real("unshot", &P::unshot, "", "stop when the unshot power is at most this fraction of the emitted power",
           0.0, 0.999);
    t.integer("shots", &P::shots, "", "stop after this many shots in all, those before a resume included (0: no limit)",
              0, 1e15);
    t.integer("snapshot_every", &P::snapshot_every, "", "write a snapshot of the field every this many shots (0: none)",
              0, 1e15);
    return t;
  }();
  return table;
}

Method make_pixmap_method() {
  Method m = make_method<PixmapOptions>(
      kName,
      "progressive refinement onto texel grids (pixmaps) with hemicube item-buffer form factors; saves lightmaps "
      "and a state that --resume continues",
      pixmap_option_table(),
      [](const Scene& scene, const Mesh&, const SolveOptions& so, const PixmapOptions& po, const SolveCallbacks& cb) {
    auto solver = std::make_shared<const PixmapSolver>(scene, po, so);
    const bool convex = Occlusion(scene).convex_enclosure();
    PixmapState start;
    if (cb.resume) {
      const auto saved = std::dynamic_pointer_cast<const PixmapState>(cb.resume);
      if (!saved) throw InputError(cb.resume->source + ": cannot resume: not a pixmap method's state", {"resume"});
      check_resumable(*saved, scene, solver->layout(), po, saved->source);
      start = *saved;
    } else {
      start = solver->initial_state();
    }
    PixmapCallbacks pc;
    pc.progress = cb.progress;
    pc.cancelled = cb.cancelled;
    pc.snapshot_every = po.snapshot_every;
    if (cb.on_round)
      pc.on_snapshot = [&](const PixmapState& s) {
        cb.on_round(result_of(solver, s, convex), static_cast<int>(s.shots));
      };
    const auto t0 = std::chrono::steady_clock::now();
    const PixmapRun run = solver->run(std::move(start), pc);
    const double run_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const auto t1 = std::chrono::steady_clock::now();
    MethodResult r = result_of(solver, run.state, convex);
    const double display_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
    r.interrupted = run.interrupted;
    r.progress = std::to_string(run.state.shots) + " shots";
    SolveStats& st = r.solution.stats;
    for (int c = 0; c < 3; ++c) {
      st.residual[static_cast<size_t>(c)] = run.residual[static_cast<size_t>(c)];
      st.error_bound[static_cast<size_t>(c)] = -1.0;  // no max-norm bound: hemicube factors are not reciprocal
    }
    st.form_factors = 0;
    st.seconds_form_factors = run.seconds_hemicubes;
    st.seconds_solve = run.seconds_shots;
    const PixmapLayout& L = solver->layout();
    r.counters = {count("pixmaps", static_cast<double>(L.pixmaps.size())),
                  count("texels", static_cast<double>(L.covered)),
                  count("shooters", static_cast<double>(L.shooters.size())),
                  count("shots", static_cast<double>(run.state.shots)),
                  count("shots_this_run", static_cast<double>(run.shots_this_run)),
                  count("hemicubes", static_cast<double>(run.rows_computed)),
                  count("rows_cached", static_cast<double>(run.rows_cached)),
                  count("pixels_spread", static_cast<double>(run.pixels_spread)),
                  measure("unshot_fraction", run.unshot_fraction),
                  Counter{"ambient",
                          {run.ambient.x * solver->unit(), run.ambient.y * solver->unit(), run.ambient.z * solver->unit()},
                          "", true, false},
                  count("interrupted", run.interrupted ? 1.0 : 0.0)};
    r.seconds = {{"hemicubes", run.seconds_hemicubes},
                 {"shots", run.seconds_shots},
                 {"display", display_seconds},
                 {"other", std::max(0.0, run_seconds - run.seconds_hemicubes - run.seconds_shots)}};
    char line[256];
    std::snprintf(line, sizeof line, "%zu pixmaps, %lld texels, %zu shooters; %lld shots (%lld this run), %lld hemicubes; "
                  "unshot %.3g of the emitted power",
                  L.pixmaps.size(), L.covered, L.shooters.size(), run.state.shots, run.shots_this_run,
                  run.rows_computed, run.unshot_fraction);
    r.report = line;
    return r;
      });
  // The geometry is never cut finer for the solve: the solver meshes the
  // scene itself, the coarsest mesh with the contact lines (what
  // pixmap_meshing_options gives), and its display mesh follows the texels.
  // The meshing options, the solve's tolerance and its shadow rays (the
  // hemicubes see occlusion) are not its.
  m.meshing = pixmap_meshing_options;
  m.unused = {"tolerance", "rays", "display_tolerance", "max_edge", "min_angle", "discontinuity", "max_shadow_lines"};
  m.read_state = [](const std::string& out_dir) -> std::shared_ptr<const MethodState> {
    return std::make_shared<const PixmapState>(read_pixmap_state(out_dir));
  };
  m.own_field = "texels";
  m.files = {"lightmapped.obj", "lightmapped.mtl"};
  return m;
}

Result solve(const Scene& scene, const PixmapOptions& options, const SolveOptions& common,
             const SolveCallbacks& callbacks) {
  return solve(scene, find_method(kName), MethodOptions::checked(pixmap_option_table(), options), common, callbacks);
}

}  // namespace radmesh
