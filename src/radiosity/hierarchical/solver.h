// The hierarchical solver's state and its phases. One class holds what
// lives between refinement rounds (the element tree, the links, the terms
// the sweeps read, the clusters); each phase is defined in a file of its own
// in this folder:
//   rounds.cpp          the constructor, rounds, growth of the tree, Baum's splits
//   linking.cpp         element links and the oracle (refinement)
//   memory.cpp          the memory budget
//   clusters.cpp        the clusters above the roots: groups, openness, direction bins
//   cluster_linking.cpp links with a cluster at one end or both
//   terms.cpp           what each leaf and group gathers over (terms), what each source sends
//   row_scaling.cpp     rows kept near 1 where clusters approximate
//   sweeps.cpp          the Gauss-Seidel sweeps and the pull up the tree
//   publish.cpp         the conforming mesh, its values and the energy balance
// hierarchical.cpp holds the public API (HierarchicalSolver, solve_hierarchical).
#pragma once

#include "radiosity/transport/clusters.h"
#include "radiosity/transport/sampling.h"
#include "radiosity/transport/transport.h"
#include "radiosity/transport/visibility.h"
#include "radmesh/errors.h"
#include "radmesh/field.h"
#include "radmesh/form_factor.h"
#include "radmesh/hierarchical.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace radmesh::internal {

inline double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

struct Link {
  int source = -1;
  // One field for two uses, which no link has both of (20 bytes a link, not
  // 24; a box field of 10^5 faces has 10^8 links):
  // - an element-to-element link: its number (store_element_link), which its
  //   leaf terms on both sides refer to;
  // - a link with a cluster end: where its visible fraction per normal group
  //   of that end starts in the solver's group_visible_ (-1: `visible` for
  //   every group). The end is the receiver when it is a cluster, else the
  //   source.
  int slot = -1;
  // Single precision: links are most of the memory.
  float f = 0.0f;         // F(receiver -> source) without occlusion
  float visible = 1.0f;   // what got through of the shadow rays, each weighed by its point kernel
  float spread = 0.0f;    // how much the point form factor varies over the receiver (oracle)
  bool partial() const { return visible > 0.0 && visible < 1.0; }
};
static_assert(sizeof(Link) == 20);

class Hierarchical {
public:
  // `out.tree` holds the roots (the initial mesh) on entry.
  Hierarchical(const Scene& scene, const SolveOptions& opt, const HierarchicalOptions& hopt, HierarchicalSolution& out,
               const ProgressFn& progress);

  // rounds.cpp
  void start();   // the first linking and the first solve
  bool step();    // one refinement round; false once the stopping rule is met
  void finish();  // the links copied out (HierarchicalOptions::export_links)

private:
  // ---- rounds.cpp: rounds, growth, Baum's splits ---------------------------
  void solve_round();
  bool display_round();
  bool gathered_field() const;
  void grow();
  // Baum's criterion adds at most kBaumShare of the leaves the links made
  // (the largest spreads first), and a round for its splits alone is made
  // only where they add kBaumRound of the leaves: a round costs a pass over
  // every leaf.
  static constexpr double kBaumShare = 0.5;
  static constexpr double kBaumRound = 0.01;
  int split_by_variation(bool round_made, bool deep = false);
  void close_t_vertices();
  int node_patch(int n) const { return out_.tree.node(n).patch; }
  static constexpr double kSplittableArea = 4.0;  // in min_area_: an element above it may be split
  bool splittable(int n) const { return tri_[static_cast<size_t>(n)].area > kSplittableArea * min_area_; }
  // Progress from the calling thread: the phase (link, solve, refine) and,
  // for the first linking, the fraction of receivers linked.
  void report(const char* phase, double fraction) const {
    reported_ = {phase, fraction};
    if (progress_) progress_(phase, fraction);
  }
  // The last report again, after each block of work that cannot tell its
  // own fraction (pairs linked, terms made): the caller hears from the
  // solve often, and can stop it there (progress.h).
  void report_again() const { report(reported_.first, reported_.second); }

  // ---- linking.cpp: element links and the oracle ---------------------------
  double form_factor_to(int p, int q) const;
  // A generation of pairs is evaluated kLinkBlock pairs at a time, so that
  // the per-pair scratch stays small and is reused; the blocks are consumed
  // in order.
  static constexpr size_t kLinkBlock = size_t{1} << 14;
  // Evaluates `pairs` in blocks: evaluate(i, p, q, link, rays, split) in
  // parallel (each pair alone, with its own random stream, so the result
  // does not depend on the threads), then take(i, p, q, link, split) in
  // order, with each pair's rays counted first.
  template <class Evaluate, class Take>
  void evaluate_pairs(const std::vector<std::pair<int, int>>& pairs, Evaluate&& evaluate, Take&& take);
  void link_pairs(std::vector<std::pair<int, int>> todo);
  void store_element_link(int p, Link l);
  void release_element_link(const Link& l);
  std::array<double, 4> corner_form_factors(int p, int q) const;
  static double spread(const std::array<double, 4>& corner_f, double f);
  bool split_by_corners(int p, int q, const std::array<double, 4>& corner_f) const;
  static bool spread_dominates(const Link& l) { return l.spread > 0.5 * l.f * l.visible; }
  bool split_whatever_visible(int p, const Link& l) const;
  double link_error(int p, const Link& l) const;
  double element_weight(int p, int q) const;
  bool wants_refinement(int p, const Link& l) const { return link_error(p, l) > hopt_.epsilon * scale_; }
  bool split_pair(int p, int q, bool receiver_first, std::vector<std::pair<int, int>>& next);
  // What the oracle would refine now: how many links, and the largest
  // error among them. step() makes no round for links that are all over
  // the threshold by at most HierarchicalOptions::marginal_refinement x:
  // they crossed it because the last solve moved their source's radiosity
  // or the scale a little, and refining one changes its receiver by about
  // its error, what the oracle leaves on every other link, while a round
  // costs a pass over every link and leaf.
  struct Wanted {
    long long links = 0;
    double worst = 0.0;  // the largest error over the threshold
  };
  void report_left();
  Wanted wanted_refinement() const;
  double refinement_error(int p, const Link& l) const;
  long long refine_links();
  long long count_links() const;

  // ---- memory.cpp: the budget -----------------------------------------------
  void check_memory();
  void check_resident();
  std::string held_text() const;

  // ---- terms.cpp: what leaves and groups gather over ------------------------
  void leaf_terms();
  // Calls make(node) for every node of `todo` in parallel, kTermBlock nodes
  // at a time, with the resident memory checked between blocks: a round's
  // terms can be most of the memory, and made at once they would pass a
  // limit before the check after them.
  static constexpr size_t kTermBlock = size_t{1} << 13;
  template <class Make>
  void in_blocks(const std::vector<int>& todo, Make&& make) {
    for (size_t begin = 0; begin < todo.size(); begin += kTermBlock) {
      const size_t end = std::min(todo.size(), begin + kTermBlock);
      tbb::parallel_for(tbb::blocked_range<size_t>(begin, end, 8), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) make(static_cast<size_t>(todo[i]));
      });
      check_resident();
      report_again();
    }
  }
  static constexpr double kLeafRaysBound = 0.1;  // see leaf_terms
  // Whether a node casts its own rays on a partly visible link it reads (a
  // leaf on its ancestors' links, a sending piece on its source's): where
  // the light the link's mean fraction may move there is over
  // kLeafRaysBound x epsilon x rays_reference_.
  bool own_rays_matter(double transport) const { return transport > kLeafRaysBound * hopt_.epsilon * rays_reference_; }
  // Those rays: a quarter of the rays (at least one), stratified on both
  // ends, node a's own stream with b, without a shaft test.
  int own_side() const { return std::max(1, visibility_.side() / 2); }
  double own_visible_fraction(int a, int b, RayCount& count) const;
  void gather_terms(size_t x);
  void node_cluster_terms(size_t x);
  std::vector<double> received_sums() const;
  void sender_terms(size_t y, const std::vector<int>& out_begin, const std::vector<std::pair<int, int>>& out);
  void link_values();
  void cluster_terms();

  // ---- sweeps.cpp ----------------------------------------------------------
  void solve();
  Rgb pull(int p, double& change, double& top);
  void gather_clusters();

  // ---- publish.cpp ---------------------------------------------------------
  int nearest_old(int n, size_t old_count) const;
  void publish();
  void publish_mesh();
  void publish_balance();
  std::vector<double> sent_rows() const;

  // ---- clusters (ClusterMode volume or shape) -------------------------------
  // The cluster tree above the roots (transport/clusters.h). A link has a
  // node code at each end: an element node (>= 0) or a cluster
  // (cluster_code(c) <= -2). A link from a cluster is gathered per group of
  // the source; a cluster receives per group of its own (at the group's
  // centroid, with s / area as its normal), and what a group gathers is
  // pushed down to every leaf below it (through the group its root belongs to).
  //
  // Cluster links need a gap between the two bounding spheres of at least
  // this fraction of the larger radius; nearer pairs are split.
  static constexpr double kClusterGap = 1.0;
  // A cluster of at most this many roots is small and never ends a link: a
  // link the oracle would make there is split down to its elements, whose
  // links have exact form factors and their own visibility, so that only
  // big clusters, which the gap rule keeps far away, are approximated.
  // With `volume` clusters a small cluster whose roots are at the links'
  // floor already (on average too small to be split, as the triangles of a
  // scanned object are) ends links: its elements' links would be no finer
  // than the cluster's, and splitting it only multiplies them.
  static constexpr int kSmallCluster = 16;
  static constexpr int cluster_code(int c) { return ClusterTree::code(c); }
  static constexpr int cluster_of(int code) { return ClusterTree::index(code); }
  // Radiosity of a term's source: an element node, or a group (-2 - g).
  Rgb value(int code) const { return code >= 0 ? B_[static_cast<size_t>(code)] : GB_[static_cast<size_t>(-2 - code)]; }

  // clusters.cpp: building them, openness, direction bins.
  // What a receiving group gathers is shared among its members' roots in
  // proportion to their openness: the fraction of their hemisphere
  // (kOpennessRays cosine-distributed rays from stratified points of the
  // root) that is not shut in. A group gathers at its centroid through its
  // mean visibility; without the shares the floor under a box would be lit
  // like the floor beside it. With `shape` clusters (where a box hangs
  // under the floor triangle it stands on, so the box's top and the floor
  // it shadows are one group) the sharing is kept per direction bin
  // (kDirectionBins, the faces of a cube).
  static constexpr int kOpennessRays = 16;
  static constexpr int kDirectionBins = 6;
  void build_clusters();
  void openness();
  static int direction_bin(const Vec3& d);
  // Entry (i, bin k) of a per-root or per-group array of bins_ per item.
  size_t bin_index(int i, int k) const { return static_cast<size_t>(i) * static_cast<size_t>(bins_) + static_cast<size_t>(k); }
  // Root r's share weight for light from bin k (its openness with one bin).
  double seen_open(int r, int k) const { return seen_open_[bin_index(r, k)]; }
  double openness_of(int m, double reach = 0.0, float* bins = nullptr) const;
  double bin_bytes(double groups, double roots) const;
  // 1 / (the group's mean share weight in a bin: entry b = bin_index(g,
  // k)), 0 for a group shut in.
  double per_open(size_t b) const { return group_seen_[b] > 0.0 ? 1.0 / group_seen_[b] : 0.0; }
  double sending_area(int g) const;
  void update_groups();

  // row_scaling.cpp: rows kept near 1 (see scale_rows).
  // The scale of a row's approximate part is kept within [0, kMaxRowScale]:
  // the gap rule keeps the group kernel's error well under 20%, so a larger
  // deficit lies elsewhere and is not the approximate part's to fill.
  static constexpr double kMaxRowScale = 1.2;
  // What the exact terms take of a row's miss: up to what their shadow rays
  // may be off by (3 standard deviations of the binomial estimates, F_noise_)
  // plus this for their quadrature.
  static constexpr double kRowTolerance = 5e-4;
  // Point pairs with which a leaf samples its approximate sources (approx_confirmed).
  static constexpr int kApproxRays = 16;
  Rgb pushed(int leaf) const;
  Rgb gathered(size_t leaf) const;
  double approx_row_sum(size_t leaf) const;
  double row_sum(size_t leaf) const;
  double approx_confirmed(size_t x) const;
  bool enclosed(size_t leaf) const;
  void scale_rows();

  // cluster_linking.cpp
  bool small_code(int code) const;
  Vec3 code_centre(int code) const;
  double code_radius(int code) const;
  double pw(int code) const;
  double code_area(int code) const;
  double element_oracle_rho(size_t e) const;
  double code_rho(int code) const;
  double code_radiosity(int code) const;
  uint64_t code_key(int code) const;
  void sample_node(int code, SplitMix& rng, Vec3& x, Vec3& n, int& patch, int& root) const;
  // Advances `rng` past what sample_node(code, ...) would draw, without
  // drawing: the pair's other draws stay what they were.
  static void skip_node(int code, SplitMix& rng) { rng.skip(code >= 0 ? 2 : 3); }
  double cluster_visible(int p, int q, RayCount& count, std::array<float, ClusterTree::kGroups>& per_group) const;
  const float* group_visible(const Link& l) const;
  double cluster_shape_error(int p, int q) const;
  double cluster_link_error(int p, const Link& l) const;
  // element_weight for a link with a cluster at one end.
  double cluster_weight(int p, int q) const { return code_rho(p) * code_radiosity(q) * pw(p); }
  bool wants_cluster_refinement(int p, const Link& l) const;
  void queue_pair(int a, int b, std::vector<std::pair<int, int>>& next);
  void split_cluster_pair(int p, int q, std::vector<std::pair<int, int>>& next);
  std::vector<std::pair<int, int>> link_cluster_pairs(std::vector<std::pair<int, int>> todo);

  // ---- state ---------------------------------------------------------------
  const Scene& scene_;
  const SolveOptions& opt_;
  HierarchicalOptions hopt_;
  HierarchicalSolution& out_;
  ProgressFn progress_;
  mutable std::pair<const char*, double> reported_{"link", 0.0};
  VisibilityEstimator visibility_;
  double min_area_ = 0.0, max_emission_ = 0.0;
  double mean_root_area_ = 0.0;  // the oracle's area weight's reference (pw)
  // The sending weights (sent_) are areas x form factors in float: they are
  // kept in units of this power of two near the mean root's area, so that
  // a scene of any unit stays inside float's range (they only share a
  // link's transport out, so their unit cancels, exactly).
  double area_unit_ = 1.0;
  double diagonal_ = 0.0;        // the scene's, once (Scene::diagonal visits every vertex)
  double limit_ = 0.0;           // memory limit, bytes
  double held_before_ = 0.0;     // the process's resident memory when the solver began, bytes
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
  // once solved (scale_ before). Not the largest: where a small part of a
  // room is far brighter than the rest (the ceiling just above a lamp), every
  // dim link would pass the bound, and a link's fraction moves its leaf's
  // row as well as its light.
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
  // sweeps read half the bytes, and the rows still sum as double terms
  // would (the furnace stays exact to rounding). Per node with links from
  // clusters: (group code -2 - g, F at its centroid) in node_terms_ (see
  // node_cluster_terms), their sum in double node_F_, what they gather in
  // node_H_.
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
  // A group's term in 8 bytes: the source (an element node, or a group
  // -2 - g) and the direction bin of the source seen from the group (0 with
  // one bin) as source x 8 + bin, and F in single precision (its sums, FG_,
  // are taken over the same floats, so rows and the energy balance stay
  // exact).
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
  std::vector<RayCount> leaf_rays_;       // per node: rays its leaf terms cast (gather_terms)
  std::vector<double> row_scale_;         // per node (leaves): what its approximate part is scaled by (scale_rows)
  std::vector<signed char> enclosed_;     // per node: 1 enclosed, 0 not, -1 not yet known
};

template <class Evaluate, class Take>
void Hierarchical::evaluate_pairs(const std::vector<std::pair<int, int>>& pairs, Evaluate&& evaluate, Take&& take) {
  std::vector<Link> ev;
  std::vector<RayCount> rays;
  std::vector<char> split;
  for (size_t begin = 0; begin < pairs.size(); begin += kLinkBlock) {
    const size_t count = std::min(kLinkBlock, pairs.size() - begin);
    ev.assign(count, Link{});
    rays.assign(count, RayCount{});
    split.assign(count, 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 16), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i != r.end(); ++i) {
        const auto [p, q] = pairs[begin + i];
        ev[i].source = q;
        evaluate(i, p, q, ev[i], rays[i], split[i]);
      }
    });
    for (size_t i = 0; i < count; ++i) {
      ++out_.stats.links_examined;
      out_.stats.rays_cast += rays[i].cast;
      out_.stats.rays_skipped += rays[i].skipped;
      out_.stats.pairs_unoccludable += rays[i].unoccludable;
      const auto [p, q] = pairs[begin + i];
      take(i, p, q, ev[i], split[i] != 0);
    }
    check_resident();
    report_again();
  }
}

}  // namespace radmesh::internal
