// The clusters above the roots (ClusterMode volume or shape): the cluster
// tree with its normal groups, the roots' openness and direction bins that
// share what a group gathers among its members, and the groups' values
// updated from the leaves.

#include "radiosity/hierarchical/solver.h"

namespace radmesh::internal {

void Hierarchical::build_clusters() {
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

void Hierarchical::openness() {
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
int Hierarchical::direction_bin(const Vec3& d) {
  const Vec3 a = glm::abs(d);
  const int axis = a.x >= a.y && a.x >= a.z ? 0 : (a.y >= a.z ? 1 : 2);
  return 2 * axis + (d[axis] > 0.0 ? 1 : 0);
}

// The openness of node m (see openness()). With `bins` (kDirectionBins
// of them, `shape` clusters), also its visibility per direction bin: of
// its rays in the bin, the fraction that are open and meet nothing within
// `reach` (its siblings); its fraction over all the rays counts as one
// more ray of every bin, so a bin with no ray takes that.
double Hierarchical::openness_of(int m, double reach, float* bins) const {
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
double Hierarchical::bin_bytes(double groups, double roots) const {
  return groups * ((bins_ - 1.0) * (2.0 * sizeof(Rgb) + 2.0 * sizeof(double)) + bins_ * sizeof(double)) +
         roots * bins_ * sizeof(float);
}

// The area over which group g's mean radiosity weighs its members, each
// leaf by its area x its root's openness (all of it for a group shut in,
// whose mean is the plain one: see update_groups).
double Hierarchical::sending_area(int g) const {
  const double open = group_open_[static_cast<size_t>(g)];
  return ct_.group(g).area * (open > 0.0 ? open : 1.0);
}

// Group radiosity from the roots' (area means of their leaves), each
// root weighed by its openness (see openness()).
void Hierarchical::update_groups() {
  if (!ct_.empty()) ct_.radiosity(B_, GB_, &open_, &group_open_);
}

}  // namespace radmesh::internal
