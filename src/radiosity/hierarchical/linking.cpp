// Element links and the oracle: every receiver linked to its sources,
// refined first where the oracle asks (breadth first, one generation of
// pairs at a time, each generation evaluated in parallel and decided in
// order), the links numbered for the terms that refer to them, and the
// refinement of existing links between rounds (with the rule that makes no
// round for marginal refinements).

#include "radiosity/hierarchical/solver.h"

namespace radmesh::internal {

// F(p -> q) without occlusion, from points on p graded toward q (the
// caller, link_pairs, has dropped pairs facing away).
double Hierarchical::form_factor_to(int p, int q) const {
  const Triangle& a = tri_[static_cast<size_t>(p)];
  const Triangle& b = tri_[static_cast<size_t>(q)];
  const ReceiverPoints pts =
      receiver_points(a, [&](const Vec3& x) { return distance_to_triangle(x, b); }, quadrature_);
  return form_factor(pts, b);
}

// Links every receiver p to its source q, refining first where the oracle
// asks: breadth first, one generation of pairs at a time.
void Hierarchical::link_pairs(std::vector<std::pair<int, int>> todo) {
  std::vector<std::pair<int, int>> next;  // its memory kept from generation to generation
  while (!todo.empty()) {
    next.clear();
    evaluate_pairs(
        todo,
        [&](size_t, int p, int q, Link& l, RayCount& rays, char& split) {
          if (facing_away(tri_[static_cast<size_t>(p)], tri_[static_cast<size_t>(q)])) return;  // F = 0
          const std::array<double, 4> corner_f = corner_form_factors(p, q);
          if (split_by_corners(p, q, corner_f)) {
            split = 1;
            return;
          }
          l.f = form_factor_to(p, q);
          if (l.f <= 0.0) return;
          l.spread = spread(corner_f, l.f);
          if (split_whatever_visible(p, l)) return;  // no rays: they would not change the decision
          l.visible = visibility_.visible_fraction(tri_[static_cast<size_t>(p)], node_patch(p), static_cast<uint64_t>(p),
                                                   tri_[static_cast<size_t>(q)], node_patch(q), static_cast<uint64_t>(q),
                                                   rays);
        },
        [&](size_t, int p, int, const Link& l, bool split) {
          if (split) {
            split_pair(p, l.source, true, next);  // split_by_corners: one of them is splittable
            return;
          }
          if (!std::isfinite(l.f) || !std::isfinite(l.spread))
            throw NumericalError(scene_.source + ": link from node " + std::to_string(l.source) + " to node " +
                                 std::to_string(p) + " has a non-finite form factor");
          if (l.f <= 0.0) return;
          if (wants_refinement(p, l) && split_pair(p, l.source, spread_dominates(l), next)) return;
          store_element_link(p, l);
        });
    todo.swap(next);
    check_memory();
  }
}

// An element-to-element link is numbered when stored (numbers of removed
// links are used again), and its source's leaves must count it among
// what they send (sender_terms).
void Hierarchical::store_element_link(int p, Link l) {
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

void Hierarchical::release_element_link(const Link& l) {
  free_ids_.push_back(l.slot);
  sent_dirty_[static_cast<size_t>(l.source)] = 1;
}

// The point form factors to q at p's corners and centroid.
std::array<double, 4> Hierarchical::corner_form_factors(int p, int q) const {
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
double Hierarchical::spread(const std::array<double, 4>& corner_f, double f) {
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
// nothing of q (a source cutting p's plane near a corner): that pair is
// split.
bool Hierarchical::split_by_corners(int p, int q, const std::array<double, 4>& corner_f) const {
  if (!(splittable(p) || splittable(q))) return false;
  double lo = corner_f[0], hi = corner_f[0];
  for (const double pf : corner_f) {
    if (!std::isfinite(pf)) return false;
    lo = std::min(lo, pf);
    hi = std::max(hi, pf);
  }
  return hi > 4.0 * lo && element_weight(p, q) * 0.5 * (hi - lo) > (1.0 + 1e-6) * hopt_.epsilon * scale_;
}

// A pair whose spread alone makes the oracle refine it, and decides that
// the receiver is split first, is split whatever its shadow rays say
// (wants_refinement and spread_dominates hold for every visible fraction,
// and with l.visible left at 1 they see the same): its rays are not cast.
// split_by_corners finds most such pairs before their F.
bool Hierarchical::split_whatever_visible(int p, const Link& l) const {
  return element_weight(p, l.source) * l.spread > hopt_.epsilon * scale_ && l.spread > 0.5 * l.f &&
         (splittable(p) || splittable(l.source));
}

// The oracle: the error of gathering over this link at this level, as
// rho_p * B_q * (spread of F over p), plus the whole transport
// rho_p B_q F V when the link is partly visible (a shadow boundary crosses it).
double Hierarchical::link_error(int p, const Link& l) const {
  const double unseen = l.partial() ? l.f * l.visible : 0.0;
  return element_weight(p, l.source) * (l.spread + unseen);
}

// What the oracle multiplies a link's form-factor error by: rho_p B_q,
// weighed by the receiver's area (pw).
double Hierarchical::element_weight(int p, int q) const {
  return max3(rho_[static_cast<size_t>(p)]) * max3(B_[static_cast<size_t>(q)]) * pw(p);
}

// Splits the receiver p when the form factor varies over it (the spread
// is what pushing down gets wrong) or it is the larger, else the source q,
// and queues the children's pairs instead. Returns false when neither may
// be split.
bool Hierarchical::split_pair(int p, int q, bool receiver_first, std::vector<std::pair<int, int>>& next) {
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

// Says so among the skips: at each publish (which starts them anew) and
// when step() leaves them, the last count standing.
void Hierarchical::report_left() {
  auto& skips = out_.solution.stats.skips;
  const std::string tag = "refinement: ";
  std::erase_if(skips, [&](const std::string& k) { return k.rfind(tag, 0) == 0; });
  if (left_.links > 0)
    skips.push_back(tag + std::to_string(left_.links) + " links over the oracle's threshold by at most " +
                    format_number(left_.worst) + "x (marginal_refinement " +
                    format_number(hopt_.marginal_refinement) +
                    ") were not refined: a round for them changes their receivers by about what the oracle leaves on every link");
}

Hierarchical::Wanted Hierarchical::wanted_refinement() const {
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
double Hierarchical::refinement_error(int p, const Link& l) const {
  if (l.source < 0) return cluster_link_error(p, l);
  return splittable(p) || splittable(l.source) ? link_error(p, l) : 0.0;
}

// Refines every link the oracle now flags (with the current radiosity).
long long Hierarchical::refine_links() {
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

long long Hierarchical::count_links() const {
  long long c = 0;
  for (const auto& l : links_) c += static_cast<long long>(l.size());
  for (const auto& l : clinks_) c += static_cast<long long>(l.size());
  return c;
}

}  // namespace radmesh::internal
