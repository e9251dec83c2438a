// The hierarchical solver's rounds: the first linking and solve, each
// refinement round (links refined where the last solve says it matters,
// Baum's splits where vertex values differ, then a solve), the growth of
// the element tree, and the T-vertices closed when the tree grows.

#include "radiosity/hierarchical/solver.h"

#include "core/power_of_two.h"

#include <queue>

namespace radmesh::internal {

Hierarchical::Hierarchical(const Scene& scene, const SolveOptions& opt, const HierarchicalOptions& hopt,
                           HierarchicalSolution& out, const ProgressFn& progress)
    : scene_(scene), opt_(opt), hopt_(hopt), out_(out), progress_(progress), visibility_(scene, opt.rays) {
  limit_ = memory_limit_bytes(opt);
  held_before_ = resident_memory_bytes();
  diagonal_ = scene.diagonal();
  min_area_ = hopt.min_area > 0.0 ? hopt.min_area : 0.5 * std::pow(diagonal_ / 150.0, 2);
  out_.stats.min_area = min_area_;
  for (const Material& m : scene.materials) max_emission_ = std::max(max_emission_, max3(m.emission));
  scale_ = max_emission_;
  rays_reference_ = scale_;
  quadrature_ = opt.quadrature;
  quadrature_.max_level = std::max(quadrature_.max_level, 3);  // links of near elements: one link, many points
  grow();
  // The roots, cut along the contact lines, lie wholly inside or outside
  // closed objects (nothing lies inside anything in a convex enclosure).
  if (!visibility_.convex_enclosure())
    enclosed_warnings_ = enclosed_emitter_warnings(scene, el_, emitting_inside_objects(scene, el_, visibility_.rays()));
  for (int r = 0; r < out_.tree.root_count(); ++r) mean_root_area_ += tri_[static_cast<size_t>(r)].area;
  if (out_.tree.root_count() > 0) mean_root_area_ /= out_.tree.root_count();
  area_unit_ = internal::power_of_two_above(mean_root_area_);
}

// The first linking (every pair of roots whose patches can see each
// other, refined by the oracle) and the first solve.
void Hierarchical::start() {
  auto& st = out_.stats;
  const ElementTree& tree = out_.tree;
  report("link", 0.0);
  auto t0 = std::chrono::steady_clock::now();
  if (hopt_.clusters != ClusterMode::off && tree.root_count() >= 2) {
    build_clusters();
    link_pairs(link_cluster_pairs({{cluster_code(0), cluster_code(0)}}));
    report("link", 1.0);
    close_t_vertices();
    st.seconds_link += seconds_since(t0);
    solve_round();
    return;
  }
  // Every root pair whose patches face each other becomes at least one
  // link: refuse at once when those alone would not fit the memory limit.
  std::vector<long long> per_patch(scene_.patches.size(), 0);
  for (int r = 0; r < tree.root_count(); ++r) ++per_patch[static_cast<size_t>(node_patch(r))];
  double facing_pairs = 0.0;
  for (size_t a = 0; a < per_patch.size(); ++a)
    for (size_t b = 0; b < per_patch.size(); ++b)
      if (a != b && visibility_.facing(static_cast<int>(a), static_cast<int>(b)))
        facing_pairs += static_cast<double>(per_patch[a]) * static_cast<double>(per_patch[b]);
  if (held_before_ + facing_pairs * kLinkBytes > limit_)
    throw NumericalError(scene_.source + ": " + std::to_string(tree.root_count()) + " initial elements make " +
                         format_number(facing_pairs) + " pairs to link, " + format_number(facing_pairs * kLinkBytes / kGiB) +
                         " GiB at least" + held_text() + ", more than the " + format_number(limit_ / kGiB) +
                         " GiB allowed; use a larger max_edge (hierarchical radiosity refines by itself) or "
                         "raise max_memory",
                         {"max_edge", "max_memory"});
  // In blocks of receivers, so that a generation's scratch stays small.
  std::vector<std::pair<int, int>> pairs;
  for (int p = 0; p < tree.root_count(); ++p) {
    for (int q = 0; q < tree.root_count(); ++q)
      if (p != q && visibility_.facing(node_patch(p), node_patch(q))) pairs.emplace_back(p, q);
    if (pairs.size() >= (1u << 20) || p + 1 == tree.root_count()) {
      link_pairs(std::move(pairs));
      pairs.clear();
      report("link", static_cast<double>(p + 1) / tree.root_count());
    }
  }
  close_t_vertices();
  st.seconds_link += seconds_since(t0);
  solve_round();
}

// One refinement round: refine the links where the current radiosity
// says it matters (and Baum's criterion), then solve again. False, with
// nothing changed, when the last round already met the stopping rule
// (max_rounds, a change below the tolerance) or nothing was refined.
bool Hierarchical::step() {
  auto& st = out_.stats;
  if (done_ || st.rounds - 1 >= hopt_.max_rounds || (st.rounds > 1 && st.last_change < opt_.tolerance)) {
    done_ = true;
    return false;
  }
  previous_ = B_;
  // The first round's leaf terms were made before any reflected radiosity
  // was known, which decides where a leaf casts its own rays: made anew.
  if (st.rounds == 1) std::fill(dirty_.begin(), dirty_.end(), 1);
  const auto t2 = std::chrono::steady_clock::now();
  report("refine", 0.0);
  long long refined = 0;
  left_ = st.rounds >= 2 ? wanted_refinement() : Wanted{};
  if (st.rounds < 2 || left_.worst > hopt_.marginal_refinement) {
    left_ = Wanted{};
    refined = refine_links();
  }
  report_left();
  // Where the field is gathered at the vertices, Baum's splits only add
  // display vertices: they wait until no link is refined any more, then
  // make the last round (display_round).
  const bool display_only = gathered_field();
  const int baum = display_only ? 0 : split_by_variation(refined > 0);
  close_t_vertices();
  st.seconds_link += seconds_since(t2);
  if (refined == 0 && display_only) return display_round();
  if (refined == 0 && baum == 0) {
    done_ = true;
    return false;
  }
  solve_round();
  return true;
}

// The links as they stand (they do not change after the last publish),
// copied into the result.
void Hierarchical::finish() {
  out_.stats.links = count_links();
  out_.links.clear();
  out_.cluster_links.clear();
  if (!hopt_.export_links) return;
  out_.links.assign(links_.size(), {});
  auto cluster_link = [&](int p, const Link& l) {
    HierarchicalClusterLink c;
    c.receiver = code_centre(p);
    c.source = code_centre(l.source);
    (p >= 0 ? c.receiver_node : c.receiver_cluster) = p >= 0 ? p : cluster_of(p);
    (l.source >= 0 ? c.source_node : c.source_cluster) = l.source >= 0 ? l.source : cluster_of(l.source);
    c.form_factor = l.f * l.visible;
    c.visible = l.visible;
    const double rho = p >= 0 ? max3(rho_[static_cast<size_t>(p)]) : ct_.cluster(cluster_of(p)).weight;
    c.transport = rho * c.form_factor * code_radiosity(l.source);
    out_.cluster_links.push_back(c);
  };
  for (size_t p = 0; p < links_.size(); ++p)
    for (const Link& l : links_[p]) {
      if (l.source >= 0)
        out_.links[p].push_back({l.source, l.f * l.visible, l.visible});
      else
        cluster_link(static_cast<int>(p), l);
    }
  for (size_t c = 0; c < clinks_.size(); ++c)
    for (const Link& l : clinks_[c]) cluster_link(cluster_code(static_cast<int>(c)), l);
}

// Solve, publish, and the change of the node field since the last round
// (a node made since is compared with its deepest ancestor that existed then).
// The solve phase's time includes the publish (the conforming mesh and its
// vertex values, every round), which would otherwise show as the method's
// "setup".
void Hierarchical::solve_round() {
  auto& st = out_.stats;
  const auto t1 = std::chrono::steady_clock::now();
  solve();
  double reflected = 0.0;
  for (size_t n = 0; n < B_.size(); ++n) reflected = std::max(reflected, max3(B_[n] - emit_[n]));
  if (reflected > 0.0) scale_ = reflected;
  rays_reference_ = scale_;
  double sum = 0.0, area = 0.0;  // over the leaves that reflect
  for (size_t n = 0; n < B_.size(); ++n)
    if (out_.tree.is_leaf(static_cast<int>(n)) && max3(rho_[n]) > 0.0) {
      sum += tri_[n].area * max3(B_[n] - emit_[n]);
      area += tri_[n].area;
    }
  if (sum > 0.0) rays_reference_ = std::min(scale_, sum / area);
  ++st.rounds;
  publish();
  check_memory();
  st.seconds_solve += seconds_since(t1);
  st.links = count_links();
  st.links_per_round.push_back(st.links);
  st.leaves_per_round.push_back(st.leaves);
  if (!previous_.empty()) {
    double change = 0.0, top = 0.0;
    for (size_t n = 0; n < B_.size(); ++n) {
      const int old = nearest_old(static_cast<int>(n), previous_.size());
      change = std::max(change, max3(glm::abs(B_[n] - previous_[static_cast<size_t>(old)])));
      top = std::max(top, max3(B_[n]));
    }
    st.last_change = top > 0.0 ? change / top : 0.0;
  }
}

// The last round where the field is gathered: Baum's splits alone, whose
// leaves take their parent's radiosity (grow) and are not solved. The
// gather evaluates every display vertex anew, exact direct light
// included, so what the splits buy is vertices where the field bends; as
// sources of the gather, the leaves' values at their parent's resolution
// do as well as solving them would, for a fraction of the cost
// (docs/decisions.md, Baum's criterion). With nothing solved after it, the
// criterion is applied once, on the last solve's values, in depth
// (split_by_variation's `deep`): the fit over leaves of their parent's
// value shows steps between them, which repeated splitting would chase.
// The balance and the solver's statistics stay the last solve's. False
// when nothing is split.
bool Hierarchical::display_round() {
  done_ = true;
  if (split_by_variation(true, true) == 0) return false;
  auto& st = out_.stats;
  const auto t1 = std::chrono::steady_clock::now();
  ++st.rounds;
  publish_mesh();
  st.seconds_solve += seconds_since(t1);
  SolveStats& solved = out_.solution.stats;
  solved.elements = st.leaves;
  solved.seconds_form_factors = st.seconds_link;
  solved.seconds_solve = st.seconds_solve;
  st.links_per_round.push_back(st.links);
  st.leaves_per_round.push_back(st.leaves);
  return true;
}

// The field the run will show is the gather: FieldMode gather, or
// automatic within the gather's budget with room for Baum's splits to
// come (resolve_field_mode decides on the final mesh). They add at most
// kBaumShare of the leaves, a vertex at most per leaf added, and a mesh
// has about half as many vertices as triangles: the vertices grow by
// 2 x kBaumShare of themselves at most. Early rounds (a small mesh) may
// say gather and later ones fit; never the other way (the mesh only
// grows), and a display round is made only while it says gather, so its
// leaves, which are not solved, always end under the gather.
bool Hierarchical::gathered_field() const {
  if (opt_.field != FieldMode::automatic) return opt_.field == FieldMode::gather;
  const double vertices = (1.0 + 2.0 * kBaumShare) * static_cast<double>(out_.mesh.positions.size());
  return gather_within_budget(scene_, vertices);
}

// Keeps the per-node arrays as long as the tree.
void Hierarchical::grow() {
  const size_t n = out_.tree.nodes().size();
  while (tri_.size() < n) {
    const auto& node = out_.tree.node(static_cast<int>(tri_.size()));
    const auto& pos = out_.tree.positions();
    el_.add(scene_, node.patch, pos[static_cast<size_t>(node.v[0])], pos[static_cast<size_t>(node.v[1])],
            pos[static_cast<size_t>(node.v[2])]);
    // A new node starts from its parent's radiosity (or its emission).
    B_.push_back(node.parent >= 0 ? B_[static_cast<size_t>(node.parent)] : emit_.back());
    links_.emplace_back();
    dirty_.push_back(1);
    sent_dirty_.push_back(1);
    sent_.emplace_back();
    if (node.parent >= 0) sent_dirty_[static_cast<size_t>(node.parent)] = 1;  // it is no longer a leaf
  }
}

// `round_made`: the round is made anyway (links were refined, or it is
// the display round, which costs a publish only), so the kBaumRound rule
// does not apply. `deep` (the display round, whose leaves are not
// solved): a leaf is split ceil(log2(spread / threshold)) levels down at
// once (to the floor), since the spread halves with each level where the
// field is linear over the leaf.
int Hierarchical::split_by_variation(bool round_made, bool deep) {
  if (!(hopt_.baum > 0.0)) return 0;
  const HierarchicalSolution& o = out_;
  const double top = scale_;  // the largest reflected radiosity
  std::vector<std::pair<double, int>> todo;  // (spread, leaf)
  for (size_t t = 0; t < o.leaf_of.size(); ++t) {
    const int n = o.leaf_of[t];
    if (n < 0 || !(tri_[static_cast<size_t>(n)].area > min_area_)) continue;
    Rgb lo(1e300), hi(-1e300);
    for (int c : o.solution.nodal.corners[t]) {
      lo = glm::min(lo, o.solution.nodal.radiosity[static_cast<size_t>(c)]);
      hi = glm::max(hi, o.solution.nodal.radiosity[static_cast<size_t>(c)]);
    }
    const double spread = max3(hi - lo);
    if (spread > hopt_.baum * top && spread > hopt_.baum_absolute) todo.push_back({spread, n});
  }
  const long long added = 3LL * out_.stats.baum_splits;
  const long long budget = static_cast<long long>(kBaumShare * static_cast<double>(o.stats.leaves - added)) - added;
  const long long wanted = std::min(3LL * static_cast<long long>(todo.size()), budget);
  if (!round_made && static_cast<double>(wanted) < kBaumRound * static_cast<double>(o.stats.leaves)) return 0;
  const double threshold = std::max(hopt_.baum * top, hopt_.baum_absolute);
  // The largest spread is split first (ties: the lower node), one level at
  // a time; in depth, its children come back with half its spread while
  // that is over the threshold, so a bound budget goes level by level to
  // the leaves where the field bends most, instead of all the levels of
  // the first leaves in spread order.
  auto later = [](const std::pair<double, int>& a, const std::pair<double, int>& b) {
    return a.first < b.first || (a.first == b.first && a.second > b.second);
  };
  std::priority_queue<std::pair<double, int>, std::vector<std::pair<double, int>>, decltype(later)> queue(
      later, std::move(todo));
  int splits = 0;
  while (!queue.empty() && 3LL * (splits + 1) <= budget) {
    const auto [spread, m] = queue.top();
    queue.pop();
    if (!(out_.tree.area(m) > min_area_)) continue;
    if (out_.tree.is_leaf(m)) {  // the link refinement just before may have split it already
      out_.tree.split(m);
      ++splits;
    }
    if (deep && 0.5 * spread > threshold)
      for (int c = out_.tree.node(m).child; c < out_.tree.node(m).child + 4; ++c) queue.emplace(0.5 * spread, c);
  }
  grow();
  out_.stats.baum_splits += splits;
  return splits;
}

// TVertexMode::split: split leaves until no T-vertex is left. The new
// leaves gather over their ancestors' links, so nothing needs relinking.
void Hierarchical::close_t_vertices() {
  if (hopt_.tvertex != TVertexMode::split) return;
  out_.stats.conforming_splits += out_.tree.split_until_conforming();
  grow();
}

}  // namespace radmesh::internal
