// Hierarchical radiosity: links, oracle, leaf gathering and pull.

#include "radmesh/hierarchical.h"

#include "radmesh/errors.h"
#include "radiosity/transport/clusters.h"
#include "radmesh/field.h"
#include "radmesh/form_factor.h"
#include "radiosity/transport/sampling.h"
#include "radiosity/transport/transport.h"
#include "radiosity/transport/visibility.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <memory>
#include <cmath>
#include <string>
#include <limits>
#include <numbers>
#include <queue>
#include <unordered_map>

namespace radmesh {

namespace {

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

struct Link {
  int source = -1;
  // One field for two uses, which no link has both of (20 bytes a link
  // instead of 24; a box field of 10^5 faces has 10^8 links):
  // - an element-to-element link: its number (store_element_link), which its
  //   leaf terms on both sides refer to;
  // - a link with a cluster end: where its visible fraction per normal group
  //   of that end starts in the solver's group_visible_ (-1: `visible` for
  //   every group). The end is the receiver when it is a cluster, else the
  //   source.
  int slot = -1;
  // Single precision (40 bytes a link before).
  float f = 0.0f;         // F(receiver -> source) without occlusion
  float visible = 1.0f;   // what got through of the shadow rays, each weighed by its point kernel
  float spread = 0.0f;    // how much the point form factor varies over the receiver (oracle)
  bool partial() const { return visible > 0.0 && visible < 1.0; }
};
static_assert(sizeof(Link) == 20);

class Solver {
public:
  // `out.tree` holds the roots (the initial mesh) on entry.
  Solver(const Scene& scene, const SolveOptions& opt, const HierarchicalOptions& hopt, HierarchicalSolution& out,
         const ProgressFn& progress)
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
  }

  // The first linking (every pair of roots whose patches can see each
  // other, refined by the oracle) and the first solve.
  void start() {
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
  bool step() {
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
  void finish() {
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

private:
  // Solve, publish, and the change of the node field since the last round
  // (a node made since is compared with its deepest ancestor that existed then).
  // The solve phase's time includes the publish (the conforming mesh and its
  // vertex values, every round): left out, it showed as the method's
  // "setup" (at 1,310,727 input faces 37.6 s of it).
  void solve_round() {
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
  // included, so what the splits buy is vertices where the field bends;
  // as sources of the gather, the leaves' values at their parent's
  // resolution did as well on the Cornell box as solving them, which took
  // a tenth of the run (their terms, their sweeps and a round of their
  // own). With nothing solved after it, the criterion is applied once, on
  // the last solve's values, in depth (split_by_variation's `deep`): the
  // fit over leaves of their parent's value shows steps between them, and
  // splitting on those (10 meshes published) gave 31,802 leaves, L2
  // 0.432% and worst patch mean 0.37% on the Cornell box, once in depth
  // 30,590, 0.444% and 0.38%, in 0.84x the solve time. The balance and the
  // solver's statistics stay the last solve's. False when nothing is split.
  bool display_round() {
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
  bool gathered_field() const {
    if (opt_.field != FieldMode::automatic) return opt_.field == FieldMode::gather;
    const double vertices = (1.0 + 2.0 * kBaumShare) * static_cast<double>(out_.mesh.positions.size());
    return gather_within_budget(scene_, vertices);
  }

  int node_patch(int n) const { return out_.tree.node(n).patch; }
  // Keeps the per-node arrays as long as the tree.
  void grow() {
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

  // Baum's a-posteriori criterion: a leaf whose vertex values (as last
  // published) differ by more than baum x the largest reflected radiosity
  // and more than baum_absolute is split, down to a quarter of the minimum
  // area (one level below the links' floor). Its children gather over its
  // links, so nothing needs relinking: the split costs leaves, not links.
  // The leaves it adds are kept within kBaumShare of those the links made,
  // the largest spreads split first: on a field of 8 x 8 boxes, all of
  // them shadowing one another, it split 22 k leaves unbounded (2.5x the
  // leaves, 2.9x the run); on the Cornell box and the sphere rooms the
  // bound is never reached.
  // A round for Baum's splits alone (no link refined) costs a pass over
  // every leaf (terms, sweeps, publish): it is made only where the splits
  // add at least kBaumRound of the leaves. On the Cornell box the last
  // round split 18 leaves of 30,689 and cost 6% of the run.
  static constexpr double kBaumShare = 0.5;
  static constexpr double kBaumRound = 0.01;
  // `round_made`: the round is made anyway (links were refined, or it is
  // the display round, which costs a publish only), so the kBaumRound rule
  // does not apply. `deep` (the display round, whose leaves are not
  // solved): a leaf is split ceil(log2(spread / threshold)) levels down at
  // once (to the floor), since the spread halves with each level where the
  // field is linear over the leaf.
  int split_by_variation(bool round_made, bool deep = false) {
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
    // the first leaves in spread order (on the Cornell box at --epsilon
    // 0.01, L2 2.44% -> 1.59% for the same leaves).
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
  void close_t_vertices() {
    if (hopt_.tvertex != TVertexMode::split) return;
    out_.stats.conforming_splits += out_.tree.split_until_conforming();
    grow();
  }

  static constexpr double kSplittableArea = 4.0;  // in min_area_: an element above it may be split
  bool splittable(int n) const { return tri_[static_cast<size_t>(n)].area > kSplittableArea * min_area_; }

  // F(p -> q) without occlusion, from points on p graded toward q (the
  // caller, link_pairs, has dropped pairs facing away).
  double form_factor_to(int p, int q) const {
    const Triangle& a = tri_[static_cast<size_t>(p)];
    const Triangle& b = tri_[static_cast<size_t>(q)];
    const ReceiverPoints pts =
        receiver_points(a, [&](const Vec3& x) { return distance_to_triangle(x, b); }, quadrature_);
    return form_factor(pts, b);
  }

  // Links every receiver p to its source q, refining first where the oracle
  // asks: breadth first, one generation of pairs at a time. The form factor,
  // visibility and spread of a generation are computed in parallel (each
  // pair alone, with its own random stream, so the result does not depend on
  // the threads); deciding, splitting and storing is sequential and in order.
  //
  // A generation is evaluated kLinkBlock pairs at a time, so that the
  // per-pair scratch stays small and is reused (link_cluster_pairs too): on a
  // sphere room of 81,927 faces a generation held tens of millions of pairs,
  // and allocating and zeroing scratch for all of them at once cost more
  // than evaluating them. The blocks are consumed in order: same result.
  static constexpr size_t kLinkBlock = size_t{1} << 14;
  void link_pairs(std::vector<std::pair<int, int>> todo) {
    std::vector<Link> ev;
    std::vector<RayCount> rays;
    std::vector<char> split;                // per pair: split_by_corners held
    std::vector<std::pair<int, int>> next;  // its memory kept from generation to generation
    while (!todo.empty()) {
      next.clear();
      for (size_t begin = 0; begin < todo.size(); begin += kLinkBlock) {
        const size_t count = std::min(kLinkBlock, todo.size() - begin);
        ev.assign(count, Link{});
        rays.assign(count, RayCount{});
        split.assign(count, 0);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 16), [&](const tbb::blocked_range<size_t>& r) {
          for (size_t i = r.begin(); i != r.end(); ++i) {
            const auto [p, q] = todo[begin + i];
            Link& l = ev[i];
            l.source = q;
            if (facing_away(tri_[static_cast<size_t>(p)], tri_[static_cast<size_t>(q)])) continue;  // F = 0
            const std::array<double, 4> corner_f = corner_form_factors(p, q);
            if (split_by_corners(p, q, corner_f)) {
              split[i] = 1;
              continue;
            }
            l.f = form_factor_to(p, q);
            if (l.f <= 0.0) continue;
            l.spread = spread(corner_f, l.f);
            if (split_whatever_visible(p, l)) continue;  // no rays: they would not change the decision
            l.visible = visibility_.visible_fraction(tri_[static_cast<size_t>(p)], node_patch(p), static_cast<uint64_t>(p),
                                                     tri_[static_cast<size_t>(q)], node_patch(q), static_cast<uint64_t>(q),
                                                     rays[i]);
          }
        });
        for (size_t i = 0; i < count; ++i) {
          const int p = todo[begin + i].first;
          ++out_.stats.links_examined;
          out_.stats.rays_cast += rays[i].cast;
          out_.stats.rays_skipped += rays[i].skipped;
          out_.stats.pairs_unoccludable += rays[i].unoccludable;
          const Link& l = ev[i];
          if (split[i]) {
            split_pair(p, l.source, true, next);  // split_by_corners: one of them is splittable
            continue;
          }
          if (!std::isfinite(l.f) || !std::isfinite(l.spread))
            throw NumericalError(scene_.source + ": link from node " + std::to_string(l.source) + " to node " +
                                 std::to_string(p) + " has a non-finite form factor");
          if (l.f <= 0.0) continue;
          if (wants_refinement(p, l) && split_pair(p, l.source, spread_dominates(l), next)) continue;
          store_element_link(p, l);
        }
        check_resident();
      }
      todo.swap(next);
      check_memory();
    }
  }

  // An element-to-element link is numbered when stored (numbers of removed
  // links are used again), and its source's leaves must count it among
  // what they send (sender_terms).
  void store_element_link(int p, Link l) {
    if (free_ids_.empty()) {
      l.slot = next_id_++;
    } else {
      l.slot = free_ids_.back();
      free_ids_.pop_back();
    }
    sent_dirty_[static_cast<size_t>(l.source)] = 1;
    links_[static_cast<size_t>(p)].push_back(l);
    dirty_[static_cast<size_t>(p)] = 1;
  }
  void release_element_link(const Link& l) {
    free_ids_.push_back(l.slot);
    sent_dirty_[static_cast<size_t>(l.source)] = 1;
  }

  // The memory limit holds for the whole process, after every generation of
  // links, the leaf terms and the published mesh: the larger of what the
  // process held when the solver began plus the solver's own count (links,
  // link numbers, leaf terms, clusters: known before the allocator shows
  // them) and the resident memory now (all the rest: the element tree, the
  // mesh, the visibility structure, the allocator's slack). The own count
  // alone let the 128 x 128 box field peak at 14.1 GB under a 12 GiB limit.
  void check_memory() {
    const long long links = count_links();
    const double own = static_cast<double>(links) * kLinkBytes + static_cast<double>(next_id_) * kLinkIdBytes +
                       static_cast<double>(group_visible_.size()) * sizeof(float) +
                       static_cast<double>(out_.stats.leaf_terms) * sizeof(Term) +
                       ClusterTree::bytes(static_cast<double>(ct_.size()), static_cast<double>(ct_.group_count())) +
                       (ct_.empty() ? 0.0 : bin_bytes(static_cast<double>(ct_.group_count()), out_.tree.root_count()));
    const double bytes = std::max(held_before_ + own, resident_memory_bytes());
    if (bytes > limit_)
      throw NumericalError(scene_.source + ": hierarchical refinement reached " + std::to_string(links) +
                           " links; with them the process needs " + format_number(bytes / kGiB) + " GiB (its links, leaf terms and clusters " +
                           format_number(own / kGiB) + "), more than the " + format_number(limit_ / kGiB) +
                           " GiB allowed; raise epsilon or min_area, or raise max_memory",
                           {"epsilon", "min_area", "max_memory"});
  }
  // Between blocks of link pairs and of leaf terms (in_blocks), the
  // resident memory alone (one read of /proc), so that a generation of
  // millions of pairs or a round's terms cannot run far past the limit.
  void check_resident() {
    if (resident_memory_bytes() > limit_) check_memory();
  }
  // For the messages of the checks before any linking.
  std::string held_text() const {
    return held_before_ > 0.0 ? " on top of the " + format_number(held_before_ / kGiB) + " GiB the process holds" : "";
  }

  // The point form factors to q at p's corners and centroid.
  std::array<double, 4> corner_form_factors(int p, int q) const {
    const Triangle& a = tri_[static_cast<size_t>(p)];
    const Triangle& b = tri_[static_cast<size_t>(q)];
    // The four points in one pass of the vectorized kernel (per thread: this
    // runs for every pair examined).
    thread_local ReceiverPoints at;
    at.normal = a.normal;
    at.x.clear();
    for (const Vec3& x : {a.v[0], a.v[1], a.v[2], a.centroid()})
      at.x.push_back(x + 1e-6 * (a.centroid() - x));  // a corner on q's edge sees q edge-on
    std::array<double, 4> point_f;
    point_form_factors(at, b, point_f.data());
    return point_f;
  }
  // The spread: the largest difference between those and the link's mean F,
  // what pushing the link's irradiance down to p's children, all alike,
  // gets wrong.
  static double spread(const std::array<double, 4>& corner_f, double f) {
    double s = 0.0;
    for (const double pf : corner_f) s = std::max(s, std::abs(pf - f));
    return s;
  }
  // Whether split_whatever_visible holds whatever F is, from the point
  // form factors alone: then F's quadrature (on the Cornell box a third of
  // the linking's points, on near pairs) is not computed. The spread is at
  // least (max - min) / 2 for every F, and over F / 2 for every F >= 0 when
  // max > 4 min (F < (max / 3 + min) leaves max - F > F / 2, and F at or
  // over it leaves F - min > F / 2, each by a margin of about max / 12); the
  // threshold is taken 1e-6 high so that rounding cannot tip either. The
  // decision is split_whatever_visible's but where F's points would all see
  // nothing of q (a source cutting p's plane near a corner): that pair,
  // dropped before, is now split.
  bool split_by_corners(int p, int q, const std::array<double, 4>& corner_f) const {
    if (!(splittable(p) || splittable(q))) return false;
    double lo = corner_f[0], hi = corner_f[0];
    for (const double pf : corner_f) {
      if (!std::isfinite(pf)) return false;
      lo = std::min(lo, pf);
      hi = std::max(hi, pf);
    }
    return hi > 4.0 * lo && element_weight(p, q) * 0.5 * (hi - lo) > (1.0 + 1e-6) * hopt_.epsilon * scale_;
  }

  static bool spread_dominates(const Link& l) { return l.spread > 0.5 * l.f * l.visible; }

  // A pair whose spread alone makes the oracle refine it, and decides that
  // the receiver is split first, is split whatever its shadow rays say
  // (wants_refinement and spread_dominates hold for every visible fraction,
  // and with l.visible left at 1 they see the same): its rays are not cast.
  // On the Cornell box 8% of the pairs the linking examined (62 k of 744 k);
  // split_by_corners finds most of them before their F.
  bool split_whatever_visible(int p, const Link& l) const {
    return element_weight(p, l.source) * l.spread > hopt_.epsilon * scale_ && l.spread > 0.5 * l.f &&
           (splittable(p) || splittable(l.source));
  }

  // The oracle: the error of gathering over this link at this level, as
  // rho_p * B_q * (spread of F over p), plus the whole transport
  // rho_p B_q F V when the link is partly visible (a shadow boundary crosses it).
  double link_error(int p, const Link& l) const {
    const double unseen = l.partial() ? l.f * l.visible : 0.0;
    return element_weight(p, l.source) * (l.spread + unseen);
  }
  // What the oracle multiplies a link's form-factor error by: rho_p B_q,
  // weighed by the receiver's area (pw).
  double element_weight(int p, int q) const {
    return max3(rho_[static_cast<size_t>(p)]) * max3(B_[static_cast<size_t>(q)]) * pw(p);
  }
  bool wants_refinement(int p, const Link& l) const { return link_error(p, l) > hopt_.epsilon * scale_; }

  // Splits the receiver p when the form factor varies over it (the spread
  // is what pushing down gets wrong) or it is the larger, else the source q,
  // and queues the children's pairs instead. Returns false when neither may
  // be split.
  bool split_pair(int p, int q, bool receiver_first, std::vector<std::pair<int, int>>& next) {
    const bool sp = splittable(p), sq = splittable(q);
    if (!sp && !sq) return false;
    const bool split_p =
        sp && (receiver_first || !sq || tri_[static_cast<size_t>(p)].area >= tri_[static_cast<size_t>(q)].area);
    const int n = split_p ? p : q;
    int first = out_.tree.node(n).child;
    if (first < 0) {
      first = out_.tree.split(n);
      grow();
    }
    for (int c = first; c < first + 4; ++c) next.emplace_back(split_p ? c : p, split_p ? q : c);
    return true;
  }

  // What the oracle would refine now: how many links, and the largest
  // error among them. step() makes no round for links that are all over
  // the threshold by at most HierarchicalOptions::marginal_refinement x:
  // they crossed it because the last solve moved their source's radiosity
  // or the scale a little, and refining one changes its receiver by about
  // its error, what the oracle leaves on every other link, while a round
  // costs a pass over every link and leaf (a re-link, terms, sweeps and a
  // publish). On the 32 x 32 box field the third round would refine
  // 103,906 of 10.4 M links, all within 1.5x, and with the fourth took 0.21
  // of the run; without them no patch mean moved by more than 0.46%
  // (per-patch error against a fine solve unchanged, median 0.61%); the
  // Cornell box's third round, 2,022 links, went too (L2 0.4415% ->
  // 0.4392%, worst patch mean 0.384% -> 0.394%). Not asked in the first
  // refinement round, whose links were made with the emission as the scale.
  struct Wanted {
    long long links = 0;
    double worst = 0.0;  // the largest error over the threshold
  };
  // Says so among the skips: at each publish (which starts them anew) and
  // when step() leaves them, the last count standing.
  void report_left() {
    auto& skips = out_.solution.stats.skips;
    const std::string tag = "refinement: ";
    std::erase_if(skips, [&](const std::string& k) { return k.rfind(tag, 0) == 0; });
    if (left_.links > 0)
      skips.push_back(tag + std::to_string(left_.links) + " links over the oracle's threshold by at most " +
                      format_number(left_.worst) + "x (marginal_refinement " +
                      format_number(hopt_.marginal_refinement) +
                      ") were not refined: a round for them changes their receivers by about what the oracle leaves on every link");
  }
  Wanted wanted_refinement() const {
    const double threshold = hopt_.epsilon * scale_;
    Wanted w;
    auto add = [&](double e) {
      if (!(e > threshold)) return;
      ++w.links;
      w.worst = std::max(w.worst, e / threshold);
    };
    for (size_t p = 0; p < links_.size(); ++p)
      for (const Link& l : links_[p]) add(refinement_error(static_cast<int>(p), l));
    for (size_t c = 0; c < clinks_.size(); ++c)
      for (const Link& l : clinks_[c]) add(cluster_link_error(cluster_code(static_cast<int>(c)), l));
    return w;
  }
  // A receiver node's link's error for refinement: 0 for an element link
  // whose two ends may not be split.
  double refinement_error(int p, const Link& l) const {
    if (l.source < 0) return cluster_link_error(p, l);
    return splittable(p) || splittable(l.source) ? link_error(p, l) : 0.0;
  }

  // Refines every link the oracle now flags (with the current radiosity).
  long long refine_links() {
    long long refined = 0;
    std::vector<std::pair<int, int>> next;
    const size_t n = links_.size();
    std::vector<std::pair<int, int>> cluster_next;
    for (size_t p = 0; p < n; ++p) {
      std::vector<Link> keep, redo;
      for (const Link& l : links_[p]) {
        const bool again = refinement_error(static_cast<int>(p), l) > hopt_.epsilon * scale_;
        (again ? redo : keep).push_back(l);
      }
      if (redo.empty()) continue;
      links_[p] = keep;
      dirty_[p] = 1;
      for (const Link& l : redo) {
        ++refined;
        if (l.source < 0)
          cluster_next.emplace_back(static_cast<int>(p), l.source);
        else if (!split_pair(static_cast<int>(p), l.source, spread_dominates(l), next))
          links_[p].push_back(l);
        else
          release_element_link(l);
      }
    }
    for (size_t c = 0; c < clinks_.size(); ++c) {
      std::vector<Link> keep;
      for (const Link& l : clinks_[c]) {
        if (wants_cluster_refinement(cluster_code(static_cast<int>(c)), l)) {
          ++refined;
          cluster_next.emplace_back(cluster_code(static_cast<int>(c)), l.source);
        } else {
          keep.push_back(l);
        }
      }
      if (keep.size() != clinks_[c].size()) clinks_[c] = std::move(keep);
    }
    // Split cluster links become pairs of their children first: a pair of
    // two elements then goes to the element linking with the rest.
    std::vector<std::pair<int, int>> children;
    for (auto& [p, q] : cluster_next) split_cluster_pair(p, q, children);
    std::vector<std::pair<int, int>> elements = link_cluster_pairs(std::move(children));
    next.insert(next.end(), elements.begin(), elements.end());
    link_pairs(std::move(next));
    return refined;
  }

  long long count_links() const {
    long long c = 0;
    for (const auto& l : links_) c += static_cast<long long>(l.size());
    for (const auto& l : clinks_) c += static_cast<long long>(l.size());
    return c;
  }

  // The receiver side at leaf resolution: every leaf gathers over its own
  // links and its ancestors' (instead of having their irradiance pushed down
  // as one average), with the form factors to all those sources taken at the
  // same points of the leaf. The sources of a leaf's path cover what it sees
  // exactly once, so in a closed scene a leaf's row sums to 1 up to
  // rounding, as in the matrix method.
  //
  // Visibility: a link's own visible fraction, except where a leaf gathers
  // over an ancestor's partly visible link that could move it by more than
  // kLeafRaysBound x epsilon x the scene's mean reflected radiosity
  // (rho_leaf F B_source, the most the link's fraction can be off by; see
  // rays_reference_): then the leaf casts its own rays to the source (a
  // quarter of --rays, at least one, stratified; its own random stream:
  // unbiased for the leaf, and its many links average the noise; 16 rays
  // gave the same Cornell errors, and on the 8 x 8 box field 1.6x the run;
  // without the bound, the same errors and 1.2x the run on a sphere room of
  // 5,127 faces; a bound of 1 lost the fix). One
  // fraction for a whole ancestor is the mean over the ancestor, and the
  // leaves next to an occluder see less than the mean: on the Cornell box
  // the floor within 15 mm of a block came out 6% brighter than the field
  // gathered there (39% in the short block's umbra, rows up to 1.04), and
  // the block faces that look at it 1.2-1.4% too bright. With the leaves'
  // own fractions, about 1% (tested) and within 0.5%.
  //
  // The sending side in pieces (sender_terms): an element link does not
  // carry its source node's mean radiosity but the mean of the source's
  // pieces weighted by how much each sends to the link's receiver
  // (A_y F(y -> receiver)). A wall's top, bright and near the ceiling, thus
  // counts for more toward the ceiling than its dim bottom: with the plain
  // mean, every surface of the Cornell box came out 0.1-1.7% low against
  // the matrix method (the ceiling most) and 0.4% of the emitted power
  // vanished between the links' two ends.
  //
  // Terms are kept between rounds for a leaf whose path has no changed link
  // (receiving) and no changed link from it (sending); the others are
  // computed in parallel, each leaf alone.
  void leaf_terms() {
    const ElementTree& tree = out_.tree;
    const size_t n = tree.nodes().size();
    terms_.resize(n);
    F_sum_.resize(n, 0.0);
    F_approx_.resize(n, 0.0);
    F_noise_.resize(n, 0.0f);
    F_doubt_.resize(n, 0.0f);
    exact_scale_.resize(n, 1.0);
    fix_exact_.resize(n, 1.0);
    node_open_.resize(n, -1.0f);
    node_terms_.resize(n);
    node_F_.resize(n, 0.0);
    node_H_.resize(n, Rgb(0.0));
    std::vector<int> todo, send_todo, node_todo;
    for (size_t x = 0; x < n; ++x)
      if (dirty_[x]) node_todo.push_back(static_cast<int>(x));
    in_blocks(node_todo, [&](size_t x) { node_cluster_terms(x); });
    node_gatherers_.clear();
    for (size_t x = 0; x < n; ++x)
      if (!node_terms_[x].empty()) node_gatherers_.push_back(static_cast<int>(x));
    for (size_t x = 0; x < n; ++x) {
      bool send_changed = false;
      for (int a = static_cast<int>(x), d = 0; a >= 0 && d <= kSenderDepth && !send_changed; a = tree.node(a).parent, ++d)
        send_changed = sent_dirty_[static_cast<size_t>(a)] != 0;
      if (send_changed) send_todo.push_back(static_cast<int>(x));
      if (!tree.is_leaf(static_cast<int>(x))) {
        terms_[x] = {};
        F_sum_[x] = 0.0;
        F_approx_[x] = 0.0;
        F_noise_[x] = 0.0f;
        F_doubt_[x] = 0.0f;
        continue;
      }
      bool changed = false;
      for (int a = static_cast<int>(x); a >= 0 && !changed; a = tree.node(a).parent)
        changed = dirty_[static_cast<size_t>(a)] != 0;
      if (changed) todo.push_back(static_cast<int>(x));
    }
    leaf_rays_.assign(n, RayCount{});
    in_blocks(todo, [&](size_t x) { gather_terms(x); });
    {
      // The element links leaving each node: (receiver, position in its
      // list), 8 bytes a link (with a pointer, 16: on the 64 x 64 box
      // field the peak came while this list was held).
      std::vector<int> out_begin(n + 1, 0);
      std::vector<std::pair<int, int>> out;
      for (size_t p = 0; p < n; ++p)
        for (const Link& l : links_[p])
          if (l.source >= 0 && l.visible > 0.0) ++out_begin[static_cast<size_t>(l.source) + 1];
      for (size_t x = 0; x < n; ++x) out_begin[x + 1] += out_begin[x];
      out.resize(static_cast<size_t>(out_begin[n]));
      std::vector<int> at(out_begin.begin(), out_begin.end() - 1);
      for (size_t p = 0; p < n; ++p)
        for (size_t k = 0; k < links_[p].size(); ++k) {
          const Link& l = links_[p][k];
          if (l.source >= 0 && l.visible > 0.0)
            out[static_cast<size_t>(at[static_cast<size_t>(l.source)]++)] = {static_cast<int>(p), static_cast<int>(k)};
        }
      at = {};
      in_blocks(send_todo, [&](size_t y) { sender_terms(y, out_begin, out); });
    }
    for (const RayCount& c : leaf_rays_) {
      out_.stats.rays_cast += c.cast;
      out_.stats.rays_skipped += c.skipped;
    }
    std::fill(dirty_.begin(), dirty_.end(), 0);
    std::fill(sent_dirty_.begin(), sent_dirty_.end(), 0);
    // Per link: what its sending leaves send (the weights' sum).
    const size_t ids = static_cast<size_t>(next_id_);
    inv_sent_.assign(ids, 0.0);
    for (size_t x = 0; x < n; ++x)
      for (const auto& [id, w] : sent_[x]) inv_sent_[static_cast<size_t>(id)] += w;
    // A link received but sent by no piece (all of them see the receiver
    // from behind at their centroids: where the receiver's plane cuts the
    // source) carries its source's plain mean: the source node itself sends,
    // weighted by what is received (area x F, the pieces' unit, should a
    // piece later send too). On the Cornell box 588 of 494,000 links, 2e-4
    // of the transport. What such a link's leaves receive is summed, negated,
    // in its own empty place in inv_sent_ (no array per link for it).
    for (size_t x = 0; x < n; ++x)
      for (const Term& t : terms_[x])
        if (inv_sent_[static_cast<size_t>(t.q)] <= 0.0) inv_sent_[static_cast<size_t>(t.q)] -= tri_[x].area * term_f(x, t);
    for (size_t p = 0; p < n; ++p)
      for (const Link& l : links_[p]) {
        if (l.source < 0) continue;  // a cluster sends it
        const size_t id = static_cast<size_t>(l.slot);
        if (inv_sent_[id] < 0.0) {
          const float w = static_cast<float>(-inv_sent_[id]);
          sent_[static_cast<size_t>(l.source)].push_back({l.slot, w});
          inv_sent_[id] = w;
        }
      }
    for (size_t id = 0; id < ids; ++id) inv_sent_[id] = inv_sent_[id] > 0.0 ? 1.0 / inv_sent_[id] : 0.0;
    cluster_terms();
    scale_rows();
    out_.stats.leaf_terms = 0;
    for (size_t x = 0; x < n; ++x)
      out_.stats.leaf_terms += static_cast<long long>(terms_[x].size() + sent_[x].size() + node_terms_[x].size());
    for (const auto& t : gterms_) out_.stats.leaf_terms += static_cast<long long>(t.size());
  }

  // Calls make(node) for every node of `todo` in parallel, kTermBlock nodes
  // at a time, with the resident memory checked between blocks: on the
  // 32 x 32 box field a round's terms are 0.8 GB, made at once they ran 40%
  // past a limit of 1 GiB before the check after them.
  static constexpr size_t kTermBlock = size_t{1} << 13;
  template <class Make>
  void in_blocks(const std::vector<int>& todo, Make&& make) {
    for (size_t begin = 0; begin < todo.size(); begin += kTermBlock) {
      const size_t end = std::min(todo.size(), begin + kTermBlock);
      tbb::parallel_for(tbb::blocked_range<size_t>(begin, end, 8), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) make(static_cast<size_t>(todo[i]));
      });
      check_resident();
    }
  }

  static constexpr double kLeafRaysBound = 0.1;  // see the comment above leaf_terms
  // Whether a node casts its own rays on a partly visible link it reads (a
  // leaf on its ancestors' links, a sending piece on its source's): where
  // the light the link's mean fraction may move there is over
  // kLeafRaysBound x epsilon x rays_reference_.
  bool own_rays_matter(double transport) const { return transport > kLeafRaysBound * hopt_.epsilon * rays_reference_; }
  // Those rays: a quarter of --rays (at least one), stratified on both
  // ends, node a's own stream with b, without a shaft test.
  int own_side() const { return std::max(1, visibility_.side() / 2); }
  double own_visible_fraction(int a, int b, RayCount& count) const {
    return visibility_.visible_fraction(tri_[static_cast<size_t>(a)], node_patch(a), static_cast<uint64_t>(a),
                                        tri_[static_cast<size_t>(b)], node_patch(b), static_cast<uint64_t>(b), count,
                                        own_side(), false);
  }
  void gather_terms(size_t x) {
    const ElementTree& tree = out_.tree;
    terms_[x].clear();
    F_sum_[x] = 0.0;
    F_approx_[x] = 0.0;
    F_noise_[x] = 0.0f;
    F_doubt_[x] = 0.0f;
    double noise = 0.0, doubt = 0.0;
    fix_exact_[x] = 1.0;
    for (int a = static_cast<int>(x); a >= 0; a = tree.node(a).parent) F_approx_[x] += node_F_[static_cast<size_t>(a)];
    thread_local std::vector<const Link*> path;  // per thread: this runs once per leaf
    path.clear();
    size_t own = 0;  // the leaf's own links come first
    for (int a = static_cast<int>(x); a >= 0; a = tree.node(a).parent) {
      for (const Link& l : links_[static_cast<size_t>(a)]) path.push_back(&l);
      if (a == static_cast<int>(x)) own = path.size();
    }
    if (path.empty()) return;
    const Triangle& t = tri_[x];
    const double rho = max3(rho_[x]);
    // The element sources' unoccluded form factors, each source at the
    // points its own distance asks for (receiver_points' rule, which takes
    // the whole leaf to one level when the distance bound is one constant:
    // the distance from the centroid to the source less the leaf's radius),
    // the sources of each level in one pass. It was the nearest source's
    // level for all of them: a leaf next to one surface took the fine
    // points for every source (on the Cornell box 76% of the points were
    // such). A row summed over several point sets is exact to the
    // quadrature only (kRowTolerance), which scale_rows allows for. The
    // lists are kept per thread: this runs once per leaf.
    thread_local std::vector<double> unoccluded;
    thread_local std::array<std::vector<const Triangle*>, kMaxQuadratureLevel + 1> by_level;
    thread_local std::array<std::vector<size_t>, kMaxQuadratureLevel + 1> slot_of;
    for (auto& v : by_level) v.clear();
    for (auto& v : slot_of) v.clear();
    const Vec3 c = t.centroid();
    size_t sources = 0;
    for (const Link* l : path) {
      if (!(l->visible > 0.0 && l->source >= 0)) continue;
      const Triangle& s = tri_[static_cast<size_t>(l->source)];
      // A bounding sphere's distance first: the level only falls as the
      // distance grows, so the exact distance is measured only where the
      // sphere's asks for more than three points.
      const double lower = std::max(glm::length(c - s.centroid()) - s.radius - t.radius, 0.0);
      int level = uniform_level(t, lower, opt_.quadrature);
      if (level > 0) level = uniform_level(t, std::max(distance_to_triangle(c, s) - t.radius, 0.0), opt_.quadrature);
      by_level[static_cast<size_t>(level)].push_back(&s);
      slot_of[static_cast<size_t>(level)].push_back(sources++);
    }
    unoccluded.resize(sources);
    thread_local std::vector<double> at_level;
    for (size_t level = 0; level < by_level.size(); ++level) {
      const auto& group = by_level[level];
      if (group.empty()) continue;
      at_level.resize(group.size());
      form_factors(uniform_points(t, static_cast<int>(level)), group.data(), group.size(), at_level.data());
      for (size_t i = 0; i < group.size(); ++i) unoccluded[slot_of[level][i]] = at_level[i];
    }
    size_t next = 0;
    for (size_t k = 0; k < path.size(); ++k) {
      const Link* l = path[k];
      if (l->visible <= 0.0) continue;  // hidden: kept as a link, never gathered
      if (l->source < 0) continue;      // a cluster: its receiver's node terms
      const double f0 = unoccluded[next++];
      // An ancestor's partly visible link that may matter here: the leaf's
      // own visible fraction.
      const bool own_rays =
          k >= own && l->visible < 1.0 && own_rays_matter(rho * f0 * max3(B_[static_cast<size_t>(l->source)]));
      // No shaft test: the ancestor's shaft holds an occluder, and on the
      // Cornell box 97% of the leaves' shafts did too (573 k pairs, 15 k
      // cleared); the tests cost more than the rays they saved.
      const double v = own_rays ? own_visible_fraction(static_cast<int>(x), l->source, leaf_rays_[x]) : l->visible;
      const double f = f0 * v;
      // The variance of the visible fraction the rays gave (binomial:
      // v (1 - v) over their number), as it enters the row. The rays are
      // weighed by their kernels (VisibilityEstimator), which makes them
      // count for fewer where the weights differ: not counted here.
      const int rays = own_rays ? own_side() * own_side() : opt_.rays;
      noise += f0 * f0 * v * (1.0 - v) / rays;
      // Rays that all got through say v = 1 and variance 0, yet the link
      // may be partly hidden (a small lamp between a floor and a ceiling):
      // half a ray of prior either way for the doubt (see scale_rows; a
      // link nothing could occlude, v = 1 without rays, is not told apart).
      const double vd = v < 1.0 ? v : (rays + 0.5) / (rays + 1.0);
      doubt += f0 * f0 * vd * (1.0 - vd) / rays;
      if (f <= 0.0) continue;
      terms_[x].push_back({l->slot, static_cast<float>(f)});
      F_sum_[x] += f;
    }
    F_noise_[x] = static_cast<float>(noise);
    F_doubt_[x] = static_cast<float>(doubt);
    double exact = 0.0;
    // Exactly the room they take: built by push_back, the lists held up to
    // twice that (0.8 GB more on the 64 x 64 box field's 214 M terms).
    terms_[x].shrink_to_fit();
    for (const Term& k : terms_[x]) exact += k.f;
    if (exact > 0.0) fix_exact_[x] = F_sum_[x] / exact;
  }

  // Node x's terms for the links it receives from clusters: per normal
  // group of the source, F at x's centroid, gathered once per sweep for all
  // the leaves below (node_H_). The oracle bounds the kernel's spread over
  // x for these links as for any other, so evaluating it at every leaf's
  // centroid instead bought nothing: on the 32 x 32 box field per-patch
  // errors against a fine solve were the same (median 0.605% against
  // 0.603%, 95th percentile 2.25% against 2.24%), the Cornell box's bench
  // figures equal to four digits, but each leaf held a term per group of
  // each of its ancestors' cluster links, half of all the terms there.
  void node_cluster_terms(size_t x) {
    auto& terms = node_terms_[x];
    terms.clear();
    node_F_[x] = 0.0;
    node_H_[x] = Rgb(0.0);  // gather_clusters sets it again while it has terms
    const Triangle& t = tri_[x];
    thread_local std::vector<std::pair<int, double>> found;
    for (const Link& l : links_[x]) {
      if (l.source >= 0 || l.visible <= 0.0) continue;
      found.clear();
      ct_.form_factors(cluster_of(l.source), t.centroid(), t.normal, l.visible, found, group_visible(l));
      for (const auto& [q, f] : found) {
        const float fs = static_cast<float>(f);
        terms.push_back({q, fs});
        node_F_[x] += fs;  // the floats' own sum: rows stay exact
      }
    }
    terms.shrink_to_fit();
  }

  // Per element link number: what its receiving leaves gather of it (area
  // x F). Made where it is read (leaf_terms, sent_rows) and not kept: 8
  // bytes a link held through the sweeps for nothing.
  std::vector<double> received_sums() const {
    std::vector<double> received(static_cast<size_t>(next_id_), 0.0);
    for (size_t x = 0; x < terms_.size(); ++x)
      for (const Term& t : terms_[x]) received[static_cast<size_t>(t.q)] += tri_[x].area * term_f(x, t);
    return received;
  }

  // Node y's sending weights: (link, A_y F(y -> receiver) x visibility,
  // the point form factor at y's centroid) over the element links it sends
  // for. A link's source sends through its descendants kSenderDepth levels
  // down (or its leaves above that): at most 16 pieces, enough to tell its
  // bright side from its dim one at a bounded cost per link. The weights
  // only share a link's transport out among its pieces (link_values), so
  // one point each does: on the Cornell box, full quadrature there gave the
  // same means to 0.01% and took 1.3x the solve time.
  void sender_terms(size_t y, const std::vector<int>& out_begin, const std::vector<std::pair<int, int>>& out) {
    auto& sent = sent_[y];
    sent.clear();
    const bool leaf = out_.tree.is_leaf(static_cast<int>(y));
    thread_local std::vector<std::pair<int, const Link*>> path;
    path.clear();
    for (int a = static_cast<int>(y), d = 0; a >= 0 && d <= kSenderDepth; a = out_.tree.node(a).parent, ++d)
      if (d == kSenderDepth || leaf)
        for (int k = out_begin[static_cast<size_t>(a)]; k < out_begin[static_cast<size_t>(a) + 1]; ++k) {
          const auto [p, at] = out[static_cast<size_t>(k)];
          path.emplace_back(p, &links_[static_cast<size_t>(p)][static_cast<size_t>(at)]);
        }
    if (path.empty()) return;
    const Triangle& t = tri_[y];
    // The point form factors from y's centroid to all the receivers in one
    // pass (the lists kept per thread: this runs once per node).
    thread_local ReceiverPoints at_c;
    thread_local std::vector<const Triangle*> receivers;
    thread_local std::vector<double> f;
    at_c.normal = t.normal;
    at_c.x.assign(1, t.centroid());
    at_c.w.assign(1, 1.0);
    receivers.clear();
    for (const auto& pl : path) receivers.push_back(&tri_[static_cast<size_t>(pl.first)]);
    f.resize(receivers.size());
    form_factors(at_c, receivers.data(), receivers.size(), f.data());
    // A piece shut in (the ceiling above a light hung under it sees only
    // the light's back) sends nothing: weighed by its openness, so that a
    // link from a node straddling it carries the radiosity of the part
    // that sends.
    if (node_open_[y] < 0.0f) node_open_[y] = static_cast<float>(openness_of(static_cast<int>(y)));
    for (size_t k = 0; k < path.size(); ++k) {
      // Over a partly visible link, the piece's own visible fraction to the
      // receiver where it could move what the link carries by more than
      // kLeafRaysBound x epsilon x rays_reference_ (rho_receiver F x the
      // piece's radiosity's difference from its source node's), with a
      // quarter of --rays, stratified, as a leaf casts on its ancestors'
      // links: the link's fraction is a mean over the source, and where the
      // bright part of the source is the hidden one (a wall lit by a lamp
      // 10 cm in front of it, which the lamp's back hides from the room)
      // weighing the pieces alike sent the room that bright part: every
      // surface 18-23% too bright against a fine matrix solve, 3.7% of the
      // emitted power made. The rays add 0.5% to the 8 x 8 box field's.
      const Link& l = *path[k].second;
      const int p = path[k].first;
      const bool own_rays =
          l.visible < 1.0 && own_rays_matter(max3(rho_[static_cast<size_t>(p)]) * l.f *
                                             max3(glm::abs(B_[y] - B_[static_cast<size_t>(l.source)])));
      const double v = own_rays ? own_visible_fraction(static_cast<int>(y), p, leaf_rays_[y]) : l.visible;
      const float w = static_cast<float>(t.area * f[k] * v) * node_open_[y];
      if (w > 0.0f) sent.push_back({l.slot, w});
    }
    sent.shrink_to_fit();
  }

  // Every element link's source value from its sending leaves (sent_):
  // the mean of their radiosity weighted by what each sends over the link.
  void link_values() {
    link_value_.assign(static_cast<size_t>(next_id_), Rgb(0.0));
    for (size_t y = 0; y < sent_.size(); ++y)
      for (const auto& [id, w] : sent_[y])
        link_value_[static_cast<size_t>(id)] += (w * inv_sent_[static_cast<size_t>(id)]) * B_[y];
  }

  // Gauss-Seidel sweeps in tree order: leaves gather (see leaf_terms),
  // inner nodes take the area-weighted mean of their children (pull), until
  // the largest change is below the tolerance times the largest radiosity.
  void solve() {
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

  Rgb pull(int p, double& change, double& top) {
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

  // The deepest node that existed in the previous round on the path to n.
  int nearest_old(int n, size_t old_count) const {
    while (n >= 0 && static_cast<size_t>(n) >= old_count) n = out_.tree.node(n).parent;
    return n;
  }

  // Fills the output: conforming mesh, per-triangle values, vertex values,
  // counts and the energy balance.
  void publish() {
    publish_mesh();
    publish_balance();
  }
  // The conforming mesh, its per-triangle values, vertex values and counts
  // (the solution's statistics are kept).
  void publish_mesh() {
    HierarchicalSolution& o = out_;
    o.node_radiosity = B_;
    o.node_links.assign(links_.size(), 0);
    for (size_t p = 0; p < links_.size(); ++p) o.node_links[p] = static_cast<int>(links_[p].size());
    o.mesh = o.tree.conforming_mesh(&o.leaf_of);
    Solution& s = o.solution;
    s.element.assign(o.leaf_of.size(), Rgb(0.0));
    // A zero-area triangle takes the value of the leaf whose edge it closes:
    // the leaf emitted just before its fan.
    int owner = -1;
    o.stats.leaves = 0;
    o.stats.zero_area_triangles = 0;
    for (size_t t = 0; t < o.leaf_of.size(); ++t) {
      if (o.leaf_of[t] >= 0) {
        owner = o.leaf_of[t];
        ++o.stats.leaves;
      } else {
        ++o.stats.zero_area_triangles;
      }
      s.element[t] = B_[static_cast<size_t>(owner)];
    }
    // Vertex values on the conforming mesh: the zero-area fans join the two
    // sides of every unsplit edge (so a vertex is not split into several
    // display vertices there) and, having no area, add nothing to a fit or a
    // mean. A T-vertex thus gets the value the finer side gives it.
    s.nodal = compute_nodal(scene_, o.mesh, s.element, opt_.crease_angle, nodal_method(opt_.field));
    // Leaf edges: directed edge (u, w) -> leaf triangle. The finer side of an
    // unsplit edge (a, b) of leaf t holds its pieces reversed.
    const FeatureEdges features(o.mesh);
    std::unordered_map<uint64_t, int> edge_of;
    edge_of.reserve(3 * o.leaf_of.size());
    auto key = [](int u, int w) { return (static_cast<uint64_t>(static_cast<uint32_t>(u)) << 32) | static_cast<uint32_t>(w); };
    for (size_t t = 0; t < o.leaf_of.size(); ++t)
      if (o.leaf_of[t] >= 0)
        for (int k = 0; k < 3; ++k)
          edge_of[key(o.mesh.triangles[t][static_cast<size_t>(k)], o.mesh.triangles[t][static_cast<size_t>((k + 1) % 3)])] =
              static_cast<int>(t);
    auto display_in = [&](int t, int v) {  // display vertex of mesh vertex v in triangle t
      for (int j = 0; j < 3; ++j)
        if (o.mesh.triangles[static_cast<size_t>(t)][static_cast<size_t>(j)] == v)
          return s.nodal.corners[static_cast<size_t>(t)][static_cast<size_t>(j)];
      return -1;
    };
    // T-vertices: the jump `free` leaves, and anchoring to the unsplit edge.
    // Along the unsplit edge (a, b) of leaf t lie a, m_1 .. m_k, b; each
    // piece between two of them is an edge of a finer leaf across. Where the
    // edge is smooth (the leaves across share t's display vertices at a and
    // b: no contact line or crease along it), the display vertices of the m_i
    // take the edge's interpolant (anchor); the difference is the jump free
    // leaves. Coarser leaves first, so that an edge whose end is itself a
    // T-vertex of a longer edge interpolates the end's anchored value.
    o.stats.max_tvertex_jump = 0.0;
    double top = 0.0;
    for (const Rgb& b : s.nodal.radiosity) top = std::max(top, max3(b));
    const std::vector<Rgb> free_values = s.nodal.radiosity;
    std::vector<int> order;
    for (size_t t = 0; t < o.leaf_of.size(); ++t)
      if (o.leaf_of[t] >= 0) order.push_back(static_cast<int>(t));
    std::stable_sort(order.begin(), order.end(), [&](int x, int y) {
      return o.tree.node(o.leaf_of[static_cast<size_t>(x)]).level < o.tree.node(o.leaf_of[static_cast<size_t>(y)]).level;
    });
    for (int t : order) {
      const auto& tri = o.mesh.triangles[static_cast<size_t>(t)];
      for (int k = 0; k < 3; ++k) {
        const int a = tri[static_cast<size_t>(k)], b = tri[static_cast<size_t>((k + 1) % 3)];
        std::vector<int> chain = o.tree.edge_points(a, b, o.tree.node(o.leaf_of[static_cast<size_t>(t)]).root);
        if (chain.empty()) continue;
        chain.insert(chain.begin(), a);
        chain.push_back(b);
        const int da = s.nodal.corners[static_cast<size_t>(t)][static_cast<size_t>(k)];
        const int db = s.nodal.corners[static_cast<size_t>(t)][static_cast<size_t>((k + 1) % 3)];
        std::vector<int> across;
        for (size_t i = 0; i + 1 < chain.size(); ++i) {
          const auto it = edge_of.find(key(chain[i + 1], chain[i]));
          if (it == edge_of.end()) break;
          across.push_back(it->second);
        }
        bool feature = false;  // a contact line along the edge: the value may jump there
        for (size_t i = 0; i + 1 < chain.size() && !feature; ++i)
          feature = features.contains(chain[i], chain[i + 1]);
        if (feature || across.size() + 1 != chain.size() || display_in(across.front(), a) != da ||
            display_in(across.back(), b) != db)
          continue;
        const Vec3 A = o.mesh.positions[static_cast<size_t>(a)], B = o.mesh.positions[static_cast<size_t>(b)];
        for (size_t i = 1; i + 1 < chain.size(); ++i) {
          const double u =
              glm::dot(o.mesh.positions[static_cast<size_t>(chain[i])] - A, B - A) / glm::dot(B - A, B - A);
          const Rgb free_interp = (1.0 - u) * free_values[static_cast<size_t>(da)] + u * free_values[static_cast<size_t>(db)];
          const Rgb anchored = (1.0 - u) * s.nodal.radiosity[static_cast<size_t>(da)] + u * s.nodal.radiosity[static_cast<size_t>(db)];
          for (int f : {across[i - 1], across[i]}) {
            const int dm = display_in(f, chain[i]);
            if (top > 0.0)
              o.stats.max_tvertex_jump = std::max(
                  o.stats.max_tvertex_jump, max3(glm::abs(free_values[static_cast<size_t>(dm)] - free_interp)) / top);
            if (hopt_.tvertex == TVertexMode::anchor) s.nodal.radiosity[static_cast<size_t>(dm)] = anchored;
          }
        }
      }
    }
  }
  // Row sums, energy balance and the residual of the leaf equations
  // B = E + rho H over the leaves (H gathered after the last sweep), and the
  // solver's statistics.
  void publish_balance() {
    HierarchicalSolution& o = out_;
    SolveStats& st = o.solution.stats;
    st = SolveStats{};
    st.elements = o.stats.leaves;
    o.stats.row_sum_min = 1e300;
    o.stats.row_sum_max = -1e300;
    BalanceAccumulator balance;
    const std::vector<double> sending = sent_rows();
    for (size_t p = 0; p < B_.size(); ++p) {
      if (!o.tree.is_leaf(static_cast<int>(p))) continue;
      o.stats.row_sum_min = std::min(o.stats.row_sum_min, row_sum(p));
      o.stats.row_sum_max = std::max(o.stats.row_sum_max, row_sum(p));
      balance.add(tri_[p].area, rho_[p], emit_[p], B_[p], H_[p], row_sum(p), sending[p]);
    }
    balance.finish(st);
    st.extrapolations = extrapolations_;
    st.rays_cast = o.stats.rays_cast;
    st.rays_skipped = o.stats.rays_skipped;
    st.pairs_unoccludable = o.stats.pairs_unoccludable;
    st.convex_enclosure = visibility_.convex_enclosure();
    st.warnings = enclosed_warnings_;
    o.stats.clusters = static_cast<int>(ct_.size());
    o.stats.cluster_groups = static_cast<int>(ct_.group_count());
    o.stats.cluster_links = 0;
    for (const auto& l : clinks_) o.stats.cluster_links += static_cast<long long>(l.size());
    for (const auto& l : links_)
      for (const Link& k : l) o.stats.cluster_links += k.source < 0 ? 1 : 0;
    st.form_factors = count_links();
    st.seconds_form_factors = o.stats.seconds_link;
    st.seconds_solve = o.stats.seconds_solve;
    report_visibility_skips(st, "node");
    report_left();
  }

  // Per leaf, the fraction of its radiosity x area the solve carries to
  // other leaves: what the receivers gather of each value that reads it
  // (area x F), shared out as that value weighs the leaf. An element link's
  // value weighs its sending pieces by sent_ and a piece's leaves by area;
  // an element node's mean (toward a receiving group) and a group's mean
  // (toward a leaf or group) weigh their leaves by area. Every unit of
  // power a leaf gathers is thus taken from some leaf's radiosity, and the
  // energy balance, taking a leaf's escaped power from this row, closes up
  // to the sweeps' tolerance: what the approximations get wrong shows as
  // power escaped (or gained) in a closed scene, not as imbalance.
  std::vector<double> sent_rows() const {
    const ElementTree& tree = out_.tree;
    const size_t n = B_.size();
    std::vector<double> by_node(n, 0.0), by_group(ct_.group_count(), 0.0);
    if (!ct_.empty()) {
      // A group's receiving area per direction bin: its leaves' area x row
      // scale x their root's share weight in the bin (its openness with one
      // bin), with its descendants' (parents have the larger group
      // numbers); over the group's mean weight where it is used.
      std::vector<double> receiving(ct_.group_count() * bins_, 0.0);
      // A node's receiving area for its node terms: its leaves' area x row scale.
      std::vector<double> node_receiving(n, 0.0);
      for (size_t x = 0; x < n; ++x) {
        if (!tree.is_leaf(static_cast<int>(x))) continue;
        const int root = tree.node(static_cast<int>(x)).root;
        const int g = ct_.root_group(root);
        if (g >= 0)
          for (int k = 0; k < bins_; ++k) receiving[bin_index(g, k)] += tri_[x].area * row_scale_[x] * seen_open(root, k);
        for (int a = static_cast<int>(x); a >= 0; a = tree.node(a).parent)
          if (!node_terms_[static_cast<size_t>(a)].empty()) node_receiving[static_cast<size_t>(a)] += tri_[x].area * row_scale_[x];
      }
      for (int a : node_gatherers_)
        for (const Term& t : node_terms_[static_cast<size_t>(a)])
          by_group[static_cast<size_t>(-2 - t.q)] += node_receiving[static_cast<size_t>(a)] * t.f / sending_area(-2 - t.q);
      for (size_t g = 0; g < ct_.group_count(); ++g) {
        const int up = ct_.group(static_cast<int>(g)).up;
        if (up >= 0)
          for (int k = 0; k < bins_; ++k) receiving[bin_index(up, k)] += receiving[bin_index(static_cast<int>(g), k)];
      }
      for (size_t g = 0; g < gterms_.size(); ++g)
        for (const GroupTerm& t : gterms_[g]) {
          const int q = t.q();
          const size_t b = bin_index(static_cast<int>(g), t.bin());
          const double received = receiving[b] * per_open(b) * t.f;
          if (q >= 0)
            by_node[static_cast<size_t>(q)] += received / tri_[static_cast<size_t>(q)].area;
          else
            by_group[static_cast<size_t>(-2 - q)] += received / sending_area(-2 - q);
        }
    }
    const std::vector<double> received = received_sums();
    for (size_t c = 0; c < n; ++c)
      for (const auto& [id, w] : sent_[c])
        by_node[c] += received[static_cast<size_t>(id)] * w * inv_sent_[static_cast<size_t>(id)] / tri_[c].area;
    std::vector<double> row(n, 0.0);
    for (size_t y = 0; y < n; ++y) {
      if (!tree.is_leaf(static_cast<int>(y))) continue;
      double r = 0.0;
      for (int a = static_cast<int>(y); a >= 0; a = tree.node(a).parent) r += by_node[static_cast<size_t>(a)];
      if (!ct_.empty()) {
        const int root = tree.node(static_cast<int>(y)).root;
        for (int g = ct_.root_group(root); g >= 0; g = ct_.group(g).up)
          r += by_group[static_cast<size_t>(g)] * (group_open_[static_cast<size_t>(g)] > 0.0 ? open_[static_cast<size_t>(root)] : 1.0);
      }
      row[y] = r;
    }
    return row;
  }

  // ---------------------------------------------------------------- clusters
  // ClusterMode volume or shape: the cluster tree above the roots (clusters.h). A
  // link has a node code at each end: an element node (>= 0) or a cluster
  // (cluster_code(c) <= -2). A link from a cluster is gathered per group of
  // the source; a cluster receives per group of its own (at the group's
  // centroid, with s / area as its normal), and what a group gathers is
  // pushed down to every leaf below it (through the group its root belongs to).
  //
  // Cluster links need a gap between the two bounding spheres of at least
  // this fraction of the larger radius; nearer pairs are split.
  static constexpr double kClusterGap = 1.0;

  // A cluster of at most this many roots is small and never ends a link:
  // a link the oracle would make there is split down to its elements,
  // whose links have exact form factors and their own visibility. Only big
  // clusters, which the gap rule keeps far away, are approximated. With
  // `volume` clusters, unless its roots are at the links' floor already (on
  // average too small to be split, as the triangles of a scanned or finely
  // tessellated object are): then its elements' links are no finer than
  // the cluster's, and splitting it only multiplies them (on the bunny room
  // 4.1 M links between bunny triangles, half the run). `shape` keeps the
  // rule for every small cluster: its small clusters of sphere triangles
  // left a sphere 9% dark (test FewerLinksSameObjectMeansAndEnergyInAClosedRoom).
  static constexpr int kSmallCluster = 16;
  bool small_code(int code) const {
    if (code >= 0) return false;
    const int members = ct_.members(cluster_of(code));
    if (members > kSmallCluster) return false;
    return !fine_small_clusters_end_links_ || code_area(code) > kSplittableArea * min_area_ * members;
  }

  static constexpr int cluster_code(int c) { return ClusterTree::code(c); }
  static constexpr int cluster_of(int code) { return ClusterTree::index(code); }

  // Radiosity of a term's source: an element node, or a group (-2 - g).
  Rgb value(int code) const { return code >= 0 ? B_[static_cast<size_t>(code)] : GB_[static_cast<size_t>(-2 - code)]; }
  // What cluster links give a leaf: the pushed gathering of the group its
  // root belongs to, and that group's form factors.
  Rgb pushed(int leaf) const {
    if (ct_.empty()) return Rgb(0.0);
    const int r = out_.tree.node(leaf).root;
    const int g = ct_.root_group(r);
    Rgb h(0.0);
    if (g >= 0)
      for (int k = 0; k < bins_; ++k) h += seen_open(r, k) * HGacc_[bin_index(g, k)];
    return h;
  }
  // What a leaf gathers: its exact terms (element links), then its
  // approximate part (what the nodes on its path gathered from big
  // clusters' groups, node_H_, and what its root's groups push down)
  // scaled by row_scale_.
  Rgb gathered(size_t leaf) const {
    Rgb exact(0.0), approx(0.0);
    for (const Term& t : terms_[leaf]) exact += static_cast<double>(t.f) * link_value_[static_cast<size_t>(t.q)];
    for (int a = static_cast<int>(leaf); a >= 0; a = out_.tree.node(a).parent) approx += node_H_[static_cast<size_t>(a)];
    return fix_exact_[leaf] * exact_scale_[leaf] * exact + row_scale_[leaf] * (approx + pushed(static_cast<int>(leaf)));
  }
  // The approximate part of a leaf's form factors, before row_scale_.
  double approx_row_sum(size_t leaf) const {
    double f = F_approx_[leaf];
    if (!ct_.empty()) {
      const int r = out_.tree.node(static_cast<int>(leaf)).root;
      const int g = ct_.root_group(r);
      if (g >= 0)
        for (int k = 0; k < bins_; ++k) f += seen_open(r, k) * FGacc_[bin_index(g, k)];
    }
    return f;
  }
  double row_sum(size_t leaf) const {
    return exact_scale_[leaf] * F_sum_[leaf] + row_scale_[leaf] * approx_row_sum(leaf);
  }

  // How much of leaf x's approximate part the leaf's own samples confirm,
  // as a ratio to what its terms say (their lower bound: the mean less two
  // standard errors, at least 0); -1 when it has no such term. kApproxRays
  // point pairs between the leaf and its terms' sources: a term drawn by
  // the light it brings (F x its source's radiosity, or F alone while that
  // is 0 everywhere), a point of the source by area, and each pair counts
  // the source's area x the point kernel x the segment's visibility over
  // the term's F.
  static constexpr int kApproxRays = 16;
  double approx_confirmed(size_t x) const {
    thread_local std::vector<std::pair<int, double>> src;  // (source code, F)
    src.clear();
    double light = 0.0, form = 0.0;
    auto add = [&](int q, double f) {
      if (!(f > 0.0)) return;
      src.emplace_back(q, f);
      form += f;
      light += f * max3(value(q));
    };
    for (int a = static_cast<int>(x); a >= 0; a = out_.tree.node(a).parent)
      for (const Term& t : node_terms_[static_cast<size_t>(a)]) add(t.q, t.f);
    const int r = out_.tree.node(static_cast<int>(x)).root;
    for (int g = ct_.root_group(r); g >= 0; g = ct_.group(g).up)
      for (const GroupTerm& t : gterms_[static_cast<size_t>(g)])
        add(t.q(), t.f * per_open(bin_index(g, t.bin())) * seen_open(r, t.bin()));
    if (src.empty()) return -1.0;
    const bool by_light = light > 0.0;
    auto weight = [&](size_t j) { return by_light ? src[j].second * max3(value(src[j].first)) : src[j].second; };
    const double total = by_light ? light : form;
    const Triangle& t = tri_[x];
    SplitMix rng(pair_seed(static_cast<uint64_t>(x), 0xA9905EE5ULL));
    double sum = 0.0, squares = 0.0;
    size_t i = 0;
    double below = 0.0;  // the weight of src[0 .. i)
    for (int k = 0; k < kApproxRays; ++k) {
      const double u = (k + rng.uniform()) / kApproxRays * total;
      while (i + 1 < src.size() && below + weight(i) <= u) below += weight(i++);
      const int q = src[i].first;
      const int node = q >= 0 ? q : ct_.root_at_area(-2 - q, rng.uniform());
      const double area = q >= 0 ? tri_[static_cast<size_t>(q)].area : ct_.group(-2 - q).area;
      const Triangle& s = tri_[static_cast<size_t>(node)];
      const double a = rng.uniform(), b = rng.uniform(), c = rng.uniform(), d = rng.uniform();
      const Vec3 from = triangle_point(t.v[0], t.v[1], t.v[2], a, b);
      const Vec3 to = triangle_point(s.v[0], s.v[1], s.v[2], c, d);
      const double kernel = point_kernel(from, t.normal, to, s.normal) / std::numbers::pi;
      if (!(kernel > 0.0) ||
          !visibility_.rays().visible_off_surfaces(from, t.normal, to, s.normal, node_patch(static_cast<int>(x)),
                                                   node_patch(node)))
        continue;
      const double z = area * kernel / src[i].second;
      sum += z;
      squares += z * z;
    }
    const double mean = sum / kApproxRays;
    const double variance = std::max(0.0, squares / kApproxRays - mean * mean) / (kApproxRays - 1);
    return std::max(0.0, mean - 2.0 * std::sqrt(variance));
  }

  // The cluster approximations keep a row near 1, not at 1; its exact
  // terms are left as they are, and its approximate part is scaled. Per
  // leaf with an approximate part, Visibility::enclosed's cosine-
  // distributed rays from its centroid: when every one meets the front of
  // a patch, the leaf is enclosed (nothing it sees is open sky or the back
  // of a one-sided patch) and the approximate part is scaled so that the
  // row sums to 1; otherwise it is scaled only where the row exceeds 1 (no
  // leaf sees more than its hemisphere), down to 1. The furnace stays
  // exact with clusters, and rho x row sum stays below 1 for reflectance
  // near 1. The scale is kept within [0, kMaxRowScale]: the gap rule keeps
  // the group kernel's error well under 20%, so a larger deficit lies
  // elsewhere (the exact terms' visibility) and is not the approximate
  // part's to fill (with a cap of 4, a ceiling lit only indirectly came
  // out 2.7% high against a finer solve; with 1.2, every object of that
  // room within 0.6%). But a leaf whose approximate part is small next to
  // its partly visible exact terms (a wall seeing a bulb of small sphere
  // triangles through cluster links) misses 1 mostly by what the shadow
  // rays got wrong (a small occluder's shadow under-sampled), and scaling
  // the approximate part for it moved the bulb's light by -63% to +20% per
  // leaf: 4.4% of its power escaped the closed room, every surface 3% dark.
  // So the exact terms take the miss up to what their rays may be off by
  // (kRowTolerance), scaled by exact_scale_, and the approximate part the
  // rest; the row still sums to 1, so the energy and reflectance near 1 stay
  // as they were (a bulb room with walls of 0.999: within 0.14% of the
  // matrix method, 0.7% low before). Where nothing occludes (a convex
  // enclosure) the exact terms are off by their quadrature alone (each
  // source at its own points, gather_terms): the approximate part takes
  // the miss with its own, and a leaf without one scales its exact terms
  // by it, up to kRowTolerance, so that the furnace stays exact. Outside
  // such an enclosure a leaf without an approximate part is left as it is:
  // scaling its exact terms toward 1 wherever the leaf is enclosed took the
  // Cornell box's worst patch mean from 0.46% to 0.63%. Scaling the partly
  // visible links' terms too (their fractions come from rays) made a
  // closed furnace with a floating block uniform (leaf values 4.987-5.005
  // against 4.95-5.16, exact 5), but lit
  // rooms came out further from their 128-ray solves than without: the
  // sphere room's ceiling +0.43% (+0.04%), the 8 x 8 box field's patches
  // 0.35% rms (0.25%). Not kept. Part of what it filled is likely
  // absorbed light (the lamp's back, seen from the ceiling, which 64 rays
  // can miss); the box faces' excess was not traced.
  // A row over 1 by more than that has two readings. The approximate part
  // may overstate what the leaf gets (a leaf in a narrow gap reached by a
  // cluster link as if as open as its cluster); or the exact terms may,
  // through links whose rays all got through though something small hides
  // part of them (a floor leaf seeing a lamp 10 cm under the ceiling by
  // cluster links, and the ceiling, a sliver of which the lamp hides, by
  // element links): there cutting the approximate part cut the lamp's
  // light, and 2.4% of its power escaped a closed room, every surface
  // 0.9-1.9% dark against the matrix method. So the leaf's own samples of
  // its approximate sources (approx_confirmed) tell them apart: the
  // approximate part gives what they say it overstates, the exact terms
  // then up to their doubt (F_doubt_: half a ray of prior on the links
  // whose rays all got through), and the approximate part the rest.
  static constexpr double kMaxRowScale = 1.2;
  // What the exact terms take of a row's miss: up to what their shadow rays
  // may be off by (3 standard deviations of the binomial estimates, F_noise_)
  // plus this for their quadrature.
  static constexpr double kRowTolerance = 5e-4;
  bool enclosed(size_t leaf) const {
    const Triangle& t = tri_[leaf];
    return visibility_.rays().enclosed(t.centroid(), t.normal, node_patch(static_cast<int>(leaf)),
                                       pair_seed(static_cast<uint64_t>(leaf), 0xE17C105EULL));
  }
  void scale_rows() {
    const size_t n = B_.size();
    row_scale_.resize(n, 1.0);
    exact_scale_.resize(n, 1.0);
    enclosed_.resize(n, -1);
    const bool convex = visibility_.convex_enclosure();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 64), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t x = r.begin(); x != r.end(); ++x) {
        row_scale_[x] = 1.0;
        exact_scale_[x] = 1.0;
        if (!out_.tree.is_leaf(static_cast<int>(x))) continue;
        const double approx = approx_row_sum(x);
        if (!(approx > 0.0) && !(convex && F_sum_[x] > 0.0)) continue;
        if (enclosed_[x] < 0) enclosed_[x] = enclosed(x) ? 1 : 0;
        const double row = F_sum_[x] + approx;
        if (enclosed_[x] != 1 && row <= 1.0) continue;
        const double miss = 1.0 - row;
        double exact_miss = 0.0;  // the exact terms' share
        if (convex) {
          if (!(approx > 0.0)) exact_miss = std::clamp(miss, -kRowTolerance, kRowTolerance);
        } else if (F_sum_[x] > 0.0) {
          double rays_off = kRowTolerance + 3.0 * std::sqrt(static_cast<double>(F_noise_[x]));
          if (miss < -rays_off) {
            // Over 1 by more than the exact terms' rays explain: the
            // approximate part gives first what the leaf's own samples say
            // it overstates, the exact terms then up to what rays that all
            // got through may have missed (F_doubt_), the approximate part
            // the rest.
            const double over = -miss;
            const double confirmed = approx_confirmed(x);
            const double overstated =
                confirmed >= 0.0 ? std::min(over, approx * std::max(0.0, 1.0 - confirmed)) : over;
            const double doubt = kRowTolerance + 3.0 * std::sqrt(static_cast<double>(F_doubt_[x]));
            rays_off = std::max(rays_off, std::min(over - overstated, doubt));
          }
          exact_miss = std::clamp(miss, -rays_off, rays_off);
        }
        if (F_sum_[x] > 0.0) exact_scale_[x] = 1.0 + exact_miss / F_sum_[x];
        if (approx > 0.0) row_scale_[x] = std::clamp(1.0 + (miss - exact_miss) / approx, 0.0, kMaxRowScale);
      }
    });
  }

  Vec3 code_centre(int code) const {
    return code >= 0 ? tri_[static_cast<size_t>(code)].centroid() : ct_.cluster(cluster_of(code)).centre;
  }
  double code_radius(int code) const {
    return code >= 0 ? tri_[static_cast<size_t>(code)].radius : ct_.cluster(cluster_of(code)).radius;
  }
  // The oracle's weight for receiver `code`. Below the links' floor
  // (min_area_: refinement makes no receiver smaller, so only input
  // triangles and clusters of them are) a receiver's error counts by its
  // share of the floor's area: the pieces of a floor-sized area answer
  // together for what one receiver of that size would, and an input mesh
  // finer than the floor multiplies the links far less (the bunny room
  // with its bunny cut into 4 x its 3,674 triangles: 10.2 M -> 6.6 M links;
  // into 16 x: 32 M -> 15 M). Then HierarchicalOptions::area_weight.
  double pw(int code) const {
    const double a = code_area(code);
    double w = a < min_area_ ? a / min_area_ : 1.0;
    if (hopt_.area_weight > 0.0 && a < mean_root_area_)
      w = std::min(w, std::pow(a / mean_root_area_, hopt_.area_weight));
    return w;
  }
  double code_area(int code) const {
    return code >= 0 ? tri_[static_cast<size_t>(code)].area : ct_.cluster(cluster_of(code)).area;
  }
  // The reflectance the cluster oracle weighs a receiver's error by: its
  // largest channel, but 1 for an emitter (an emitter reflects little, yet
  // its row says where its power goes in the energy balance); a cluster's
  // largest over its members.
  double element_oracle_rho(size_t e) const {
    return max3(emit_[e]) > 0.0 ? 1.0 : max3(rho_[e]);
  }
  double code_rho(int code) const {
    return code >= 0 ? element_oracle_rho(static_cast<size_t>(code)) : ct_.cluster(cluster_of(code)).weight;
  }
  // The mean radiosity (largest channel) of a node: its power per area.
  double code_radiosity(int code) const {
    return max3(code >= 0 ? B_[static_cast<size_t>(code)] : ct_.mean(cluster_of(code), GB_));
  }
  uint64_t code_key(int code) const {
    return code >= 0 ? static_cast<uint64_t>(code) : (uint64_t{1} << 40) + static_cast<uint64_t>(cluster_of(code));
  }

  void build_clusters() {
    const int roots = out_.tree.root_count();
    // Refused before any work when the clusters alone would not fit (at
    // least one group per cluster).
    bins_ = hopt_.clusters == ClusterMode::shape ? kDirectionBins : 1;
    fine_small_clusters_end_links_ = hopt_.clusters == ClusterMode::volume;
    const double need = ClusterTree::bytes(roots - 1.0, roots - 1.0) + bin_bytes(roots - 1.0, roots);
    if (held_before_ + need > limit_)
      throw NumericalError(scene_.source + ": the " + std::to_string(roots - 1) + " clusters above " +
                           std::to_string(roots) + " initial elements need " + format_number(need / kGiB) +
                           " GiB at least" + held_text() + ", more than the " + format_number(limit_ / kGiB) +
                           " GiB allowed; use a larger max_edge (hierarchical radiosity refines by itself) or "
                           "raise max_memory",
                           {"max_edge", "max_memory"});
    std::vector<double> weight(static_cast<size_t>(roots));
    for (int r = 0; r < roots; ++r) weight[static_cast<size_t>(r)] = element_oracle_rho(static_cast<size_t>(r));
    const std::vector<Triangle> root_triangles(tri_.begin(), tri_.begin() + roots);
    ct_ = hopt_.clusters == ClusterMode::shape ? ClusterTree::shape(root_triangles, weight)
                                               : ClusterTree::volume(root_triangles, weight);
    root_samples_.resize(static_cast<size_t>(roots));
    for (int i = 0; i < roots; ++i) {
      const int r = ct_.root_at(i);
      const Triangle& t = tri_[static_cast<size_t>(r)];
      root_samples_[static_cast<size_t>(i)] = {t.v, t.normal, node_patch(r), r};
    }
    const size_t groups = ct_.group_count();
    clinks_.assign(ct_.size(), {});
    HG_.assign(groups * bins_, Rgb(0.0));
    HGacc_.assign(groups * bins_, Rgb(0.0));
    FG_.assign(groups * bins_, 0.0);
    FGacc_.assign(groups * bins_, 0.0);
    gterms_.assign(groups, {});
    openness();
    update_groups();
  }

  // What a receiving group gathers is shared among its members' roots in
  // proportion to their openness o: the fraction of their hemisphere (16
  // cosine-distributed rays from stratified points of the root) that is
  // not shut in, the ray meeting nothing or the front of a patch. A group
  // gathers at its centroid through its mean visibility, so without this
  // every member got the same: in a closed room of 16 x 16 boxes the floor
  // under the boxes (every ray meets a box from inside) was lit like the
  // floor between them, 1.7% of the emitted power escaped the closed room
  // (0.5% without clusters), and the floor and boxes between needed their
  // approximate rows scaled up 1.4 to 2.1 times where the scale stops at
  // kMaxRowScale. A root's share of group g's light is o / (the area mean
  // of o over g's roots), which keeps what g gathers in all; a group
  // whose roots are all shut in gathers nothing.
  //
  // With `shape` clusters, the seed's local visibility per direction: a
  // group's gathering is kept per direction bin (kDirectionBins, the
  // faces of a cube: the bin of the direction from the group's centroid
  // to the source) and shared by each root's visibility in that bin
  // (openness_of: its rays that also meet nothing among its siblings),
  // over the group's mean. In the seed's hierarchy a box hangs under the
  // floor triangle it stands on, so the boxes' tops and the floor between
  // them, which the boxes shadow, are one group: on a 16 x 16 box field
  // the tops came out 7.3% below a fine solve, 0.7% with the bins. With
  // `volume` clusters the same sharing made the box field worse (the
  // boxes 0.66% -> 1.12% low, more power escaping): one bin, openness
  // alone.
  static constexpr int kOpennessRays = 16;
  static constexpr int kDirectionBins = 6;
  void openness() {
    const int roots = out_.tree.root_count();
    open_.assign(static_cast<size_t>(roots), 1.0);
    seen_open_.assign(static_cast<size_t>(roots) * bins_, 1.0f);
    // A root's siblings: what lies within the radius of the smallest
    // cluster above it that may end a link.
    std::vector<double> reach(bins_ > 1 ? static_cast<size_t>(roots) : 0, 0.0);
    if (bins_ > 1)
      for (size_t c = 0; c < ct_.size(); ++c) {
        const ClusterTree::Cluster& cl = ct_.cluster(static_cast<int>(c));
        if (small_code(cluster_code(static_cast<int>(c)))) continue;
        for (int i = cl.begin; i < cl.end; ++i) reach[static_cast<size_t>(ct_.root_at(i))] = cl.radius;
      }
    tbb::parallel_for(tbb::blocked_range<int>(0, roots, 64), [&](const tbb::blocked_range<int>& range) {
      for (int r = range.begin(); r != range.end(); ++r) {
        const size_t i = static_cast<size_t>(r);
        if (bins_ > 1)
          open_[i] = openness_of(r, reach[i], &seen_open_[bin_index(r, 0)]);
        else
          seen_open_[i] = static_cast<float>(open_[i] = openness_of(r));
      }
    });
    // The roots' sending weights take the same values (sender_terms).
    node_open_.resize(std::max(node_open_.size(), static_cast<size_t>(roots)), -1.0f);
    for (int r = 0; r < roots; ++r) node_open_[static_cast<size_t>(r)] = static_cast<float>(open_[static_cast<size_t>(r)]);
    // Per group, the area mean of its roots' openness (a root counts for
    // every group above its own), and of their visibility per bin.
    const size_t groups = ct_.group_count();
    std::vector<double> sum(groups, 0.0), area(groups, 0.0), seen(groups * bins_, 0.0);
    for (int r = 0; r < roots; ++r) {
      const double a = tri_[static_cast<size_t>(r)].area;
      for (int g = ct_.root_group(r); g >= 0; g = ct_.group(g).up) {
        sum[static_cast<size_t>(g)] += a * open_[static_cast<size_t>(r)];
        area[static_cast<size_t>(g)] += a;
        for (int k = 0; k < bins_; ++k) seen[bin_index(g, k)] += a * seen_open(r, k);
      }
    }
    group_open_.assign(groups, 0.0);
    group_seen_.assign(groups * bins_, 0.0);
    for (size_t g = 0; g < groups; ++g) {
      if (!(area[g] > 0.0)) continue;
      group_open_[g] = sum[g] / area[g];
      for (int k = 0; k < bins_; ++k) group_seen_[bin_index(static_cast<int>(g), k)] = seen[bin_index(static_cast<int>(g), k)] / area[g];
    }
  }
  // The direction bin of d: the axis and sign of its largest component.
  static int direction_bin(const Vec3& d) {
    const Vec3 a = glm::abs(d);
    const int axis = a.x >= a.y && a.x >= a.z ? 0 : (a.y >= a.z ? 1 : 2);
    return 2 * axis + (d[axis] > 0.0 ? 1 : 0);
  }
  // Entry (i, bin k) of a per-root or per-group array of bins_ per item.
  size_t bin_index(int i, int k) const { return static_cast<size_t>(i) * static_cast<size_t>(bins_) + static_cast<size_t>(k); }
  // Root r's share weight for light from bin k (its openness with one bin).
  double seen_open(int r, int k) const { return seen_open_[bin_index(r, k)]; }
  // The openness of node m (see openness()). With `bins` (kDirectionBins
  // of them, `shape` clusters), also its visibility per direction bin: of
  // its rays in the bin, the fraction that are open and meet nothing within
  // `reach` (its siblings); its fraction over all the rays counts as one
  // more ray of every bin, so a bin with no ray takes that.
  double openness_of(int m, double reach = 0.0, float* bins = nullptr) const {
    if (visibility_.convex_enclosure()) {
      if (bins) std::fill(bins, bins + kDirectionBins, 1.0f);
      return 1.0;
    }
    const Triangle& t = tri_[static_cast<size_t>(m)];
    const CosineHemisphere h(t.normal);
    SplitMix rng(pair_seed(static_cast<uint64_t>(m), 0x0BE11E55ULL));
    constexpr int side = 4;
    static_assert(side * side == kOpennessRays);
    int open = 0, seen = 0;
    std::array<int, kDirectionBins> rays{}, through{};
    for (int k = 0; k < kOpennessRays; ++k) {
      const Vec3 d = h.direction(k, side, rng);
      const double pa = rng.uniform(), pb = rng.uniform();
      const Vec3 x = triangle_point(t.v[0], t.v[1], t.v[2], pa, pb);
      const size_t b = static_cast<size_t>(direction_bin(d));
      if (bins) ++rays[b];
      if (visibility_.rays().ray_end(x, d, node_patch(m)) == Visibility::RayEnd::back) continue;
      ++open;
      if (!bins || (reach > 0.0 && visibility_.rays().first_hit(x, d, reach, node_patch(m)) >= 0)) continue;
      ++through[b];
      ++seen;
    }
    if (bins) {
      const double prior = static_cast<double>(seen) / kOpennessRays;
      for (size_t k = 0; k < kDirectionBins; ++k) bins[k] = static_cast<float>((through[k] + prior) / (rays[k] + 1.0));
    }
    return static_cast<double>(open) / kOpennessRays;
  }
  // Bytes the direction bins take beyond one (ClusterTree::bytes counts
  // one bin per group): the groups' gathering and form factors, their and
  // the roots' share weights.
  double bin_bytes(double groups, double roots) const {
    return groups * ((bins_ - 1.0) * (2.0 * sizeof(Rgb) + 2.0 * sizeof(double)) + bins_ * sizeof(double)) +
           roots * bins_ * sizeof(float);
  }
  // 1 / (the group's mean share weight in a bin: entry b = bin_index(g,
  // k)), 0 for a group shut in.
  double per_open(size_t b) const { return group_seen_[b] > 0.0 ? 1.0 / group_seen_[b] : 0.0; }
  // The area over which group g's mean radiosity weighs its members, each
  // leaf by its area x its root's openness (all of it for a group shut in,
  // whose mean is the plain one: see update_groups).
  double sending_area(int g) const {
    const double open = group_open_[static_cast<size_t>(g)];
    return ct_.group(g).area * (open > 0.0 ? open : 1.0);
  }

  // Group radiosity from the roots' (area means of their leaves), each
  // root weighed by its openness (see openness()).
  void update_groups() {
    if (!ct_.empty()) ct_.radiosity(B_, GB_, &open_, &group_open_);
  }

  // Per group of every receiving cluster: (source, F) at the group's
  // centroid with its mean normal, over the cluster's links.
  void cluster_terms() {
    if (ct_.empty()) return;
    // A term's source is an element node or a group (-2 - g): both must
    // fit GroupTerm's packing, checked once for the round.
    const size_t sources = std::max(out_.tree.nodes().size(), ct_.group_count() + 2);
    if (sources > static_cast<size_t>(kMaxTermSource))
      throw NumericalError(scene_.source + ": " + std::to_string(out_.tree.nodes().size()) + " element nodes and " +
                           std::to_string(ct_.group_count()) + " cluster groups, more than a cluster term can name (" +
                           std::to_string(kMaxTermSource) + ")");
    tbb::parallel_for(tbb::blocked_range<size_t>(0, ct_.size(), 16), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t c = r.begin(); c != r.end(); ++c) {
        const ClusterTree::Cluster& cl = ct_.cluster(static_cast<int>(c));
        thread_local std::vector<std::pair<int, double>> found;
        for (int g = cl.group_begin; g < cl.group_end; ++g) {
          auto& terms = gterms_[static_cast<size_t>(g)];
          terms.clear();
          for (int k = 0; k < bins_; ++k) FG_[bin_index(g, k)] = 0.0;
          const ClusterTree::Group& gr = ct_.group(g);
          auto add = [&](int q, const Vec3& towards, double f) {
            const int bin = bins_ > 1 ? direction_bin(towards) : 0;
            const float fs = static_cast<float>(f);
            terms.push_back({q * 8 + bin, fs});
            FG_[bin_index(g, bin)] += fs;
          };
          const Vec3 n = gr.s / gr.area;  // not unit: the group's mean projected area per area
          for (const Link& l : clinks_[c]) {
            if (l.visible <= 0.0) continue;
            const float* seen = group_visible(l);
            const double visible = seen ? seen[g - cl.group_begin] : l.visible;
            if (l.source < 0) {
              found.clear();
              ct_.form_factors(cluster_of(l.source), gr.centroid, n, visible, found);
              for (const auto& [q, f] : found) add(q, ct_.group(-2 - q).centroid - gr.centroid, f);
            } else {
              // An element source as a point (its area at its centroid), the
              // kernel its own leaves use toward this group.
              const Triangle& t = tri_[static_cast<size_t>(l.source)];
              const Vec3 r = gr.centroid - t.centroid();
              const double d2 = glm::dot(r, r);
              const double f = visible * t.area * std::max(0.0, glm::dot(t.normal, r)) *
                               std::max(0.0, -glm::dot(n, r)) / (std::numbers::pi * d2 * d2);
              if (f > 0.0) add(l.source, -r, f);
            }
          }
          terms.shrink_to_fit();  // cleared, not freed, from round to round
        }
      }
    });
    // Pushed form factors: a group's and its ancestors' (parents have the
    // larger group numbers).
    for (int g = static_cast<int>(ct_.group_count()) - 1; g >= 0; --g) {
      const int up = ct_.group(g).up;
      for (int k = 0; k < bins_; ++k)
        FGacc_[bin_index(g, k)] = per_open(bin_index(g, k)) * FG_[bin_index(g, k)] + (up >= 0 ? FGacc_[bin_index(up, k)] : 0.0);
    }
  }

  // What every cluster group gathers now, pushed down (accumulated over its
  // ancestors' groups) for the leaves.
  void gather_clusters() {
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

  // A point of node `code` (area-uniform over its roots), its normal, patch
  // and root.
  // A cluster's roots come from root_samples_, in cluster order: the roots
  // a pair's draws fall in then lie together in memory, where their
  // triangles and patches, read by root number, cost cache misses (on the
  // 32 x 32 box field the draws took a quarter of the run).
  void sample_node(int code, SplitMix& rng, Vec3& x, Vec3& n, int& patch, int& root) const {
    const std::array<Vec3, 3>* v = nullptr;
    if (code >= 0) {
      const Triangle& t = tri_[static_cast<size_t>(code)];
      v = &t.v;
      n = t.normal;
      patch = node_patch(code);
      root = code;
    } else {
      const RootSample& s = root_samples_[static_cast<size_t>(ct_.position_at_area(cluster_of(code), rng.uniform()))];
      v = &s.v;
      n = s.normal;
      patch = s.patch;
      root = s.root;
    }
    const double a = rng.uniform(), b = rng.uniform();
    x = triangle_point((*v)[0], (*v)[1], (*v)[2], a, b);
  }
  // Advances `rng` past what sample_node(code, ...) would draw, without
  // drawing: the pair's other draws stay what they were.
  static void skip_node(int code, SplitMix& rng) { rng.skip(code >= 0 ? 2 : 3); }

  // Visible fraction between two nodes, at least one a cluster: shadow rays
  // between area-uniform points of both, weighted by the point kernel
  // (cosines at both ends over r^4), so that members facing away count for
  // nothing. One stream per pair, order-free. The same rays, sorted by the
  // normal group of the cluster end (the receiver p if a cluster, else the
  // source q) their point fell in, give each group its own fraction in
  // `per_group` (the whole pair's where a group got no ray): a floor piece
  // and the dim sides of the box standing on it, in one cluster, do not see
  // a light alike.
  // -1 when none of the first `rays` point pairs drawn face each other
  // (kernel 0 at every one): the sampled transport is zero and the pair is
  // dropped, neither linked nor split. Parts of one convex object never
  // see each other: in the 20,487-face sphere room 79% of the pairs tried
  // were such, and each drew 4 x `rays` point pairs for nothing, then was
  // linked as fully visible (0.8 M of its 2.1 M links, carrying nothing).
  double cluster_visible(int p, int q, RayCount& count, std::array<float, ClusterTree::kGroups>& per_group) const {
    const int rays = opt_.rays;
    per_group.fill(1.0f);
    if (visibility_.convex_enclosure()) {
      count.skipped += rays;
      ++count.unoccludable;
      return 1.0;
    }
    const bool swap = code_key(q) < code_key(p);
    const int a = swap ? q : p, b = swap ? p : q;
    const bool end_is_a = (p < 0 ? p : q) == a;  // the cluster end whose groups are told apart
    // The point pairs that face each other, drawn first (whether a draw
    // is used does not depend on the rays), their rays then cast in one
    // call; per ray, the root its point at the cluster end fell in, for the
    // groups.
    struct Draws {
      std::vector<Vec3> x, nx, y, ny;
      std::vector<int> px, py, root;
      std::vector<double> w;
      std::vector<unsigned char> through;
      void clear() {
        for (auto* v : {&x, &nx, &y, &ny}) v->clear();
        for (auto* v : {&px, &py, &root}) v->clear();
        w.clear();
      }
    };
    thread_local Draws d;
    d.clear();
    SplitMix rng(pair_seed(code_key(a), code_key(b)));
    // A point of a whose plane leaves all of b's bounding sphere behind it
    // faces no point of b: b's point is not drawn, only skipped in the
    // stream.
    const Vec3 centre_b = code_centre(b);
    const double radius_b = code_radius(b);
    const size_t want = static_cast<size_t>(rays);
    for (int k = 0; k < 4 * rays && d.w.size() < want && (!d.w.empty() || k < rays); ++k) {
      Vec3 x, nx, y, ny;
      int px = -1, py = -1, rx = -1, ry = -1;
      sample_node(a, rng, x, nx, px, rx);
      if (glm::dot(nx, centre_b - x) <= -radius_b) {
        skip_node(b, rng);
        continue;
      }
      sample_node(b, rng, y, ny, py, ry);
      const Vec3 r = y - x;
      const double cx = glm::dot(nx, r), cy = -glm::dot(ny, r);
      if (!(cx > 0.0 && cy > 0.0)) continue;  // half the draws on a box field: no division for them
      const double d2 = glm::dot(r, r);
      const double w = cx * cy / (d2 * d2);
      if (!(w > 0.0)) continue;
      d.x.push_back(x);
      d.nx.push_back(nx);
      d.y.push_back(y);
      d.ny.push_back(ny);
      d.px.push_back(px);
      d.py.push_back(py);
      d.root.push_back(end_is_a ? rx : ry);
      d.w.push_back(w);
    }
    const size_t n = d.w.size();
    count.cast += static_cast<long long>(n);
    if (n == 0) return -1.0;
    d.through.resize(n);
    visibility_.visible(d.x.data(), d.nx.data(), d.y.data(), d.ny.data(), d.px.data(), d.py.data(), n,
                        d.through.data());
    double weight = 0.0, open = 0.0;
    for (size_t k = 0; k < n; ++k) {
      weight += d.w[k];
      if (d.through[k]) open += d.w[k];
    }
    const double visible = open / weight;
    if (visible > 0.0 && visible < 1.0) {
      const ClusterTree::Cluster& cl = ct_.cluster(cluster_of(p < 0 ? p : q));
      std::array<double, ClusterTree::kGroups> gweight{}, gopen{};
      for (size_t k = 0; k < n; ++k) {
        const int root = d.root[k];
        const double w = d.w[k];
        const bool through = d.through[k] != 0;
        int g = ct_.root_group(root);
        while (g >= 0 && (g < cl.group_begin || g >= cl.group_end)) g = ct_.group(g).up;
        if (g < 0) continue;
        gweight[static_cast<size_t>(g - cl.group_begin)] += w;
        if (through) gopen[static_cast<size_t>(g - cl.group_begin)] += w;
      }
      for (size_t g = 0; g < per_group.size(); ++g)
        per_group[g] = static_cast<float>(gweight[g] > 0.0 ? gopen[g] / gweight[g] : visible);
    }
    return visible;
  }
  // Per-group visible fractions of a link with a cluster end (see Link::slot), or null.
  const float* group_visible(const Link& l) const {
    return l.slot >= 0 ? group_visible_.data() + l.slot : nullptr;
  }

  // The pair's kernel error factor (F bound x size over gap), or a negative
  // value when the pair must be split (bounding spheres too close), or 0
  // when the two cannot see each other (one wholly behind an element's plane).
  double cluster_shape_error(int p, int q) const {
    const Vec3 cp = code_centre(p), cq = code_centre(q);
    const double rp = code_radius(p), rq = code_radius(q);
    if (p >= 0 && glm::dot(cq - cp, tri_[static_cast<size_t>(p)].normal) <= -rq) return 0.0;
    if (q >= 0 && glm::dot(cp - cq, tri_[static_cast<size_t>(q)].normal) <= -rp) return 0.0;
    const double gap = glm::length(cq - cp) - rp - rq;
    const double size = std::max(rp, rq);
    if (!(gap > kClusterGap * size)) return -1.0;
    // A source cluster's groups whose normals straddle the direction to p
    // send it the wrong amount (ClusterTree::straddle).
    const double straddle = q < 0 ? ct_.straddle(cluster_of(q), cp, rp) : 0.0;
    return (code_area(q) * size / gap + straddle) / (std::numbers::pi * gap * gap);
  }

  // The oracle for a link with a cluster at one end: rho_p B_q times its
  // kernel error factor, plus the whole transport when partly visible.
  double cluster_link_error(int p, const Link& l) const {
    const double unseen = l.partial() ? l.f * l.visible : 0.0;
    return cluster_weight(p, l.source) * (l.spread + unseen);
  }
  // element_weight for a link with a cluster at one end.
  double cluster_weight(int p, int q) const { return code_rho(p) * code_radiosity(q) * pw(p); }
  bool wants_cluster_refinement(int p, const Link& l) const {
    return cluster_link_error(p, l) > hopt_.epsilon * scale_;
  }

  // Queues the pair (a, b). Two elements that cannot see each other (one
  // wholly behind the other's plane) are dropped here, as the element
  // linking would drop them, instead of waiting in the pair lists: the
  // clusters of one convex object, too near one another for the gap rule,
  // are split down to their triangles, and in the 327,687-face sphere room
  // that made 112 M pairs of sphere triangles (0.9 GB of lists, 1.1 GB
  // with their growth), nearly all facing away.
  void queue_pair(int a, int b, std::vector<std::pair<int, int>>& next) {
    if (a >= 0 && b >= 0 && facing_away(tri_[static_cast<size_t>(a)], tri_[static_cast<size_t>(b)])) {
      ++out_.stats.links_examined;
      return;
    }
    next.emplace_back(a, b);
  }

  // Queues the children pairs of (p, q), one end at least a cluster: a
  // small cluster first (it may not end a link), else the larger end by
  // radius, an element too (split in four, as the element linking would)
  // while it may be split. A cluster paired with itself gives every pair of
  // its children.
  void split_cluster_pair(int p, int q, std::vector<std::pair<int, int>>& next) {
    if (p == q) {
      if (p >= 0) return;  // a planar element does not see itself
      const auto children = ct_.children(cluster_of(p));
      for (int a : children)
        for (int b : children) queue_pair(a, b, next);
      return;
    }
    auto may_split = [&](int code) { return code < 0 || splittable(code); };
    bool split_p;
    if (small_code(p) != small_code(q))
      split_p = small_code(p);
    else if (may_split(p) != may_split(q))
      split_p = may_split(p);
    else
      split_p = code_radius(p) >= code_radius(q);
    const int n = split_p ? p : q;
    if (n < 0) {
      for (int c : ct_.children(cluster_of(n))) queue_pair(split_p ? c : p, split_p ? q : c, next);
      return;
    }
    int first = out_.tree.node(n).child;
    if (first < 0) {
      first = out_.tree.split(n);
      grow();
    }
    for (int c = first; c < first + 4; ++c) next.emplace_back(split_p ? c : p, split_p ? q : c);
  }

  // Links pairs with a cluster at one end or both, top down: a pair is
  // linked when its oracle allows, else split. Returns the pairs of two
  // elements reached, for link_pairs.
  std::vector<std::pair<int, int>> link_cluster_pairs(std::vector<std::pair<int, int>> todo) {
    std::vector<std::pair<int, int>> elements;
    std::vector<std::pair<int, int>> pairs, next;  // their memory kept from generation to generation
    std::vector<Link> ev;                           // per block (kLinkBlock)
    std::vector<std::array<float, ClusterTree::kGroups>> per_group;
    std::vector<RayCount> rays;
    std::vector<char> split;
    while (!todo.empty()) {
      pairs.clear();
      next.clear();
      for (const auto& [p, q] : todo) {
        if (p >= 0 && q >= 0)
          elements.emplace_back(p, q);
        else if (p == q)
          split_cluster_pair(p, q, next);
        else
          pairs.emplace_back(p, q);
      }
      for (size_t begin = 0; begin < pairs.size(); begin += kLinkBlock) {
        const size_t count = std::min(kLinkBlock, pairs.size() - begin);
        ev.assign(count, Link{});
        per_group.resize(count);
        rays.assign(count, RayCount{});
        split.assign(count, 0);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 16), [&](const tbb::blocked_range<size_t>& r) {
          for (size_t i = r.begin(); i != r.end(); ++i) {
            const auto [p, q] = pairs[begin + i];
            Link& l = ev[i];
            l.source = q;
            const double shape = cluster_shape_error(p, q);
            if (shape == 0.0) continue;
            if (shape < 0.0 || cluster_weight(p, q) * shape > hopt_.epsilon * scale_ || small_code(p) ||
                small_code(q)) {
              split[i] = 1;
              continue;
            }
            l.spread = shape;
            const double d = glm::length(code_centre(q) - code_centre(p));
            l.f = code_area(q) / (std::numbers::pi * d * d);
            l.visible = cluster_visible(p, q, rays[i], per_group[i]);
            if (l.visible < 0.0) {
              l.f = 0.0;
              continue;
            }
            if (wants_cluster_refinement(p, l)) split[i] = 1;
          }
        });
        for (size_t i = 0; i < count; ++i) {
          const auto [p, q] = pairs[begin + i];
          ++out_.stats.links_examined;
          out_.stats.rays_cast += rays[i].cast;
          out_.stats.rays_skipped += rays[i].skipped;
          out_.stats.pairs_unoccludable += rays[i].unoccludable;
          if (split[i]) {
            split_cluster_pair(p, q, next);
            continue;
          }
          Link& l = ev[i];
          if (!(l.f > 0.0)) continue;
          if (l.partial()) {
            const ClusterTree::Cluster& end = ct_.cluster(cluster_of(p < 0 ? p : q));
            l.slot = static_cast<int>(group_visible_.size());
            group_visible_.insert(group_visible_.end(), per_group[i].begin(),
                                  per_group[i].begin() + (end.group_end - end.group_begin));
          }
          if (p >= 0) {
            links_[static_cast<size_t>(p)].push_back(l);
            dirty_[static_cast<size_t>(p)] = 1;
          } else {
            clinks_[static_cast<size_t>(cluster_of(p))].push_back(l);
          }
        }
        check_resident();
      }
      todo.swap(next);
      check_memory();
    }
    return elements;
  }

  // Progress from the calling thread: the phase (link, solve, refine) and,
  // for the first linking, the fraction of receivers linked.
  void report(const char* phase, double fraction) const {
    if (progress_) progress_(phase, fraction);
  }

  const Scene& scene_;
  const SolveOptions& opt_;
  HierarchicalOptions hopt_;
  HierarchicalSolution& out_;
  ProgressFn progress_;
  VisibilityEstimator visibility_;
  double min_area_ = 0.0, max_emission_ = 0.0;
  double mean_root_area_ = 0.0;  // the oracle's area weight's reference (pw)
  double diagonal_ = 0.0;  // the scene's, once (Scene::diagonal visits every vertex)
  double limit_ = 0.0;          // memory limit, bytes
  double held_before_ = 0.0;    // the process's resident memory when the solver began, bytes
  // A link's memory: the Link in its receiver's list, with the vector's slack.
  static constexpr double kLinkBytes = 1.5 * sizeof(Link);
  static constexpr int kSenderDepth = 2;
  // Per link number: its value and sent-weight norm.
  static constexpr double kLinkIdBytes = sizeof(Rgb) + sizeof(double);
  static constexpr double kGiB = 1024.0 * 1024.0 * 1024.0;
  // The radiosity the oracle's epsilon is relative to: the largest emission
  // for the first linking, then the largest reflected radiosity (B - E) of
  // the last solve, so that a small bright lamp does not set the scale.
  double scale_ = 0.0;
  // The radiosity the leaves' own rays are bounded against (own_rays_matter):
  // the area mean of the reflected radiosity over the leaves that reflect,
  // once solved (scale_ before). It was scale_, the largest: in a closed
  // room lit by a tube 5 cm under the ceiling, the ceiling above the tube is
  // about 70 times as bright as the rest, so every dim link passed the bound
  // on its ancestor's visible fraction. A link's fraction moves the leaf's
  // row as well as its light, and the row scale takes a row's miss out of
  // the approximate part whatever the link's source radiosity: the leaves
  // in the 10 cm gaps behind a cabinet had exact rows several percent over
  // or under 1, the row scale cut or stretched their approximate parts, and
  // 1.08% of the emitted power escaped the closed room; now -0.11% (test
  // ATubeUnderTheCeilingLightsAClosedRoomWithACabinetAndLosesNoPower), the
  // 16 x 16 box field's 0.13% -> 0.08% for 1.04x its time. A bound of 0.01 x
  // the largest instead: -0.03% and 0.04%, but 1.13x the box field's time.
  double rays_reference_ = 0.0;
  QuadratureOptions quadrature_;
  ElementSet el_;  // per tree node
  std::vector<std::string> enclosed_warnings_;  // emitting roots inside closed objects (SolveStats::warnings)
  std::vector<Triangle>& tri_ = el_.triangle;
  std::vector<Rgb>& rho_ = el_.reflectance;
  std::vector<Rgb>& emit_ = el_.emission;
  std::vector<Rgb> B_, H_;
  std::vector<Rgb> previous_;  // node radiosity of the round before (for last_change)
  bool done_ = false;          // the stopping rule was met: step() changes nothing more
  int extrapolations_ = 0;     // Aitken steps of the sweeps, all rounds
  std::vector<double> F_sum_;     // per leaf: its exact form factors (element sources)
  std::vector<double> F_approx_;  // per leaf: its form factors to big clusters' groups (its path's node_F_)
  std::vector<float> F_noise_;    // per leaf: the variance of F_sum_ from its links' shadow rays
  std::vector<float> F_doubt_;    // per leaf: F_noise_ with half a ray of doubt on links whose rays all got through
  std::vector<double> exact_scale_;  // per leaf: what scale_rows scales its exact terms by (in double: rows exact to rounding)
  // Per leaf: (link id, F x visibility at the leaf) over its own and its
  // ancestors' element links, F in float, and per leaf what its float
  // terms are scaled by so that they sum to F_sum_ (taken in double): the
  // sweeps read half the bytes, and the rows still sum as the double terms
  // do (the furnace stays exact to rounding). In double the terms were 0.73
  // GB of the 20,487-face sphere room's 1.15 GB peak; in float the peak is
  // 0.87 GB there and 1.29 GB (from 1.71) at 81,927 faces, object means
  // equal to six digits. Per node with links from clusters: (group code
  // -2 - g, F at its centroid) in node_terms_ (see node_cluster_terms),
  // their sum in double node_F_, what they gather in node_H_.
  struct Term {
    int q;
    float f;
  };
  std::vector<std::vector<Term>> terms_;
  std::vector<double> fix_exact_;
  double term_f(size_t leaf, const Term& t) const {
    return static_cast<double>(t.f) * fix_exact_[leaf] * exact_scale_[leaf];
  }
  std::vector<std::vector<Term>> node_terms_;
  std::vector<double> node_F_;
  std::vector<Rgb> node_H_;
  std::vector<int> node_gatherers_;  // the nodes whose node_terms_ are not empty
  // Per node: (link id, A F(node -> receiver) x visibility), in float: it
  // only shares a link's transport out, and its sums are taken in double.
  std::vector<std::vector<std::pair<int, float>>> sent_;
  std::vector<float> node_open_;          // per node: its openness (openness_of), -1 until needed
  std::vector<char> sent_dirty_;          // per node: element links from it changed since the last leaf_terms
  int next_id_ = 0;                       // element links numbered so far
  std::vector<int> free_ids_;             // numbers of removed links, to use again
  std::vector<Rgb> link_value_;           // per link id: its source leaves' radiosity, weighted by sent_
  std::vector<double> inv_sent_;          // per link id: 1 / the sum of its sent_ weights (0: none)
  std::vector<std::vector<Link>> links_;  // per receiver node
  std::vector<char> dirty_;               // per node: links changed since the last leaf_terms (new nodes too)
  // Clusters (ClusterMode volume or shape; all empty otherwise).
  ClusterTree ct_;
  struct RootSample {  // a root's triangle, patch and number, at its position in cluster order
    std::array<Vec3, 3> v;
    Vec3 normal;
    int patch, root;
  };
  std::vector<RootSample> root_samples_;
  Wanted left_;  // the marginal links step() last left unrefined (none while it refines)
  std::vector<float> group_visible_;  // per partly visible cluster link, per group of its cluster end
  std::vector<std::vector<Link>> clinks_;  // per receiving cluster
  // A group's term in 8 bytes (they were 16, an eighth of the 32 x 32 box
  // field's peak): the source (an element node, or a group -2 - g) and the
  // direction bin of the source seen from the group (0 with one bin) as
  // source x 8 + bin, and F in single precision (its sums, FG_, are taken
  // over the same floats, so rows and the energy balance stay exact).
  struct GroupTerm {
    int code;
    float f;
    int q() const { return code >> 3; }
    int bin() const { return code & 7; }
  };
  static constexpr int kMaxTermSource = (1 << 27) - 1;  // |source| x 8 + 7 fits an int
  static_assert(kDirectionBins <= 8);
  std::vector<std::vector<GroupTerm>> gterms_;  // per group: (source, bin, F) at its centroid
  int bins_ = 1;                          // direction bins of the groups' gathering (kDirectionBins with `shape`)
  bool fine_small_clusters_end_links_ = false;  // small_code: `volume` only
  std::vector<float> seen_open_;          // per root x bins_: its share weight (openness, or per bin openness_of's)
  std::vector<double> group_seen_;        // per group x bins_: the area mean of its roots' seen_open_
  std::vector<Rgb> GB_;                   // per group: radiosity
  std::vector<Rgb> HG_, HGacc_;           // per group x bins_: gathered, gathered with its ancestors'
  std::vector<double> open_;              // per root: its openness (see openness())
  std::vector<double> group_open_;        // per group: the area mean of its roots' openness
  std::vector<double> FG_, FGacc_;        // per group x bins_: form factor sum, with its ancestors'
  std::vector<RayCount> leaf_rays_;    // per node: rays its leaf terms cast (gather_terms)
  std::vector<double> row_scale_;      // per node (leaves): what its approximate part is scaled by (scale_rows)
  std::vector<signed char> enclosed_;  // per node: 1 enclosed, 0 not, -1 not yet known
};

}  // namespace

TVertexMode parse_tvertex_mode(const std::string& name) {
  if (name == "anchor") return TVertexMode::anchor;
  if (name == "free") return TVertexMode::free;
  if (name == "split") return TVertexMode::split;
  throw InputError("T-vertex mode '" + name + "': expected anchor, free or split");
}

ClusterMode parse_cluster_mode(const std::string& name) {
  if (name == "off") return ClusterMode::off;
  if (name == "volume") return ClusterMode::volume;
  if (name == "shape") return ClusterMode::shape;
  throw InputError("cluster mode '" + name + "': expected shape, volume or off");
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
      solver = std::make_unique<Solver>(scene, options, h, out, progress);
      solver->start();
    });
  }
  SolveOptions options;
  HierarchicalSolution out;
  std::unique_ptr<Solver> solver;
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
