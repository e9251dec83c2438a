// Rows kept near 1 where clusters approximate. A leaf's row is its exact
// terms (element links) and its approximate part (what its groups gather
// from clusters). The approximate part is scaled, within [0,
// kMaxRowScale], so that an enclosed leaf's row sums to 1 and no leaf's row
// passes 1; the exact terms take a row's miss only up to what their shadow
// rays may be off by (kRowTolerance beside their noise), because a deficit
// beyond that comes from what the rays got wrong and scaling the
// approximate part for it moves light between surfaces. Where a row is over
// 1, the leaf's own samples of its approximate sources (approx_confirmed)
// tell whether the approximate part overstates what the leaf gets or the
// exact terms do, and the part that overstates gives way. The energy and
// reflectance near 1 stay as the exact rows would have them.

#include "radiosity/hierarchical/solver.h"

#include <numbers>

namespace radmesh::internal {

// What cluster links give a leaf: the pushed gathering of the group its
// root belongs to, and that group's form factors.
Rgb Hierarchical::pushed(int leaf) const {
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
Rgb Hierarchical::gathered(size_t leaf) const {
  Rgb exact(0.0), approx(0.0);
  for (const Term& t : terms_[leaf]) exact += static_cast<double>(t.f) * link_value_[static_cast<size_t>(t.q)];
  for (int a = static_cast<int>(leaf); a >= 0; a = out_.tree.node(a).parent) approx += node_H_[static_cast<size_t>(a)];
  return fix_exact_[leaf] * exact_scale_[leaf] * exact + row_scale_[leaf] * (approx + pushed(static_cast<int>(leaf)));
}

// The approximate part of a leaf's form factors, before row_scale_.
double Hierarchical::approx_row_sum(size_t leaf) const {
  double f = F_approx_[leaf];
  if (!ct_.empty()) {
    const int r = out_.tree.node(static_cast<int>(leaf)).root;
    const int g = ct_.root_group(r);
    if (g >= 0)
      for (int k = 0; k < bins_; ++k) f += seen_open(r, k) * FGacc_[bin_index(g, k)];
  }
  return f;
}

double Hierarchical::row_sum(size_t leaf) const {
  return exact_scale_[leaf] * F_sum_[leaf] + row_scale_[leaf] * approx_row_sum(leaf);
}

double Hierarchical::approx_confirmed(size_t x) const {
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

bool Hierarchical::enclosed(size_t leaf) const {
  const Triangle& t = tri_[leaf];
  return visibility_.rays().enclosed(t.centroid(), t.normal, node_patch(static_cast<int>(leaf)),
                                     pair_seed(static_cast<uint64_t>(leaf), 0xE17C105EULL));
}

void Hierarchical::scale_rows() {
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

}  // namespace radmesh::internal
