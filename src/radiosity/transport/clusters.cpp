// The cluster tree above the patches or the initial triangles: a volume
// hierarchy (or Tanaka and Noma's shape approximation), each cluster with
// oriented normal groups whose form factors, straddle and radiosity stand
// for its members seen from afar.

#include "radiosity/transport/clusters.h"

#include "core/snap.h"
#include "radiosity/transport/sampling.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <numbers>
#include <unordered_map>

namespace radmesh {

namespace {

// The node over order[begin, end): a root, or a new tree node (code -2 - t)
// splitting them at the median of their centroids on the longest axis.
int median_split(int begin, int end, std::vector<int>& order, const std::vector<Vec3>& centroids,
                 std::vector<std::vector<int>>& tree) {
  if (end - begin == 1) return order[static_cast<size_t>(begin)];
  const int t = static_cast<int>(tree.size());
  tree.emplace_back();
  Vec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
  for (int i = begin; i < end; ++i) {
    lo = glm::min(lo, centroids[static_cast<size_t>(order[static_cast<size_t>(i)])]);
    hi = glm::max(hi, centroids[static_cast<size_t>(order[static_cast<size_t>(i)])]);
  }
  const Vec3 e = hi - lo;
  const int axis = e.x >= e.y && e.x >= e.z ? 0 : (e.y >= e.z ? 1 : 2);
  const int mid = begin + (end - begin) / 2;
  std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end, [&](int a, int b) {
    const double ca = centroids[static_cast<size_t>(a)][axis], cb = centroids[static_cast<size_t>(b)][axis];
    return ca < cb || (ca == cb && a < b);
  });
  const int left = median_split(begin, mid, order, centroids, tree);
  const int right = median_split(mid, end, order, centroids, tree);
  tree[static_cast<size_t>(t)] = {left, right};
  return ClusterTree::code(t);
}

// An octree cell: 21 bits per axis.
using Cell = uint64_t;
constexpr size_t made_none = std::numeric_limits<size_t>::max();
constexpr Cell parent_cell(Cell c) {
  constexpr Cell mask = (Cell{1} << 21) - 1;
  return (((c >> 42) >> 1) << 42) | ((((c >> 21) & mask) >> 1) << 21) | ((c & mask) >> 1);
}
struct CellsHash {
  size_t operator()(const std::array<Cell, 3>& k) const {
    uint64_t h = 0x9E3779B97F4A7C15ULL;
    for (Cell c : k) h = (h ^ c) * 0xBF58476D1CE4E5B9ULL + (h >> 29);
    return static_cast<size_t>(h ^ (h >> 31));
  }
};

}  // namespace

ClusterTree ClusterTree::volume(const std::vector<Triangle>& roots, const std::vector<double>& weights) {
  ClusterTree ct;
  const int n = static_cast<int>(roots.size());
  if (n < 2) return ct;
  std::vector<int> order(roots.size());
  std::vector<Vec3> centroids(roots.size());
  for (int r = 0; r < n; ++r) {
    order[static_cast<size_t>(r)] = r;
    centroids[static_cast<size_t>(r)] = roots[static_cast<size_t>(r)].centroid();
  }
  // The splits compare centroids and extents, whose ties decide.
  centroids = internal::snapped_keys(centroids);
  std::vector<std::vector<int>> tree;
  tree.reserve(roots.size());
  median_split(0, n, order, centroids, tree);
  ct.finish(tree, roots, weights);
  return ct;
}

ClusterTree ClusterTree::shape(const std::vector<Triangle>& roots, const std::vector<double>& weights) {
  ClusterTree ct;
  const size_t n = roots.size();
  if (n < 2) return ct;
  Vec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
  double shortest = std::numeric_limits<double>::infinity();
  for (const Triangle& t : roots)
    for (int k = 0; k < 3; ++k) {
      lo = glm::min(lo, t.v[static_cast<size_t>(k)]);
      hi = glm::max(hi, t.v[static_cast<size_t>(k)]);
      const double e = glm::length(t.v[static_cast<size_t>(k)] - t.v[static_cast<size_t>((k + 1) % 3)]);
      if (e > 0.0) shortest = std::min(shortest, e);
    }
  const double size = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
  // The finest level: cells no wider than the shortest edge (at most 2^21
  // a side).
  int depth = 1;
  while (depth < 21 && size / static_cast<double>(Cell{1} << depth) > shortest) ++depth;
  // Positions in units of the extent, snapped (internal::snap_unit), so
  // that a point on a cell's edge falls the same way in a scaled or moved
  // scene.
  const double scale = static_cast<double>(Cell{1} << depth) / (1.0 + 1e-12);
  const auto last = static_cast<double>((Cell{1} << depth) - 1);
  auto cell = [&](const Vec3& p) {
    Cell c = 0;
    for (int a = 0; a < 3; ++a)
      c = (c << 21) |
          static_cast<Cell>(std::clamp(std::floor(internal::snap_unit((p[a] - lo[a]) / size) * scale), 0.0, last));
    return c;
  };
  struct Entry {
    int code;  // a root or a tree node (-2 - t)
    std::array<Cell, 3> cells;  // where its corners fall at the current level
  };
  std::vector<Entry> frontier(n);
  for (size_t r = 0; r < n; ++r)
    frontier[r] = {static_cast<int>(r), {cell(roots[r].v[0]), cell(roots[r].v[1]), cell(roots[r].v[2])}};
  std::vector<std::vector<int>> tree(1);  // node 0: the top
  for (int level = depth - 1; level >= 0 && frontier.size() > 1; --level) {
    // This level's triangles, in the order first met (so the tree does
    // not depend on hashing), with the entries mapping to each.
    struct Made {
      std::array<Cell, 3> cells;
      std::vector<size_t> members;
    };
    std::vector<Made> made;
    std::unordered_map<std::array<Cell, 3>, size_t, CellsHash> made_at;
    std::vector<size_t> degenerate;
    for (size_t i = 0; i < frontier.size(); ++i) {
      std::array<Cell, 3>& c = frontier[i].cells;
      for (Cell& x : c) x = parent_cell(x);
      std::sort(c.begin(), c.end());
      if (c[0] == c[1] || c[1] == c[2]) {
        degenerate.push_back(i);
        continue;
      }
      const auto [it, fresh] = made_at.try_emplace(c, made.size());
      if (fresh) made.push_back({c, {}});
      made[it->second].members.push_back(i);
    }
    // A segment or point hangs under the first triangle having it.
    std::unordered_map<std::array<Cell, 3>, size_t, CellsHash> edge, corner;
    for (size_t m = 0; m < made.size(); ++m) {
      const auto& c = made[m].cells;
      edge.try_emplace({c[0], c[1], 0}, m);
      edge.try_emplace({c[0], c[2], 0}, m);
      edge.try_emplace({c[1], c[2], 0}, m);
      for (Cell x : c) corner.try_emplace({x, 0, 0}, m);
    }
    std::vector<Entry> next;
    next.reserve(made.size() + degenerate.size());
    for (size_t i : degenerate) {
      const auto& c = frontier[i].cells;
      const Cell a = c[0], b = c[1] == c[0] ? c[2] : c[1];
      auto find = [](const auto& map, const std::array<Cell, 3>& key) {
        const auto it = map.find(key);
        return it == map.end() ? made_none : it->second;
      };
      size_t to = a != b ? find(edge, {a, b, 0}) : made_none;
      if (to == made_none) to = find(corner, {a, 0, 0});
      if (to == made_none) to = find(corner, {b, 0, 0});
      if (to != made_none)
        made[to].members.push_back(i);
      else
        next.push_back(frontier[i]);  // tries again a level up
    }
    for (const Made& m : made) {
      if (m.members.size() == 1) {
        next.push_back({frontier[m.members[0]].code, m.cells});
        continue;
      }
      const int t = static_cast<int>(tree.size());
      tree.emplace_back();
      tree.back().reserve(m.members.size());
      for (size_t i : m.members) tree.back().push_back(frontier[i].code);
      next.push_back({code(t), m.cells});
    }
    frontier = std::move(next);
  }
  if (frontier.size() == 1 && frontier[0].code < 0) {
    tree[0] = std::move(tree[static_cast<size_t>(index(frontier[0].code))]);
  } else {
    for (const Entry& e : frontier) tree[0].push_back(e.code);
  }
  ct.finish(tree, roots, weights);
  return ct;
}

int ClusterTree::lay_out(int t, const std::vector<std::vector<int>>& tree) {
  const int c = static_cast<int>(clusters_.size());
  clusters_.emplace_back();
  clusters_.back().begin = static_cast<int>(order_.size());
  std::vector<int> codes;
  codes.reserve(tree[static_cast<size_t>(t)].size());
  for (int k : tree[static_cast<size_t>(t)]) {
    if (k >= 0) {
      order_.push_back(k);
      codes.push_back(k);
    } else {
      codes.push_back(code(lay_out(index(k), tree)));
    }
  }
  Cluster& cl = clusters_[static_cast<size_t>(c)];
  cl.end = static_cast<int>(order_.size());
  cl.child_begin = static_cast<int>(children_.size());
  children_.insert(children_.end(), codes.begin(), codes.end());
  cl.child_end = static_cast<int>(children_.size());
  return c;
}

namespace {
// The unit vector along a group's s (sum of area x normal), or 0.
Vec3 direction_of(const Vec3& s) {
  const double l = glm::length(s);
  return l > 0.0 ? s / l : Vec3(0.0);
}
}  // namespace

void ClusterTree::finish(const std::vector<std::vector<int>>& tree, const std::vector<Triangle>& roots,
                         const std::vector<double>& weights) {
  clusters_.reserve(tree.size());
  order_.reserve(roots.size());
  children_.reserve(tree.size() + roots.size());
  lay_out(0, tree);
  root_group_.assign(roots.size(), -1);
  // Children before parents (parents have the smaller numbers): each
  // cluster's items are its children's groups, merged down to kGroups.
  struct Item {
    Vec3 s{0.0}, moment{0.0};
    double area = 0.0;
    std::vector<std::pair<int, double>> from;  // (root or -2 - group, area)
    void absorb(Item& o) {
      s += o.s;
      moment += o.moment;
      area += o.area;
      from.insert(from.end(), o.from.begin(), o.from.end());
    }
  };
  auto direction = [](const Item& it) { return direction_of(it.s); };
  for (int c = static_cast<int>(clusters_.size()) - 1; c >= 0; --c) {
    Cluster& cl = clusters_[static_cast<size_t>(c)];
    std::vector<Item> items;
    for (int child : children(c)) {
      if (child >= 0) {
        const Triangle& t = roots[static_cast<size_t>(child)];
        items.push_back({t.area * t.normal, t.area * t.centroid(), t.area, {{child, t.area}}});
        cl.weight = std::max(cl.weight, weights[static_cast<size_t>(child)]);
      } else {
        const Cluster& ch = clusters_[static_cast<size_t>(index(child))];
        for (int g = ch.group_begin; g < ch.group_end; ++g) {
          const Group& gr = groups_[static_cast<size_t>(g)];
          items.push_back({gr.s, gr.area * gr.centroid, gr.area, {{-2 - g, gr.area}}});
        }
        cl.weight = std::max(cl.weight, ch.weight);
      }
    }
    // Many items (a shape cluster of many children): first merged per the
    // nearest of the 26 directions of a cube's faces, edges and corners
    // (and those with no net normal together), so that the greedy merge
    // below stays cheap.
    if (items.size() > static_cast<size_t>(4 * kGroups)) {
      std::vector<Item> binned;
      std::vector<int> bin_of(27, -1);
      for (Item& it : items) {
        const Vec3 d = direction(it);
        int bin = 0;
        for (int a = 0; a < 3; ++a) bin = 3 * bin + (d[a] > 0.38 ? 2 : (d[a] < -0.38 ? 0 : 1));
        int& b = bin_of[static_cast<size_t>(bin)];
        if (b < 0) {
          b = static_cast<int>(binned.size());
          binned.push_back(std::move(it));
        } else {
          binned[static_cast<size_t>(b)].absorb(it);
        }
      }
      items = std::move(binned);
    }
    // The pair nearest in direction merges first; their cosines snapped,
    // so that ties (a floor's triangles, all facing up) go to the first
    // pair in a scaled or moved scene as well.
    while (items.size() > static_cast<size_t>(kGroups)) {
      size_t bi = 0, bj = 1;
      double best = -2.0;
      for (size_t i = 0; i < items.size(); ++i)
        for (size_t j = i + 1; j < items.size(); ++j) {
          const double d = internal::snap_unit(glm::dot(direction(items[i]), direction(items[j])));
          if (d > best) {
            best = d;
            bi = i;
            bj = j;
          }
        }
      items[bi].absorb(items[bj]);
      items.erase(items.begin() + static_cast<std::ptrdiff_t>(bj));
    }
    cl.group_begin = static_cast<int>(groups_.size());
    cl.member_begin = static_cast<int>(members_.size());
    Vec3 moment(0.0);
    for (const Item& it : items) {
      const int g = static_cast<int>(groups_.size());
      groups_.push_back({it.s, it.moment / it.area, it.area, -1, 0.0f, c});
      const Vec3 axis = direction(it);
      double cone = glm::length(axis) > 0.0 ? 0.0 : std::numbers::pi;
      for (const auto& [from, a] : it.from) {
        members_.push_back({from, a, g});
        const Vec3 n = from >= 0 ? roots[static_cast<size_t>(from)].normal : direction_of(groups_[static_cast<size_t>(-2 - from)].s);
        const double own = from >= 0 ? 0.0 : groups_[static_cast<size_t>(-2 - from)].cone;
        if (cone < std::numbers::pi)
          cone = std::max(cone, std::acos(std::clamp(glm::dot(axis, n), -1.0, 1.0)) + own);
        if (from >= 0)
          root_group_[static_cast<size_t>(from)] = g;
        else
          groups_[static_cast<size_t>(-2 - from)].up = g;
      }
      groups_[static_cast<size_t>(g)].cone = static_cast<float>(std::min(cone, std::numbers::pi));
      cl.area += it.area;
      moment += it.moment;
    }
    cl.group_end = static_cast<int>(groups_.size());
    cl.member_end = static_cast<int>(members_.size());
    cl.centre = moment / cl.area;
    for (int child : children(c)) {
      if (child >= 0) {
        for (const Vec3& v : roots[static_cast<size_t>(child)].v) cl.radius = std::max(cl.radius, glm::length(v - cl.centre));
      } else {
        const Cluster& ch = clusters_[static_cast<size_t>(index(child))];
        cl.radius = std::max(cl.radius, glm::length(ch.centre - cl.centre) + ch.radius);
      }
    }
  }
  cumulative_.assign(roots.size() + 1, 0.0);
  for (size_t i = 0; i < roots.size(); ++i)
    cumulative_[i + 1] = cumulative_[i] + roots[static_cast<size_t>(order_[i])].area;
}

double ClusterTree::bytes(double clusters, double groups) {
  return clusters * (sizeof(Cluster) + 3 * sizeof(int) + sizeof(double)) +
         groups * (sizeof(Group) + sizeof(Member) + 3 * sizeof(Rgb) + 2 * sizeof(double) +
                   sizeof(std::vector<std::pair<int, double>>));
}

void ClusterTree::radiosity(const std::vector<Rgb>& root_radiosity, std::vector<Rgb>& group_radiosity,
                            const std::vector<double>* root_weight, const std::vector<double>* group_weight) const {
  group_radiosity.resize(groups_.size());
  std::array<Rgb, kGroups> plain;
  std::array<double, kGroups> weight;
  for (int c = static_cast<int>(clusters_.size()) - 1; c >= 0; --c) {
    const Cluster& cl = clusters_[static_cast<size_t>(c)];
    plain.fill(Rgb(0.0));
    weight.fill(0.0);
    for (int g = cl.group_begin; g < cl.group_end; ++g) group_radiosity[static_cast<size_t>(g)] = Rgb(0.0);
    for (int k = cl.member_begin; k < cl.member_end; ++k) {
      const Member& m = members_[static_cast<size_t>(k)];
      const Rgb b = m.from >= 0 ? root_radiosity[static_cast<size_t>(m.from)] : group_radiosity[static_cast<size_t>(-2 - m.from)];
      const size_t i = static_cast<size_t>(m.group - cl.group_begin);
      plain[i] += m.area * b;
      if (!root_weight) continue;
      const double w = m.area * (m.from >= 0 ? (*root_weight)[static_cast<size_t>(m.from)]
                                             : (*group_weight)[static_cast<size_t>(-2 - m.from)]);
      group_radiosity[static_cast<size_t>(m.group)] += w * b;
      weight[i] += w;
    }
    for (int g = cl.group_begin; g < cl.group_end; ++g) {
      const size_t i = static_cast<size_t>(g - cl.group_begin);
      Rgb& out = group_radiosity[static_cast<size_t>(g)];
      out = weight[i] > 0.0 ? out / weight[i] : plain[i] / groups_[static_cast<size_t>(g)].area;
    }
  }
}

Rgb ClusterTree::mean(int c, const std::vector<Rgb>& group_radiosity) const {
  const Cluster& cl = cluster(c);
  Rgb sum(0.0);
  for (int g = cl.group_begin; g < cl.group_end; ++g)
    sum += groups_[static_cast<size_t>(g)].area * group_radiosity[static_cast<size_t>(g)];
  return sum / cl.area;
}

void ClusterTree::form_factors(int c, const Vec3& x, const Vec3& n, double visible,
                               std::vector<std::pair<int, double>>& out, const float* per_group) const {
  const Cluster& cl = cluster(c);
  for (int g = cl.group_begin; g < cl.group_end; ++g) {
    const Group& gr = groups_[static_cast<size_t>(g)];
    const Vec3 r = x - gr.centroid;
    const double d2 = glm::dot(r, r);
    const double out_cos = glm::dot(gr.s, r), in_cos = -glm::dot(n, r);
    if (out_cos <= 0.0 || in_cos <= 0.0) continue;
    const double seen = per_group ? per_group[g - cl.group_begin] : visible;
    if (!(seen > 0.0)) continue;
    const double f = seen * out_cos * in_cos / (std::numbers::pi * d2 * d2);
    out.push_back({-2 - g, f});
  }
}

double ClusterTree::straddle(int c, const Vec3& x, double rx) const {
  const Cluster& cl = cluster(c);
  double wrong = 0.0;
  for (int g = cl.group_begin; g < cl.group_end; ++g) {
    const Group& gr = groups_[static_cast<size_t>(g)];
    if (gr.cone == 0.0f) continue;  // flat: exact
    const Vec3 r = x - gr.centroid;
    const double d = glm::length(r);
    if (!(d > rx)) {  // x's sphere holds the centroid: any direction
      wrong += gr.area;
      continue;
    }
    // Angles from the axis: the direction's, widened by the sphere's
    // angular radius, plus the cone.
    const double len = glm::length(gr.s);
    const double cos_a = len > 0.0 ? glm::dot(gr.s, r) / (len * d) : 0.0;
    const double a = std::acos(std::clamp(cos_a, -1.0, 1.0));
    const double spread = static_cast<double>(gr.cone) + std::asin(std::min(1.0, rx / d));
    const double near = a - spread, far = a + spread;  // the cone's nearest and furthest normals from w
    if (near >= 0.5 * std::numbers::pi || far <= 0.5 * std::numbers::pi) continue;  // all away, or all facing
    // Facing overall: the members turned away cost up to area x -cos(far);
    // turned away overall: those facing w are lost, up to area x cos(near).
    wrong += gr.area * (cos_a >= 0.0 ? -std::cos(std::min(far, std::numbers::pi)) : std::cos(std::max(near, 0.0)));
  }
  return wrong;
}

int ClusterTree::position_at_area(int c, double u) const {
  const Cluster& cl = cluster(c);
  const double lo = cumulative_[static_cast<size_t>(cl.begin)], hi = cumulative_[static_cast<size_t>(cl.end)];
  return area_index(cumulative_.data(), cl.begin, cl.end, lo + u * (hi - lo), u);
}

int ClusterTree::root_at_area(int g, double u) const {
  for (;;) {
    const Cluster& cl = cluster(group(g).cluster);
    double total = 0.0;
    for (int k = cl.member_begin; k < cl.member_end; ++k)
      if (members_[static_cast<size_t>(k)].group == g) total += members_[static_cast<size_t>(k)].area;
    double at = u * total;
    const Member* pick = nullptr;
    for (int k = cl.member_begin; k < cl.member_end; ++k) {
      const Member& m = members_[static_cast<size_t>(k)];
      if (m.group != g) continue;
      pick = &m;
      if (at < m.area) break;
      at -= m.area;
    }
    if (pick->from >= 0) return pick->from;
    u = pick->area > 0.0 ? std::clamp(at / pick->area, 0.0, 1.0 - 1e-12) : 0.0;
    g = -2 - pick->from;
  }
}

}  // namespace radmesh
