// Links with a cluster at one end or both: a cluster pair's form factor
// (area over pi d^2 between the two centres), its visibility from sampled
// point pairs (per normal group of its cluster end, weighed by the point
// kernel), the oracle's shape error and weight, and the top-down linking
// that splits a pair into its children until the oracle allows a link, or
// hands pairs of two elements to link_pairs.

#include "radiosity/hierarchical/solver.h"

#include <numbers>

namespace radmesh::internal {

bool Hierarchical::small_code(int code) const {
  if (code >= 0) return false;
  const int members = ct_.members(cluster_of(code));
  if (members > kSmallCluster) return false;
  return !fine_small_clusters_end_links_ || code_area(code) > kSplittableArea * min_area_ * members;
}

Vec3 Hierarchical::code_centre(int code) const {
  return code >= 0 ? tri_[static_cast<size_t>(code)].centroid() : ct_.cluster(cluster_of(code)).centre;
}

double Hierarchical::code_radius(int code) const {
  return code >= 0 ? tri_[static_cast<size_t>(code)].radius : ct_.cluster(cluster_of(code)).radius;
}

// The oracle's weight for receiver `code`. Below the links' floor
// (min_area_: refinement makes no receiver smaller, so only input
// triangles and clusters of them are) a receiver's error counts by its
// share of the floor's area: the pieces of a floor-sized area answer
// together for what one receiver of that size would, so that an input mesh
// finer than the floor does not multiply the links (docs/decisions.md).
// Then HierarchicalOptions::area_weight.
double Hierarchical::pw(int code) const {
  const double a = code_area(code);
  double w = a < min_area_ ? a / min_area_ : 1.0;
  if (hopt_.area_weight > 0.0 && a < mean_root_area_)
    w = std::min(w, std::pow(a / mean_root_area_, hopt_.area_weight));
  return w;
}

double Hierarchical::code_area(int code) const {
  return code >= 0 ? tri_[static_cast<size_t>(code)].area : ct_.cluster(cluster_of(code)).area;
}

// The reflectance the cluster oracle weighs a receiver's error by: its
// largest channel, but 1 for an emitter (an emitter reflects little, yet
// its row says where its power goes in the energy balance); a cluster's
// largest over its members.
double Hierarchical::element_oracle_rho(size_t e) const {
  return max3(emit_[e]) > 0.0 ? 1.0 : max3(rho_[e]);
}

double Hierarchical::code_rho(int code) const {
  return code >= 0 ? element_oracle_rho(static_cast<size_t>(code)) : ct_.cluster(cluster_of(code)).weight;
}

// The mean radiosity (largest channel) of a node: its power per area.
double Hierarchical::code_radiosity(int code) const {
  return max3(code >= 0 ? B_[static_cast<size_t>(code)] : ct_.mean(cluster_of(code), GB_));
}

uint64_t Hierarchical::code_key(int code) const {
  return code >= 0 ? static_cast<uint64_t>(code) : (uint64_t{1} << 40) + static_cast<uint64_t>(cluster_of(code));
}

// A point of node `code` (area-uniform over its roots), its normal, patch
// and root.
// A cluster's roots come from root_samples_, in cluster order: the roots
// a pair's draws fall in then lie together in memory, where their
// triangles and patches, read by root number, would cost cache misses.
void Hierarchical::sample_node(int code, SplitMix& rng, Vec3& x, Vec3& n, int& patch, int& root) const {
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
// dropped, neither linked nor split: parts of one convex object never
// see each other, and linked as fully visible such pairs would be many
// links carrying nothing.
double Hierarchical::cluster_visible(int p, int q, RayCount& count, std::array<float, ClusterTree::kGroups>& per_group) const {
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
const float* Hierarchical::group_visible(const Link& l) const {
  return l.slot >= 0 ? group_visible_.data() + l.slot : nullptr;
}

// The pair's kernel error factor (F bound x size over gap), or a negative
// value when the pair must be split (bounding spheres too close), or 0
// when the two cannot see each other (one wholly behind an element's plane).
double Hierarchical::cluster_shape_error(int p, int q) const {
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
double Hierarchical::cluster_link_error(int p, const Link& l) const {
  const double unseen = l.partial() ? l.f * l.visible : 0.0;
  return cluster_weight(p, l.source) * (l.spread + unseen);
}

bool Hierarchical::wants_cluster_refinement(int p, const Link& l) const {
  return cluster_link_error(p, l) > hopt_.epsilon * scale_;
}

// Queues the pair (a, b). Two elements that cannot see each other (one
// wholly behind the other's plane) are dropped here, as the element
// linking would drop them, instead of waiting in the pair lists: the
// clusters of one convex object, too near one another for the gap rule,
// are split down to their triangles, and on a finely tessellated sphere
// their pairs, nearly all facing away, would fill the lists.
void Hierarchical::queue_pair(int a, int b, std::vector<std::pair<int, int>>& next) {
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
void Hierarchical::split_cluster_pair(int p, int q, std::vector<std::pair<int, int>>& next) {
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
std::vector<std::pair<int, int>> Hierarchical::link_cluster_pairs(std::vector<std::pair<int, int>> todo) {
  std::vector<std::pair<int, int>> elements;
  std::vector<std::pair<int, int>> pairs, next;  // their memory kept from generation to generation
  std::vector<std::array<float, ClusterTree::kGroups>> per_group;  // per pair of a block (evaluate_pairs)
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
    // cluster_visible fills a pair's entry before it is read.
    per_group.resize(std::min(kLinkBlock, pairs.size()));
    evaluate_pairs(
        pairs,
        [&](size_t i, int p, int q, Link& l, RayCount& rays, char& split) {
          const double shape = cluster_shape_error(p, q);
          if (shape == 0.0) return;
          if (shape < 0.0 || cluster_weight(p, q) * shape > hopt_.epsilon * scale_ || small_code(p) ||
              small_code(q)) {
            split = 1;
            return;
          }
          l.spread = shape;
          const double d = glm::length(code_centre(q) - code_centre(p));
          l.f = code_area(q) / (std::numbers::pi * d * d);
          l.visible = cluster_visible(p, q, rays, per_group[i]);
          if (l.visible < 0.0) {
            l.f = 0.0;
            return;
          }
          if (wants_cluster_refinement(p, l)) split = 1;
        },
        [&](size_t i, int p, int q, Link& l, bool split) {
          if (split) {
            split_cluster_pair(p, q, next);
            return;
          }
          if (!(l.f > 0.0)) return;
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
        });
    todo.swap(next);
    check_memory();
  }
  return elements;
}

}  // namespace radmesh::internal
