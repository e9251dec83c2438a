// The classic full-matrix radiosity solve.

#include "radmesh/errors.h"
#include "radmesh/solve.h"
#include "radiosity/transport/transport.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <functional>
#include <limits>
#include <sstream>

namespace radmesh {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

struct Counters {
  long long form_factors = 0, zero_pairs = 0, receiver_points = 0;
  RayCount rays;
};

// Makes the matrix reciprocal without changing its row sums. Each row was
// integrated at its own element's points, so a row sums to that element's
// whole view of the scene (1 in a closed one, exactly where nothing
// occludes: the point form factors cover each point's hemisphere once), but
// A_i F_ij and A_j F_ji differ by the receiver quadrature's error, and then
// the matrix creates or destroys light, most where a large receiver lies
// close to a small source (a ceiling just over a box). Each pair keeps the
// estimate made at
// the smaller element's points (that error grows with the receiver's size
// over the distance), both entries from it; then symmetric scales s (Sinkhorn
// balancing of the symmetric A_i F_ij) bring every row back to its own sum t:
// s_i sum_j F_ij s_j = t_i, F_ij <- s_i F_ij s_j. The result sends what it
// receives and keeps every element's total view, so a closed scene's balance
// closes to the solve's residual and the furnace stays exact.
void make_reciprocal(const ElementSet& el, std::vector<double>& F) {
  const long long n = static_cast<long long>(el.size());
  const size_t un = static_cast<size_t>(n);
  auto area = [&](long long i) { return el.triangle[static_cast<size_t>(i)].area; };
  std::vector<double> target(un, 0.0);
  tbb::parallel_for(tbb::blocked_range<long long>(0, n), [&](const tbb::blocked_range<long long>& r) {
    for (long long i = r.begin(); i != r.end(); ++i) {
      const double* fi = &F[static_cast<size_t>(i) * un];
      double t = 0.0;
      for (long long j = 0; j < n; ++j) t += fi[j];
      target[static_cast<size_t>(i)] = t;
    }
  });
  // Pair (i, j), i < j, is written by row i alone.
  tbb::parallel_for(tbb::blocked_range<long long>(0, n), [&](const tbb::blocked_range<long long>& r) {
    for (long long i = r.begin(); i != r.end(); ++i)
      for (long long j = i + 1; j < n; ++j) {
        double& fij = F[static_cast<size_t>(i) * un + static_cast<size_t>(j)];
        double& fji = F[static_cast<size_t>(j) * un + static_cast<size_t>(i)];
        if (fij == 0.0 && fji == 0.0) continue;
        if (area(i) <= area(j))
          fji = fij * area(i) / area(j);
        else
          fij = fji * area(j) / area(i);
      }
  });
  // Over-relaxed in log s: 1.5 x the half step of the plain symmetric
  // iteration converges in fewer rounds than the plain step, while a larger
  // factor oscillates.
  // Rows need not all be reachable: where elements see only each other's
  // sides (a bipartite exchange) the scales cannot give every row its sum, and
  // the rounds stop at 40 with the entries still reciprocal and the rows
  // close to their sums.
  constexpr double kOverRelaxation = 1.5;
  std::vector<double> s(un, 1.0), next(un, 1.0), misfit(un, 0.0);
  for (int round = 0; round < 40; ++round) {
    tbb::parallel_for(tbb::blocked_range<long long>(0, n), [&](const tbb::blocked_range<long long>& r) {
      for (long long i = r.begin(); i != r.end(); ++i) {
        const size_t u = static_cast<size_t>(i);
        const double* fi = &F[u * un];
        double sum = 0.0;
        for (size_t j = 0; j < un; ++j) sum += fi[j] * s[j];
        next[u] = s[u];
        misfit[u] = 0.0;
        // A row whose own points see nothing while others' points see its
        // element (a floor triangle reaching under a box standing on it,
        // its points all under the box) keeps its scale: the step would
        // take it to 0 and then to 0/0.
        if (sum > 0.0 && target[u] > 0.0) {
          next[u] = s[u] * std::pow(target[u] / (s[u] * sum), 0.5 * kOverRelaxation);
          misfit[u] = std::abs(s[u] * sum - target[u]);
        }
      }
    });
    s.swap(next);
    if (*std::max_element(misfit.begin(), misfit.end()) <= 1e-10) break;
  }
  tbb::parallel_for(tbb::blocked_range<long long>(0, n), [&](const tbb::blocked_range<long long>& r) {
    for (long long i = r.begin(); i != r.end(); ++i) {
      double* fi = &F[static_cast<size_t>(i) * un];
      for (size_t j = 0; j < un; ++j) fi[j] *= s[static_cast<size_t>(i)] * s[j];
    }
  });
}

// The matrix, in the calling arena.
std::vector<double> compute_matrix(const Scene& scene, const ElementSet& el, const SolveOptions& options,
                                   SolveStats& st, const ProgressFn& progress) {
  const long long n = static_cast<long long>(el.size());
  const auto t0 = Clock::now();
  const VisibilityEstimator visibility(scene, options.rays);
  st.convex_enclosure = visibility.convex_enclosure();
  // Nothing lies inside anything in one convex enclosure.
  if (!st.convex_enclosure)
    st.warnings = enclosed_emitter_warnings(scene, el, emitting_inside_objects(scene, el, visibility.rays()));

  std::vector<double> F(static_cast<size_t>(n * n), 0.0);
  tbb::combinable<Counters> counters;

  // Runs body(i, counters) for every row, in chunks of about equal cost, and
  // reports progress from this thread between chunks.
  auto rows = [&](const std::string& phase, double phase_start, double phase_share,
                  const std::function<double(long long)>& cost, const std::function<void(long long, Counters&)>& body) {
    double total = 0.0;
    for (long long i = 0; i < n; ++i) total += cost(i);
    const int chunks = 50;
    long long row = 0;
    double done = 0.0;
    for (int c = 1; c <= chunks && row < n; ++c) {
      long long end = row;
      const double goal = total * c / chunks;
      while (end < n && (done < goal || c == chunks)) done += cost(end++);
      tbb::parallel_for(tbb::blocked_range<long long>(row, end, 1), [&](const tbb::blocked_range<long long>& r) {
        Counters& cnt = counters.local();
        for (long long i = r.begin(); i != r.end(); ++i) body(i, cnt);
      });
      row = end;
      if (progress) progress(phase, phase_start + phase_share * done / std::max(total, 1.0));
    }
  };

  // Pass 1, per unordered pair: zero when the elements face away or are
  // coplanar; otherwise the visible fraction (VisibilityEstimator). Stored in
  // both F_ij and F_ji.
  rows("form factors", 0.0, 0.5, [&](long long i) { return static_cast<double>(n - i); },
       [&](long long i, Counters& c) {
    const size_t u = static_cast<size_t>(i);
    for (long long j = i + 1; j < n; ++j) {
      const size_t w = static_cast<size_t>(j);
      if (el.zero_area[u] || el.zero_area[w] || facing_away(el.triangle[u], el.triangle[w])) {
        ++c.zero_pairs;
        continue;
      }
      const double visible = visibility.visible_fraction(el.triangle[u], el.patch[u], static_cast<uint64_t>(i),
                                                         el.triangle[w], el.patch[w], static_cast<uint64_t>(j), c.rays);
      F[static_cast<size_t>(i * n + j)] = visible;
      F[static_cast<size_t>(j * n + i)] = visible;
    }
  });

  // Pass 2, per row: the unoccluded form factors at the receiver's points,
  // times the visible fraction. All sources of a row share the points.
  std::vector<std::vector<int>> facing(scene.patches.size());
  for (size_t p = 0; p < scene.patches.size(); ++p)
    for (size_t q = 0; q < scene.patches.size(); ++q)
      if (p != q && visibility.facing(static_cast<int>(p), static_cast<int>(q)))
        facing[p].push_back(static_cast<int>(q));
  rows("form factors", 0.5, 0.5, [&](long long) { return 1.0; }, [&](long long i, Counters& c) {
    const int pi = el.patch[static_cast<size_t>(i)];
    const ReceiverPoints pts = receiver_points(
        el.triangle[static_cast<size_t>(i)],
        [&](const Vec3& x) {
          double d = std::numeric_limits<double>::infinity();
          for (int q : facing[static_cast<size_t>(pi)]) d = std::min(d, visibility.distance_to_patch(q, x));
          return d;
        },
        options.quadrature);
    c.receiver_points += static_cast<long long>(pts.x.size());
    thread_local std::vector<const Triangle*> sources;
    thread_local std::vector<long long> column;
    thread_local std::vector<double> ff;
    sources.clear();
    column.clear();
    double* fi = &F[static_cast<size_t>(i * n)];
    for (long long j = 0; j < n; ++j)
      if (fi[j] != 0.0) {
        sources.push_back(&el.triangle[static_cast<size_t>(j)]);
        column.push_back(j);
      }
    ff.resize(sources.size());
    form_factors(pts, sources.data(), sources.size(), ff.data());
    for (size_t k = 0; k < column.size(); ++k) fi[column[k]] *= ff[k];
    c.form_factors += static_cast<long long>(column.size());
  });
  make_reciprocal(el, F);
  counters.combine_each([&](const Counters& c) {
    st.form_factors += c.form_factors;
    st.form_factors_skipped += 2 * c.zero_pairs;
    st.rays_cast += c.rays.cast;
    st.rays_skipped += c.rays.skipped;
    st.pairs_unoccludable += c.rays.unoccludable;
    st.receiver_points += c.receiver_points;
  });
  st.seconds_form_factors = seconds_since(t0);
  report_visibility_skips(st, "element");
  if (st.form_factors_skipped > 0)
    st.skips.push_back("form factors: " + std::to_string(st.form_factors_skipped) +
                       " entries are zero because the elements face away or are coplanar");
  return F;
}

// Gauss-Seidel per distinct channel on a computed matrix, in the calling arena.
Solution solve_with_matrix(const Scene& scene, const Mesh& mesh, const ElementSet& el, const std::vector<double>& F,
                           const SolveStats& matrix_stats, const SolveOptions& options) {
  const long long n = static_cast<long long>(el.size());
  Solution sol;
  SolveStats& st = sol.stats;
  st = matrix_stats;
  st.elements = n;
  const std::vector<Rgb>& rho = el.reflectance;
  const std::vector<Rgb>& emit = el.emission;

  const auto t1 = Clock::now();
  int source_of[3] = {0, 1, 2};
  for (int c = 1; c < 3; ++c)
    for (int d = 0; d < c; ++d) {
      if (source_of[d] != d) continue;
      bool same = true;
      for (long long i = 0; i < n && same; ++i)
        same = rho[static_cast<size_t>(i)][c] == rho[static_cast<size_t>(i)][d] &&
               emit[static_cast<size_t>(i)][c] == emit[static_cast<size_t>(i)][d];
      if (same) {
        source_of[c] = d;
        break;
      }
    }
  std::vector<int> solve_channels;
  for (int c = 0; c < 3; ++c)
    if (source_of[c] == c) solve_channels.push_back(c);
  st.channels_solved = static_cast<int>(solve_channels.size());
  if (st.channels_solved < 3)
    st.skips.push_back("solve: " + std::to_string(3 - st.channels_solved) +
                       " colour channel(s) identical to another were solved once");
  long long black = 0;
  for (long long i = 0; i < n; ++i)
    if (rho[static_cast<size_t>(i)] == Rgb(0.0)) ++black;
  if (black > 0)
    st.skips.push_back("solve: " + std::to_string(black) +
                       " elements with reflectance 0 take B = E without iterating");

  // Row sums, and per channel the norm of rho F (the stopping rule's bound).
  std::vector<double> row_sum(static_cast<size_t>(n), 0.0);
  tbb::parallel_for(tbb::blocked_range<long long>(0, n), [&](const tbb::blocked_range<long long>& r) {
    for (long long i = r.begin(); i != r.end(); ++i) {
      const double* fi = &F[static_cast<size_t>(i * n)];
      double s = 0.0;
      for (long long j = 0; j < n; ++j) s += fi[j];
      row_sum[static_cast<size_t>(i)] = s;
    }
  });
  Rgb contraction(0.0);
  for (long long i = 0; i < n; ++i)
    contraction = glm::max(contraction, rho[static_cast<size_t>(i)] * row_sum[static_cast<size_t>(i)]);

  std::vector<std::vector<double>> B(3, std::vector<double>(static_cast<size_t>(n)));
  std::vector<int> extrapolations(solve_channels.size(), 0);
  tbb::parallel_for(size_t(0), solve_channels.size(), [&](size_t k) {
    const int c = solve_channels[k];
    std::vector<double>& b = B[static_cast<size_t>(c)];
    for (long long i = 0; i < n; ++i) b[static_cast<size_t>(i)] = emit[static_cast<size_t>(i)][c];
    int it = 0;
    double max_b = 0.0;
    SweepMonitor monitor(options.tolerance, contraction[c]);
    std::vector<double> before;
    for (; it < options.max_iterations; ++it) {
      before = b;
      double change = 0.0;
      max_b = 0.0;
      for (long long i = 0; i < n; ++i) {
        const double r = rho[static_cast<size_t>(i)][c];
        double value = emit[static_cast<size_t>(i)][c];
        if (r > 0.0) {
          const double* fi = &F[static_cast<size_t>(i * n)];
          double h = 0.0;
          for (long long j = 0; j < n; ++j) h += fi[j] * b[static_cast<size_t>(j)];
          value += r * h;
        }
        change = std::max(change, std::abs(value - b[static_cast<size_t>(i)]));
        b[static_cast<size_t>(i)] = value;
        max_b = std::max(max_b, std::abs(value));
      }
      const SweepMonitor::Action action = monitor.after_sweep(change, max_b);
      if (action == SweepMonitor::Action::stop) {
        ++it;
        break;
      }
      if (action == SweepMonitor::Action::extrapolate) {
        const double k = monitor.extrapolation_factor();
        for (size_t i = 0; i < b.size(); ++i) b[i] += k * (b[i] - before[i]);
      }
    }
    st.iterations[static_cast<size_t>(c)] = it;
    extrapolations[k] = monitor.extrapolations();
  });
  for (const int e : extrapolations) st.extrapolations += e;
  for (int c = 0; c < 3; ++c)
    if (source_of[c] != c) {
      B[static_cast<size_t>(c)] = B[static_cast<size_t>(source_of[c])];
      st.iterations[static_cast<size_t>(c)] = st.iterations[static_cast<size_t>(source_of[c])];
    }
  for (int c : solve_channels)
    if (st.iterations[static_cast<size_t>(c)] >= options.max_iterations)
      throw NumericalError(scene.source + ": Gauss-Seidel did not converge to tolerance " +
                           std::to_string(options.tolerance) + " in " +
                           std::to_string(options.max_iterations) + " iterations");

  // Residual and energy balance from H = F B (rows in parallel, each row summed in order).
  std::vector<Rgb> H(static_cast<size_t>(n), Rgb(0.0));
  tbb::parallel_for(tbb::blocked_range<long long>(0, n), [&](const tbb::blocked_range<long long>& r) {
    for (long long i = r.begin(); i != r.end(); ++i) {
      const double* fi = &F[static_cast<size_t>(i * n)];
      Rgb h(0.0);
      for (long long j = 0; j < n; ++j)
        for (int c = 0; c < 3; ++c) h[c] += fi[j] * B[static_cast<size_t>(c)][static_cast<size_t>(j)];
      H[static_cast<size_t>(i)] = h;
    }
  });
  sol.element.resize(static_cast<size_t>(n));
  BalanceAccumulator balance;
  for (long long i = 0; i < n; ++i) {
    const size_t u = static_cast<size_t>(i);
    for (int c = 0; c < 3; ++c) sol.element[u][c] = B[static_cast<size_t>(c)][u];
    balance.add(el.triangle[u].area, rho[u], emit[u], sol.element[u], H[u], row_sum[u], row_sum[u]);
  }
  balance.finish(st);
  for (const Rgb& b : sol.element)
    if (!std::isfinite(b.x) || !std::isfinite(b.y) || !std::isfinite(b.z))
      throw NumericalError(scene.source + ": the solve produced a non-finite radiosity");
  st.seconds_solve = seconds_since(t1);

  sol.nodal = compute_nodal(scene, mesh, sol.element, options.crease_angle, nodal_method(options.field));
  return sol;
}

void check_matrix_memory(const Scene& scene, long long n, const SolveOptions& options) {
  const double limit = memory_limit_bytes(options);
  if (matrix_bytes(n) > limit) {
    std::ostringstream m;
    m.precision(3);
    m << scene.source << ": the full matrix of " << n << " elements needs "
      << matrix_bytes(n) / (1024.0 * 1024.0 * 1024.0) << " GiB, more than the "
      << limit / (1024.0 * 1024.0 * 1024.0)
      << " GiB allowed; use a larger max_edge (the element count falls with its square) "
         "or raise max_memory";
    throw NumericalError(m.str(), {"max_edge", "max_memory"});
  }
}

}  // namespace

double matrix_bytes(long long n) { return static_cast<double>(n) * static_cast<double>(n) * 8.0; }

std::vector<double> form_factor_matrix(const Scene& scene, const Mesh& mesh, const SolveOptions& options,
                                       SolveStats& st, const ProgressFn& progress) {
  check_solve_options(options);
  const ElementSet el = make_elements(scene, mesh);
  std::vector<double> F;
  run_in_arena(options.threads, [&] { F = compute_matrix(scene, el, options, st, progress); });
  return F;
}

struct MatrixSolver::Impl {
  const Scene& scene;
  Mesh mesh;
  SolveOptions options;
  ElementSet elements;
  std::vector<double> F;
  SolveStats stats;  // of the matrix: counts, rays, skips
};

MatrixSolver::MatrixSolver(const Scene& scene, const Mesh& mesh, const SolveOptions& options,
                           const ProgressFn& progress)
    : impl_(std::make_unique<Impl>(Impl{scene, mesh, options, make_elements(scene, mesh), {}, {}})) {
  check_solve_options(options);
  check_matrix_memory(scene, mesh.triangle_count(), options);
  Impl& m = *impl_;
  run_in_arena(options.threads, [&] { m.F = compute_matrix(scene, m.elements, options, m.stats, progress); });
}

MatrixSolver::~MatrixSolver() = default;

Solution MatrixSolver::solve() const {
  const Impl& m = *impl_;
  Solution sol;
  run_in_arena(m.options.threads,
               [&] { sol = solve_with_matrix(m.scene, m.mesh, m.elements, m.F, m.stats, m.options); });
  return sol;
}

Solution MatrixSolver::solve(const std::vector<Material>& materials) const {
  const Impl& m = *impl_;
  if (materials.size() != m.scene.materials.size())
    throw InputError("MatrixSolver::solve: " + std::to_string(materials.size()) + " materials given, the scene has " +
                     std::to_string(m.scene.materials.size()));
  for (const Material& mat : materials)
    for (int c = 0; c < 3; ++c)
      if (!(mat.reflectance[c] >= 0.0 && mat.reflectance[c] < 1.0) || !(mat.emission[c] >= 0.0) ||
          !std::isfinite(mat.emission[c]))
        throw InputError("MatrixSolver::solve: material '" + mat.name + "' has reflectance " +
                         format_number(mat.reflectance[c]) + " or emission " + format_number(mat.emission[c]) +
                         " out of range (reflectance in [0, 1), emission finite and >= 0)");
  ElementSet relit = m.elements;
  for (size_t i = 0; i < relit.size(); ++i) {
    const Material& mat =
        materials[static_cast<size_t>(m.scene.patches[static_cast<size_t>(relit.patch[i])].material)];
    relit.reflectance[i] = mat.reflectance;
    relit.emission[i] = mat.emission;
  }
  Solution sol;
  run_in_arena(m.options.threads,
               [&] { sol = solve_with_matrix(m.scene, m.mesh, relit, m.F, m.stats, m.options); });
  return sol;
}

const std::vector<double>& MatrixSolver::form_factors() const { return impl_->F; }

Solution solve_matrix(const Scene& scene, const Mesh& mesh, const SolveOptions& options,
                      const ProgressFn& progress) {
  const MatrixSolver solver(scene, mesh, options, progress);
  Solution sol = solver.solve();
  if (progress) progress("solve", 1.0);
  return sol;
}

}  // namespace radmesh
