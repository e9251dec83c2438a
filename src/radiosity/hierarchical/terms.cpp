// What each leaf and group gathers over: a leaf's terms are its own and its
// ancestors' element links re-evaluated at its own points (so that rows
// sum to 1 in a closed scene), with its own shadow rays where a link's mean
// visibility would move its light; a node's cluster terms; a group's terms
// at its centroid; and what each source sends along a link (its pieces
// weighted by what each sends), made once per round for the sweeps.

#include "radiosity/hierarchical/solver.h"

#include <numbers>

namespace radmesh::internal {

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
// quarter of the rays, at least one, stratified; its own random stream:
// unbiased for the leaf, and its many links average the noise). One
// fraction for a whole ancestor is the mean over the ancestor, and the
// leaves next to an occluder see less than the mean: the floor at a
// block's foot would come out brighter than the light that reaches it
// (docs/decisions.md).
//
// The sending side in pieces (sender_terms): an element link does not
// carry its source node's mean radiosity but the mean of the source's
// pieces weighted by how much each sends to the link's receiver
// (A_y F(y -> receiver)). A wall's top, bright and near the ceiling, thus
// counts for more toward the ceiling than its dim bottom; with the plain
// mean, light would vanish between the links' two ends.
//
// Terms are kept between rounds for a leaf whose path has no changed link
// (receiving) and no changed link from it (sending); the others are
// computed in parallel, each leaf alone.
void Hierarchical::leaf_terms() {
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
    // list), 8 bytes a link: the run's peak memory can come while this
    // list is held.
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
      if (inv_sent_[static_cast<size_t>(t.q)] <= 0.0)
        inv_sent_[static_cast<size_t>(t.q)] -= tri_[x].area / area_unit_ * term_f(x, t);
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

double Hierarchical::own_visible_fraction(int a, int b, RayCount& count) const {
  return visibility_.visible_fraction(tri_[static_cast<size_t>(a)], node_patch(a), static_cast<uint64_t>(a),
                                      tri_[static_cast<size_t>(b)], node_patch(b), static_cast<uint64_t>(b), count,
                                      own_side(), false);
}

void Hierarchical::gather_terms(size_t x) {
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
  // the sources of each level in one pass, so that a leaf next to one
  // surface does not take the fine points for every source. A row summed
  // over several point sets is exact to the quadrature only
  // (kRowTolerance), which scale_rows allows for. The lists are kept per
  // thread: this runs once per leaf.
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
    // No shaft test: the ancestor's shaft holds an occluder, and nearly
    // every leaf's does too; the tests would cost more than the rays they
    // save.
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
  // Exactly the room they take: built by push_back, the lists would hold
  // up to twice that.
  terms_[x].shrink_to_fit();
  for (const Term& k : terms_[x]) exact += k.f;
  if (exact > 0.0) fix_exact_[x] = F_sum_[x] / exact;
}

// Node x's terms for the links it receives from clusters: per normal
// group of the source, F at x's centroid, gathered once per sweep for all
// the leaves below (node_H_). The oracle bounds the kernel's spread over
// x for these links as for any other, so evaluating it at every leaf's
// centroid instead buys no accuracy, and each leaf would hold a term per
// group of each of its ancestors' cluster links (docs/decisions.md).
void Hierarchical::node_cluster_terms(size_t x) {
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
std::vector<double> Hierarchical::received_sums() const {
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
// one point each does as well as a full quadrature.
void Hierarchical::sender_terms(size_t y, const std::vector<int>& out_begin, const std::vector<std::pair<int, int>>& out) {
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
    // quarter of the rays, stratified, as a leaf casts on its ancestors'
    // links: the link's fraction is a mean over the source, and where the
    // bright part of the source is the hidden one (a wall lit by a lamp
    // just in front of it, which the lamp's back hides from the room)
    // weighing the pieces alike would send the room that bright part.
    const Link& l = *path[k].second;
    const int p = path[k].first;
    const bool own_rays =
        l.visible < 1.0 && own_rays_matter(max3(rho_[static_cast<size_t>(p)]) * l.f *
                                           max3(glm::abs(B_[y] - B_[static_cast<size_t>(l.source)])));
    const double v = own_rays ? own_visible_fraction(static_cast<int>(y), p, leaf_rays_[y]) : l.visible;
    const float w = static_cast<float>(t.area / area_unit_ * f[k] * v) * node_open_[y];
    if (w > 0.0f) sent.push_back({l.slot, w});
  }
  sent.shrink_to_fit();
}

// Every element link's source value from its sending leaves (sent_):
// the mean of their radiosity weighted by what each sends over the link.
void Hierarchical::link_values() {
  link_value_.assign(static_cast<size_t>(next_id_), Rgb(0.0));
  for (size_t y = 0; y < sent_.size(); ++y)
    for (const auto& [id, w] : sent_[y])
      link_value_[static_cast<size_t>(id)] += (w * inv_sent_[static_cast<size_t>(id)]) * B_[y];
}

// Per group of every receiving cluster: (source, F) at the group's
// centroid with its mean normal, over the cluster's links.
void Hierarchical::cluster_terms() {
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

}  // namespace radmesh::internal
