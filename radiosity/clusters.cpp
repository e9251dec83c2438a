#include "radiosity/clusters.h"

#include <algorithm>
#include <cstddef>
#include <limits>
#include <numbers>

namespace radmesh {

ClusterTree::ClusterTree(const std::vector<Triangle>& roots, const std::vector<double>& weights) {
  const int n = static_cast<int>(roots.size());
  if (n < 2) return;
  order_.resize(roots.size());
  std::vector<Vec3> centroids(roots.size());
  for (int r = 0; r < n; ++r) {
    order_[static_cast<size_t>(r)] = r;
    centroids[static_cast<size_t>(r)] = roots[static_cast<size_t>(r)].centroid();
  }
  clusters_.reserve(roots.size());
  build(0, n, centroids);
  root_group_.assign(roots.size(), -1);
  // Children before parents (parents have the smaller numbers): each
  // cluster's items are its children's groups, merged down to kGroups.
  struct Item {
    Vec3 s{0.0}, moment{0.0};
    double area = 0.0;
    std::vector<std::pair<int, double>> from;  // (root or -2 - group, area)
  };
  for (int c = static_cast<int>(clusters_.size()) - 1; c >= 0; --c) {
    Cluster& cl = clusters_[static_cast<size_t>(c)];
    std::vector<Item> items;
    for (int child : cl.child) {
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
    auto direction = [](const Item& it) {
      const double l = glm::length(it.s);
      return l > 0.0 ? it.s / l : Vec3(0.0);
    };
    while (items.size() > static_cast<size_t>(kGroups)) {
      size_t bi = 0, bj = 1;
      double best = -2.0;
      for (size_t i = 0; i < items.size(); ++i)
        for (size_t j = i + 1; j < items.size(); ++j) {
          const double d = glm::dot(direction(items[i]), direction(items[j]));
          if (d > best) {
            best = d;
            bi = i;
            bj = j;
          }
        }
      Item& a = items[bi];
      a.s += items[bj].s;
      a.moment += items[bj].moment;
      a.area += items[bj].area;
      a.from.insert(a.from.end(), items[bj].from.begin(), items[bj].from.end());
      items.erase(items.begin() + static_cast<std::ptrdiff_t>(bj));
    }
    cl.group_begin = static_cast<int>(groups_.size());
    cl.member_begin = static_cast<int>(members_.size());
    Vec3 moment(0.0);
    for (const Item& it : items) {
      const int g = static_cast<int>(groups_.size());
      groups_.push_back({it.s, it.moment / it.area, it.area, -1});
      for (const auto& [from, a] : it.from) {
        members_.push_back({from, a, g});
        if (from >= 0)
          root_group_[static_cast<size_t>(from)] = g;
        else
          groups_[static_cast<size_t>(-2 - from)].up = g;
      }
      cl.area += it.area;
      moment += it.moment;
    }
    cl.group_end = static_cast<int>(groups_.size());
    cl.member_end = static_cast<int>(members_.size());
    cl.centre = moment / cl.area;
    for (int child : cl.child) {
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

int ClusterTree::build(int begin, int end, const std::vector<Vec3>& centroids) {
  if (end - begin == 1) return order_[static_cast<size_t>(begin)];
  const int c = static_cast<int>(clusters_.size());
  clusters_.emplace_back();
  clusters_.back().begin = begin;
  clusters_.back().end = end;
  Vec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
  for (int i = begin; i < end; ++i) {
    lo = glm::min(lo, centroids[static_cast<size_t>(order_[static_cast<size_t>(i)])]);
    hi = glm::max(hi, centroids[static_cast<size_t>(order_[static_cast<size_t>(i)])]);
  }
  const Vec3 e = hi - lo;
  const int axis = e.x >= e.y && e.x >= e.z ? 0 : (e.y >= e.z ? 1 : 2);
  const int mid = begin + (end - begin) / 2;
  std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end, [&](int a, int b) {
    const double ca = centroids[static_cast<size_t>(a)][axis], cb = centroids[static_cast<size_t>(b)][axis];
    return ca < cb || (ca == cb && a < b);
  });
  const int left = build(begin, mid, centroids);
  const int right = build(mid, end, centroids);
  clusters_[static_cast<size_t>(c)].child = {left, right};
  return code(c);
}

double ClusterTree::bytes(double clusters, double groups) {
  return clusters * (sizeof(Cluster) + sizeof(int) + sizeof(double)) +
         groups * (sizeof(Group) + sizeof(Member) + 3 * sizeof(Rgb) + 2 * sizeof(double) +
                   sizeof(std::vector<std::pair<int, double>>));
}

void ClusterTree::radiosity(const std::vector<Rgb>& root_radiosity, std::vector<Rgb>& group_radiosity) const {
  group_radiosity.resize(groups_.size());
  for (int c = static_cast<int>(clusters_.size()) - 1; c >= 0; --c) {
    const Cluster& cl = clusters_[static_cast<size_t>(c)];
    for (int g = cl.group_begin; g < cl.group_end; ++g) group_radiosity[static_cast<size_t>(g)] = Rgb(0.0);
    for (int k = cl.member_begin; k < cl.member_end; ++k) {
      const Member& m = members_[static_cast<size_t>(k)];
      group_radiosity[static_cast<size_t>(m.group)] +=
          m.area * (m.from >= 0 ? root_radiosity[static_cast<size_t>(m.from)]
                                : group_radiosity[static_cast<size_t>(-2 - m.from)]);
    }
    for (int g = cl.group_begin; g < cl.group_end; ++g)
      group_radiosity[static_cast<size_t>(g)] /= groups_[static_cast<size_t>(g)].area;
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
                               std::vector<std::pair<int, double>>& out, double& f_sum) const {
  const Cluster& cl = cluster(c);
  for (int g = cl.group_begin; g < cl.group_end; ++g) {
    const Group& gr = groups_[static_cast<size_t>(g)];
    const Vec3 r = x - gr.centroid;
    const double d2 = glm::dot(r, r);
    const double out_cos = glm::dot(gr.s, r), in_cos = -glm::dot(n, r);
    if (out_cos <= 0.0 || in_cos <= 0.0) continue;
    const double f = visible * out_cos * in_cos / (std::numbers::pi * d2 * d2);
    out.push_back({-2 - g, f});
    f_sum += f;
  }
}

int ClusterTree::root_at_area(int c, double u) const {
  const Cluster& cl = cluster(c);
  const double lo = cumulative_[static_cast<size_t>(cl.begin)], hi = cumulative_[static_cast<size_t>(cl.end)];
  const double a = lo + u * (hi - lo);
  const auto it = std::upper_bound(cumulative_.begin() + cl.begin + 1, cumulative_.begin() + cl.end, a);
  return order_[static_cast<size_t>(it - cumulative_.begin() - 1)];
}

}  // namespace radmesh
