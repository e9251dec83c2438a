// The solver: its construction (the layout on the coarse mesh, the
// polygons the hemicube renders, the emitted power, the display mesh) and
// the run loop of progressive refinement, which shoots from the shooter
// with the most unshot power until the unshot fraction or the shot count
// is reached. Rows are cached while they fit in the memory the texels
// leave, since a shooter that receives light shoots again; the loop is
// serial, each row's hemicube and receivers parallel inside (rows.cpp).

#include "radiosity/pixmap/solver.h"

#include "core/power_of_two.h"
#include "radmesh/errors.h"
#include "radiosity/pixmap/layout.h"
#include "radiosity/transport/transport.h"

#include <chrono>
#include <cmath>
#include <sstream>

namespace radmesh {

using internal::Row;
using internal::RowEntry;

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Shooter s's unshot power: the sum over its texels and the channels of
// unshot radiosity times area.
double shooter_power(const PixmapLayout& L, const PixmapState& st, size_t s) {
  const Shooter& sh = L.shooters[s];
  const Pixmap& pm = L.pixmaps[sh.pixmap];
  double p = 0.0;
  for (int t : sh.texels)
    for (int c = 0; c < 3; ++c) p += static_cast<double>(st.unshot[sh.pixmap][t * 3 + c]) * pm.area[t];
  return p;
}

// Per channel: the largest unshot radiosity over the largest radiosity.
std::array<double, 3> residual_of(const PixmapLayout& L, const PixmapState& st) {
  std::array<double, 3> residual{0, 0, 0};
  for (int c = 0; c < 3; ++c) {
    double bmax = 0.0, umax = 0.0;
    for (size_t k = 0; k < L.pixmaps.size(); ++k)
      for (size_t i = static_cast<size_t>(c); i < st.radiosity[k].size(); i += 3) {
        bmax = std::max(bmax, static_cast<double>(st.radiosity[k][i]));
        umax = std::max(umax, static_cast<double>(st.unshot[k][i]));
      }
    residual[c] = bmax > 0.0 ? umax / bmax : 0.0;
  }
  return residual;
}

}  // namespace

PixmapSolver::PixmapSolver(const Scene& input, const PixmapOptions& options, const SolveOptions& solve)
    : impl_(std::make_unique<Impl>(input, options, solve)) {
  Impl& m = *impl_;
  const Scene& scene = m.scene;
  internal::check_options(options);
  m.coarse = internal::outline_triangulation(scene);
  const double limit = memory_limit_bytes(solve);
  // The hemicube's buffers come first: they grow with the square of its
  // resolution (16 GB at the largest), whatever the scene.
  const double cube_bytes = Hemicube::bytes(options.hemicube_res);
  if (cube_bytes > limit) {
    std::ostringstream m;
    m.precision(3);
    m << scene.source << ": a hemicube of " << options.hemicube_res << " pixels needs " << cube_bytes / (1u << 30)
      << " GiB, more than the " << limit / (1u << 30) << " GiB allowed; use a smaller hemicube_res or raise max_memory";
    throw NumericalError(m.str(), {"hemicube_res", "max_memory"});
  }
  const double memory = limit - cube_bytes;  // what the texels and the rows may take
  m.vis = std::make_unique<Visibility>(scene);
  m.layout = internal::layout_of(scene, m.coarse, options, limit, m.vis.get());
  if (m.layout.texels >= (1LL << 32)) throw NumericalError(scene.source + ": more than 2^32 texels; use a larger texel_size", {"texel_size"});
  // The hemicube renders whole polygons (their coarsest triangulation): the
  // contact lines would only add triangles.
  const Mesh polygons = triangulate_patches(scene);
  for (int t = 0; t < polygons.triangle_count(); ++t) {
    const auto& tri = polygons.triangles[t];
    const int p = polygons.patch[t];
    m.polygons.push_back({polygons.positions[tri[0]], polygons.positions[tri[1]], polygons.positions[tri[2]],
                          scene.patches[p].normal, p});
  }
  double top = 0.0;
  for (const Material& mat : scene.materials) top = std::max(top, max3(mat.emission));
  if (top > 0.0 && (top > 0x1p60 || top < 0x1p-60)) m.unit = internal::power_of_two_above(top);
  for (const Pixmap& pm : m.layout.pixmaps) {
    m.rho.push_back(scene.materials[pm.material].reflectance);
    m.emission.push_back(scene.materials[pm.material].emission / m.unit);
  }
  for (size_t k = 0; k < m.layout.pixmaps.size(); ++k) {
    const Pixmap& pm = m.layout.pixmaps[k];
    for (long long i = 0; i < pm.texels(); ++i)
      if (pm.owner[i] == i) m.power_emitted += m.emission[k] * pm.area[i];
  }
  {
    const ElementSet el = make_elements(scene, m.coarse);
    for (size_t t = 0; t < el.size(); ++t)
      if (m.layout.enclosed[t]) m.power_enclosed += el.emission[t] * el.triangle[t].area;
    m.warnings = enclosed_emitter_warnings(scene, el, m.layout.enclosed);
  }
  m.shooter_of.assign(static_cast<size_t>(m.layout.texels), -1);
  for (size_t s = 0; s < m.layout.shooters.size(); ++s)
    for (int t : m.layout.shooters[s].texels) m.shooter_of[m.global(m.layout.shooters[s].pixmap, t)] = static_cast<int>(s);
  m.row_budget = std::max(0.0, memory - internal::kBytesPerTexel * static_cast<double>(m.layout.texels));
  m.memory_limit = limit;
  m.build_display();
}

PixmapSolver::~PixmapSolver() = default;

const Scene& PixmapSolver::scene() const { return impl_->scene; }
const PixmapLayout& PixmapSolver::layout() const { return impl_->layout; }

Rgb PixmapSolver::power_emitted() const { return impl_->power_emitted * impl_->unit; }
double PixmapSolver::unit() const { return impl_->unit; }
Rgb PixmapSolver::power_enclosed() const { return impl_->power_enclosed; }
const std::vector<std::string>& PixmapSolver::warnings() const { return impl_->warnings; }

// The run loop's state between shots: each shooter's unshot power, the
// cached rows, and the hemicube the rows are rendered into.
struct PixmapSolver::Impl::Shots {
  const Impl& m;
  const PixmapLayout& L;
  PixmapRun& r;
  PixmapState& st;
  const size_t ns;                 // shooters
  std::vector<double> power;       // per shooter: sum of the channels' unshot power
  std::vector<Row> cache;          // per shooter: its row, where cached
  std::vector<char> cached;
  double cache_bytes = 0.0;
  std::vector<long long> stamp;    // per shooter: the last shot that reached it
  std::vector<int> touched;        // the shooters the current shot reached
  std::vector<Rgb> phis;           // per source texel of the shooter: its unshot power
  Hemicube cube;

  Shots(const Impl& m, PixmapRun& r)
      : m(m), L(m.layout), r(r), st(r.state), ns(L.shooters.size()), power(ns, 0.0), cache(ns), cached(ns, 0),
        stamp(ns, -1), cube(m.options.hemicube_res) {
    for (size_t s = 0; s < ns; ++s) power[s] = shooter_power(L, st, s);
  }
  size_t pick(double& unshot) const;
  const Row* row_of(size_t best, Row& fresh);
  void shoot(size_t best, const Row& row);
};

// The shooter with the most unshot power (ns when none has any), and the
// unshot power in all.
size_t PixmapSolver::Impl::Shots::pick(double& unshot) const {
  size_t best = ns;
  for (size_t s = 0; s < ns; ++s) {
    unshot += power[s];
    if (power[s] > 0.0 && (best == ns || power[s] > power[best])) best = s;
  }
  return best;
}

// The row of the shooter: cached, or rendered now (into `fresh` when it
// does not fit in the cache).
const Row* PixmapSolver::Impl::Shots::row_of(size_t best, Row& fresh) {
  const Row* row = &cache[best];
  if (!cached[best]) {
    fresh = m.compute_row(static_cast<int>(best), cube, r.pixels_spread);
    ++r.rows_computed;
    const double bytes = fresh.bytes();
    if (cache_bytes + bytes <= m.row_budget) {
      cache[best] = std::move(fresh);
      cached[best] = 1;
      cache_bytes += bytes;
      ++r.rows_cached;
    } else {
      row = &fresh;
    }
  }
  return row;
}

// Shoot: the block's unshot power leaves; each texel it reaches gets
// rho times the power arriving / its area: along the far entries the
// source texels' power times their far_scale, along the near ones
// each source texel's own. The shooters reached get their power anew.
void PixmapSolver::Impl::Shots::shoot(size_t best, const Row& row) {
  const Shooter& sh = L.shooters[best];
  const Pixmap& spm = L.pixmaps[sh.pixmap];
  const size_t nsrc = sh.texels.size();
  phis.assign(nsrc, Rgb(0.0));
  Rgb phi(0.0), phi_far(0.0);
  for (size_t q = 0; q < nsrc; ++q) {
    const int t = sh.texels[q];
    for (int c = 0; c < 3; ++c) {
      float& u = st.unshot[sh.pixmap][t * 3 + c];
      phis[q][c] = static_cast<double>(u) * spm.area[t];
      u = 0.0f;
    }
    phi += phis[q];
    phi_far += phis[q] * static_cast<double>(row.far_scale[q]);
  }
  power[best] = 0.0;
  Rgb received(0.0);
  int k = -1;
  long long k_end = 0;
  ++st.shots;
  ++r.shots_this_run;
  touched.clear();
  // Always inlined: it runs for every entry of the row, and a call per entry
  // costs about a third of the shots' time (GCC does not inline it alone).
  auto deposit = [&](uint32_t texel, const Rgb& arriving) __attribute__((always_inline)) {
    if (k < 0 || texel < L.pixmaps[k].first || texel >= k_end) {
      k = m.pixmap_of_global(texel);
      k_end = L.pixmaps[k].first + L.pixmaps[k].texels();
    }
    const Pixmap& pm = L.pixmaps[k];
    const long long i = texel - pm.first;
    received += arriving;
    for (int c = 0; c < 3; ++c) {
      const double dh = arriving[c] / pm.area[i];
      const double db = m.rho[k][c] * dh;
      float& b = st.radiosity[k][i * 3 + c];
      float& u = st.unshot[k][i * 3 + c];
      b = static_cast<float>(static_cast<double>(b) + db);
      u = static_cast<float>(static_cast<double>(u) + db);
      st.power_absorbed[c] += (1.0 - m.rho[k][c]) * arriving[c];
    }
    const int s = m.shooter_of[texel];
    if (s >= 0 && stamp[s] != st.shots) {
      stamp[s] = st.shots;
      touched.push_back(s);
    }
  };
  for (const RowEntry& e : row.far) deposit(e.texel, phi_far * static_cast<double>(e.f));
  for (size_t n = 0; n < row.near.size(); ++n) {
    Rgb arriving(0.0);
    for (size_t q = 0; q < nsrc; ++q) arriving += phis[q] * static_cast<double>(row.near_f[n * nsrc + q]);
    deposit(row.near[n], arriving);
  }
  for (int c = 0; c < 3; ++c) st.power_escaped[c] += std::max(0.0, phi[c] - received[c]);
  for (int s : touched) power[s] = shooter_power(L, st, static_cast<size_t>(s));
}

PixmapRun PixmapSolver::run(PixmapState start, const PixmapCallbacks& cb) const {
  const Impl& m = *impl_;
  PixmapRun r;
  r.state = std::move(start);
  PixmapState& st = r.state;
  r.power_emitted = m.power_emitted;
  Impl::Shots shots(m, r);
  const double emitted = r.power_emitted.x + r.power_emitted.y + r.power_emitted.z;
  const double target = m.options.unshot * emitted;
  const double log_goal = target > 0.0 && emitted > 0.0 ? std::log(target / emitted) : 0.0;

  run_in_arena(m.solve.threads, [&] {
    while (true) {
      double unshot = 0.0;
      const size_t best = shots.pick(unshot);
      r.unshot_fraction = emitted > 0.0 ? unshot / emitted : 0.0;
      if (cb.progress && emitted > 0.0) {
        double f = log_goal < 0.0 && unshot > 0.0 ? std::log(unshot / emitted) / log_goal : 1.0;
        if (m.options.shots > 0) f = std::max(f, static_cast<double>(st.shots) / static_cast<double>(m.options.shots));
        cb.progress("shots", std::clamp(f, 0.0, 1.0));
      }
      if (best == shots.ns || unshot <= target) break;
      if (m.options.shots > 0 && st.shots >= m.options.shots) break;
      if (cb.cancelled && cb.cancelled()) {
        r.interrupted = true;
        break;
      }
      const auto t0 = Clock::now();
      Row fresh;
      const Row* row = shots.row_of(best, fresh);
      r.seconds_hemicubes += seconds_since(t0);
      const auto t1 = Clock::now();
      shots.shoot(best, *row);
      r.seconds_shots += seconds_since(t1);
      if (cb.on_snapshot && cb.snapshot_every > 0 && st.shots % cb.snapshot_every == 0) cb.on_snapshot(st);
    }
  });
  r.ambient = ambient(st);
  r.residual = residual_of(m.layout, st);
  return r;
}

}  // namespace radmesh
