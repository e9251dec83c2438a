// Pixmap radiosity (progressive refinement through hemicubes onto texel
// grids) as an entry of the method table.

#include "radmesh/errors.h"
#include "radmesh/method.h"
#include "radiosity/transport/occlusion.h"
#include "radmesh/pixmap.h"

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
  st.power_absorbed = state.power_absorbed;
  // What emitting parts inside closed objects emit goes into the objects:
  // emitted and escaped, as the other methods count it.
  st.power_escaped = state.power_escaped + solver->power_enclosed();
  st.power_emitted = solver->power_emitted() + solver->power_enclosed();
  st.warnings = solver->warnings();
  r.pixmaps = std::move(out);
  return r;
}

}  // namespace

Method make_pixmap_method() {
  using K = OptionSpec::Kind;
  Method m;
  m.name = "pixmap";
  m.help = "progressive refinement onto texel grids (pixmaps) with hemicube item-buffer form factors; "
           "saves lightmaps and a state that --resume continues";
  const PixmapOptions d;  // the defaults, in one place
  m.options = {
      {"texel_size", K::real, "scene units", "texel edge of the pixmaps (0: scene diagonal / 80)", d.texel_size, 0.0,
       1e300, {}},
      {"max_texels", K::integer, "", "most texels one pixmap may have (its texels grow to fit)",
       static_cast<double>(d.max_texels), 1, 1 << 26, {}},
      {"hemicube_res", K::integer, "", "hemicube pixels along the top face's side (even)",
       static_cast<double>(d.hemicube_res), 2, 16384, {}},
      {"block", K::integer, "", "a shooter is a block of block x block texels", static_cast<double>(d.block), 1, 256, {}},
      {"unshot", K::real, "", "stop when the unshot power is at most this fraction of the emitted power", d.unshot, 0.0,
       0.999, {}},
      {"shots", K::integer, "", "stop after this many shots in all, those before a resume included (0: no limit)",
       static_cast<double>(d.shots), 0, 1e15, {}},
      {"snapshot_every", K::integer, "", "write a snapshot of the field every this many shots (0: none)", 0, 0, 1e15,
       {}},
  };
  m.quick = {{"hemicube_res", "64"}};
  m.resumable = true;
  // Measured at hemicube 64 (the quick options), the default texel and block
  // 4: a rho 0.9 furnace's worst texel 10.2% off (31% before the near
  // field), at rho 0.5 B - E within 3.1% (the bench); their area mean
  // exact; Howell's plates
  // +0.14%; rotated scenes 1.4%; the residual (unshot / radiosity) 4.4e-4
  // on the Cornell box at --unshot 1e-3.
  m.accuracy = {0.12, 0.02, 1e-3, false, false};
  m.texel_field = true;
  // The geometry is never cut finer for the solve: the initial mesh is the
  // coarsest one with the contact lines, which the solver makes itself
  // whatever the meshing flags (the display mesh follows the texels).
  m.meshing = pixmap_meshing_options;
  m.solve = [](const Scene& scene, const Mesh&, const SolveOptions& so, const MethodOptions& opts,
               const SolveCallbacks& cb) {
    PixmapOptions po;
    po.texel_size = opts.number("texel_size");
    po.max_texels = static_cast<long long>(opts.number("max_texels"));
    po.hemicube_res = static_cast<int>(opts.number("hemicube_res"));
    po.block = static_cast<int>(opts.number("block"));
    po.unshot = opts.number("unshot");
    po.shots = static_cast<long long>(opts.number("shots"));
    auto solver = std::make_shared<const PixmapSolver>(scene, po, so);
    const bool convex = Occlusion(scene).convex_enclosure();
    PixmapState start;
    if (cb.resume) {
      check_resumable(*cb.resume, scene, solver->layout(), po, cb.resume->source);
      start = *cb.resume;
    } else {
      start = solver->initial_state();
    }
    PixmapCallbacks pc;
    pc.progress = cb.progress;
    pc.cancelled = cb.cancelled;
    pc.snapshot_every = static_cast<long long>(opts.number("snapshot_every"));
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
                  Counter{"ambient", {run.ambient.x, run.ambient.y, run.ambient.z}, "", true, false},
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
  };
  return m;
}

}  // namespace radmesh
