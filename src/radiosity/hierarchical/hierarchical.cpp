// Hierarchical radiosity's public face: the mode names, the options'
// checks, HierarchicalSolver (which runs each call in its own TBB arena) and
// the one-off solve_hierarchical. The solver itself is
// internal::Hierarchical (solver.h), its phases in the files beside this one.

#include "radiosity/hierarchical/solver.h"

#include <memory>

namespace radmesh {

using internal::Hierarchical;
TVertexMode parse_tvertex_mode(const std::string& name) {
  if (name == "anchor") return TVertexMode::anchor;
  if (name == "free") return TVertexMode::free;
  if (name == "split") return TVertexMode::split;
  throw InputError("tvertex '" + name + "': expected anchor, free or split", {"tvertex"});
}

ClusterMode parse_cluster_mode(const std::string& name) {
  if (name == "off") return ClusterMode::off;
  if (name == "volume") return ClusterMode::volume;
  if (name == "shape") return ClusterMode::shape;
  throw InputError("clusters '" + name + "': expected shape, volume or off", {"clusters"});
}

const char* to_string(ClusterMode mode) {
  switch (mode) {
    case ClusterMode::off: return "off";
    case ClusterMode::volume: return "volume";
    case ClusterMode::shape: return "shape";
  }
  return "?";
}

const char* to_string(TVertexMode mode) {
  switch (mode) {
    case TVertexMode::anchor: return "anchor";
    case TVertexMode::free: return "free";
    case TVertexMode::split: return "split";
  }
  return "?";
}

namespace {

void check_hierarchical_options(const Scene& scene, const SolveOptions& options, const HierarchicalOptions& hopt) {
  check_solve_options(options);
  hierarchical_option_table().check(hopt);
  if (hopt.max_rounds < 0 || !(hopt.baum_absolute >= 0.0))
    throw InputError("hierarchical options out of range: max_rounds " + std::to_string(hopt.max_rounds) +
                         ", baum_absolute " + format_number(hopt.baum_absolute) + " (both must be >= 0)",
                     {"max_rounds", "baum_absolute"});
  const double diag2 = scene.diagonal() * scene.diagonal();
  if (hopt.min_area > 0.0 && hopt.min_area < 1e-8 * diag2)
    throw InputError("min_area " + format_number(hopt.min_area) + " is below 1e-8 of the scene diagonal squared (" +
                         format_number(diag2) + "): refinement to it would not end in time or memory",
                     {"min_area"});
}

}  // namespace

struct HierarchicalSolver::Impl {
  Impl(const Scene& scene, const Mesh& initial, const SolveOptions& o, const HierarchicalOptions& h,
       const ProgressFn& progress)
      : options(o), out{ElementTree(initial), {}, {}, {}, {}, {}, {}, {}, {}} {
    run_in_arena(options.threads, [&] {
      solver = std::make_unique<Hierarchical>(scene, options, h, out, progress);
      solver->start();
    });
  }
  SolveOptions options;
  HierarchicalSolution out;
  std::unique_ptr<Hierarchical> solver;
  bool links_current = false;  // out.links filled since the last round
};

HierarchicalSolver::HierarchicalSolver(const Scene& scene, const Mesh& initial, const SolveOptions& options,
                                       const HierarchicalOptions& hopt, const ProgressFn& progress) {
  check_hierarchical_options(scene, options, hopt);
  impl_ = std::make_unique<Impl>(scene, initial, options, hopt, progress);
}

HierarchicalSolver::~HierarchicalSolver() = default;

bool HierarchicalSolver::refine() {
  bool changed = false;
  run_in_arena(impl_->options.threads, [&] { changed = impl_->solver->step(); });
  if (changed) impl_->links_current = false;
  return changed;
}

const HierarchicalSolution& HierarchicalSolver::solution() const {
  if (!impl_->links_current) {
    impl_->solver->finish();
    impl_->links_current = true;
  }
  return impl_->out;
}

HierarchicalSolution HierarchicalSolver::take_solution() {
  solution();
  return std::move(impl_->out);
}

int HierarchicalSolver::rounds() const { return impl_->out.stats.rounds; }

HierarchicalSolution solve_hierarchical(const Scene& scene, const Mesh& initial, const SolveOptions& options,
                                        const HierarchicalOptions& hopt,
                                        const std::function<void(const HierarchicalSolution&, int)>& on_round,
                                        const ProgressFn& progress) {
  HierarchicalSolver solver(scene, initial, options, hopt, progress);
  // Each round's solution as it stands, without copying the links every
  // round: they are published once, at the end.
  if (on_round) on_round(solver.impl_->out, 0);
  while (solver.refine())
    if (on_round) on_round(solver.impl_->out, solver.rounds() - 1);
  return solver.take_solution();
}

}  // namespace radmesh
