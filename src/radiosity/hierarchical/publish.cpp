// Publishing a round: the conforming mesh (the leaves, then zero-area
// triangles closing every T-vertex), its element and vertex values, the
// T-vertex jump, and the energy balance (emitted = absorbed + escaped, where
// escaped is what the leaves send that no row carries).

#include "radiosity/hierarchical/solver.h"

#include <unordered_map>

namespace radmesh::internal {

// The deepest node that existed in the previous round on the path to n.
int Hierarchical::nearest_old(int n, size_t old_count) const {
  while (n >= 0 && static_cast<size_t>(n) >= old_count) n = out_.tree.node(n).parent;
  return n;
}

// Fills the output: conforming mesh, per-triangle values, vertex values,
// counts and the energy balance.
void Hierarchical::publish() {
  publish_mesh();
  publish_balance();
}

// The conforming mesh, its per-triangle values, vertex values and counts
// (the solution's statistics are kept).
void Hierarchical::publish_mesh() {
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
void Hierarchical::publish_balance() {
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
std::vector<double> Hierarchical::sent_rows() const {
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

}  // namespace radmesh::internal
