// The solve: Gauss-Seidel sweeps over the leaves' terms in root order
// (results do not depend on the thread count), what the groups gather,
// the pull of radiosity up the tree, and Aitken extrapolation when a sweep
// converges slowly (reflectance near 1).

#include "radiosity/hierarchical/solver.h"

namespace radmesh::internal {

// Gauss-Seidel sweeps in tree order: leaves gather (see leaf_terms),
// inner nodes take the area-weighted mean of their children (pull), until
// the largest change is below the tolerance times the largest radiosity.
void Hierarchical::solve() {
  const ElementTree& tree = out_.tree;
  const size_t n = tree.nodes().size();
  leaf_terms();
  check_memory();
  link_values();
  report("solve", 0.0);
  // The norm of rho F over the leaves, for the stopping rule.
  double contraction = 0.0;
  for (size_t x = 0; x < n; ++x)
    if (tree.is_leaf(static_cast<int>(x))) contraction = std::max(contraction, max3(rho_[x]) * row_sum(x));
  SweepMonitor monitor(opt_.tolerance, contraction);
  std::vector<Rgb> before;
  for (int sweep = 0;; ++sweep) {
    if (sweep >= opt_.max_iterations)
      throw NumericalError(scene_.source + ": hierarchical solve did not converge to tolerance " +
                           std::to_string(opt_.tolerance) + " in " + std::to_string(opt_.max_iterations) +
                           " sweeps");
    before = B_;
    double change = 0.0, top = 0.0;
    gather_clusters();
    for (int r = 0; r < tree.root_count(); ++r) pull(r, change, top);
    update_groups();
    ++out_.stats.sweeps;
    if (!std::isfinite(change))
      throw NumericalError(scene_.source + ": hierarchical solve produced a non-finite radiosity");
    if (change > 0.0 && top > 0.0)  // the decades of the tolerance reached
      report("solve", std::clamp(std::log(change / top) / std::log(opt_.tolerance), 0.0, 1.0));
    const SweepMonitor::Action action = monitor.after_sweep(change, top);
    if (action == SweepMonitor::Action::stop) break;
    if (action == SweepMonitor::Action::extrapolate) {
      // Every node at once: inner nodes are area means of their children,
      // and the extrapolation is linear, so they stay consistent.
      const double k = monitor.extrapolation_factor();
      for (size_t x = 0; x < n; ++x) B_[x] += k * (B_[x] - before[x]);
      update_groups();
      link_values();
    }
  }
  extrapolations_ += monitor.extrapolations();
  gather_clusters();
  H_.assign(n, Rgb(0.0));
  for (size_t x = 0; x < n; ++x) {
    if (!tree.is_leaf(static_cast<int>(x))) continue;
    H_[x] = gathered(x);
  }
}

Rgb Hierarchical::pull(int p, double& change, double& top) {
  const auto& node = out_.tree.node(p);
  Rgb b(0.0);
  if (node.child < 0) {
    const Rgb g = gathered(static_cast<size_t>(p));
    b = emit_[static_cast<size_t>(p)] + rho_[static_cast<size_t>(p)] * g;
  } else {
    double area = 0.0;
    for (int c = node.child; c < node.child + 4; ++c) {
      const double a = tri_[static_cast<size_t>(c)].area;
      b += a * pull(c, change, top);
      area += a;
    }
    b /= area;
  }
  // What it sends changes now (Gauss-Seidel on the links' values too).
  const Rgb d = b - B_[static_cast<size_t>(p)];
  for (const auto& [id, w] : sent_[static_cast<size_t>(p)])
    link_value_[static_cast<size_t>(id)] += (w * inv_sent_[static_cast<size_t>(id)]) * d;
  Rgb& old = B_[static_cast<size_t>(p)];
  change = std::max(change, max3(glm::abs(b - old)));
  top = std::max(top, max3(b));
  old = b;
  return b;
}

// What every cluster group gathers now, pushed down (accumulated over its
// ancestors' groups) for the leaves.
void Hierarchical::gather_clusters() {
  if (ct_.empty()) return;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, ct_.group_count(), 256), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t g = r.begin(); g != r.end(); ++g) {
      const int gi = static_cast<int>(g);
      for (int k = 0; k < bins_; ++k) HG_[bin_index(gi, k)] = Rgb(0.0);
      for (const GroupTerm& t : gterms_[g]) HG_[bin_index(gi, t.bin())] += static_cast<double>(t.f) * value(t.q());
    }
  });
  tbb::parallel_for(tbb::blocked_range<size_t>(0, node_gatherers_.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const size_t a = static_cast<size_t>(node_gatherers_[i]);
      Rgb h(0.0);
      for (const Term& t : node_terms_[a]) h += static_cast<double>(t.f) * GB_[static_cast<size_t>(-2 - t.q)];
      node_H_[a] = h;
    }
  });
  for (int g = static_cast<int>(ct_.group_count()) - 1; g >= 0; --g) {
    const int up = ct_.group(g).up;
    for (int k = 0; k < bins_; ++k)
      HGacc_[bin_index(g, k)] = per_open(bin_index(g, k)) * HG_[bin_index(g, k)] + (up >= 0 ? HGacc_[bin_index(up, k)] : Rgb(0.0));
  }
}

}  // namespace radmesh::internal
