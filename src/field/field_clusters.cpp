// The display field's clustered gather (see FieldEvaluator in
// radmesh/field.h): a cluster tree whose roots stand for the reflecting
// patches, built over their source trees, and the gather at a point that
// takes far clusters whole and opens the others down to the patches, which
// the gather over one patch (field.cpp) takes. The evaluator's state is
// field_impl.h.

#include "field/field_impl.h"

#include <algorithm>
#include <cmath>

namespace radmesh {

using internal::SourceTree;

void FieldEvaluator::Impl::build_clusters() {
  // One root per reflecting patch: a stand-in triangle in its plane with
  // its area, normal and area centroid, its corners as far from that
  // centroid as the patch's furthest vertex (the cluster tree takes that
  // for the root's radius).
  std::vector<Triangle> roots;
  std::vector<Box3> root_box;
  for (size_t p = 0; p < sources.size(); ++p) {
    const SourceTree& s = sources[p];
    if (s.nodes.empty()) continue;
    const Vec3 c = s.nodes[0].centre;
    double r = 0.0;
    Box3 box;
    for (const Triangle& t : s.triangle)
      for (const Vec3& v : t.v) {
        r = std::max(r, glm::length(v - c));
        box.add(v);
      }
    root_box.push_back(box);
    const Vec3 u = glm::normalize(glm::cross(s.normal, std::abs(s.normal.x) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0)));
    const Vec3 w = glm::cross(s.normal, u);
    const double h = 0.5 * std::sqrt(3.0);
    Triangle t;
    t.v = {c + r * u, c + r * (-0.5 * u + h * w), c + r * (-0.5 * u - h * w)};
    t.normal = s.normal;
    t.area = s.nodes[0].area;
    t.radius = r;
    roots.push_back(t);
    cluster_patch.push_back(static_cast<int>(p));
    cluster_plane.emplace_back(s.normal, -glm::dot(s.normal, s.triangle[0].v[0]));
  }
  if (roots.size() < 2) {
    cluster_patch.clear();
    cluster_plane.clear();
    return;
  }
  clusters = ClusterTree::volume(roots, std::vector<double>(roots.size(), 1.0));
  cluster_reach.assign(clusters.size(), 0.0);
  cluster_box.assign(clusters.size(), Box3{});
  for (int c = static_cast<int>(clusters.size()) - 1; c >= 0; --c) {
    const Vec3& centre = clusters.cluster(c).centre;
    double& reach = cluster_reach[static_cast<size_t>(c)];
    Box3& box = cluster_box[static_cast<size_t>(c)];
    for (const int child : clusters.children(c)) {
      if (child >= 0) {
        const Triangle& t = roots[static_cast<size_t>(child)];
        reach = std::max(reach, glm::length(t.centroid() - centre) + t.radius);
        box.add(root_box[static_cast<size_t>(child)]);
      } else {
        const int k = ClusterTree::index(child);
        reach = std::max(reach, glm::length(clusters.cluster(k).centre - centre) + cluster_reach[static_cast<size_t>(k)]);
        box.add(cluster_box[static_cast<size_t>(k)]);
      }
    }
  }
  std::vector<Rgb> root_reflected;
  for (const int p : cluster_patch) root_reflected.push_back(sources[static_cast<size_t>(p)].nodes[0].reflected);
  clusters.radiosity(root_reflected, group_reflected);
}

// What x gathers from every source patch by the cluster tree over them: a
// cluster far enough (its patches within a sphere of radius at most
// kClusterOpening x its distance), wholly in front of x's tangent plane and
// with groups whose normals do not straddle the direction to x by more than
// kClusterStraddle of its area, is taken whole: its groups' form factors
// (ClusterTree::form_factors) times the kernel-weighted mean of V R over
// area-stratified points of its patches (rays_for, at least rays_per_node),
// one random stream per (point, cluster). A cluster wholly behind the plane
// gives nothing; any other is opened, down to the patches, which
// gather_patch takes.
Rgb FieldEvaluator::Impl::gather_clustered(const Vec3& x, const Vec3& n, int patch, uint64_t id, double full,
                                           FieldReport& report) const {
  struct Far {
    double f = 0.0;   // the cluster's form factor
    Rgb send{0.0};    // f x its groups' radiosity, where no rays are cast
    size_t begin = 0, end = 0;  // its samples
    double weight = 0.0;        // of the samples
  };
  thread_local std::vector<int> stack;
  thread_local std::vector<Far> far;
  thread_local std::vector<std::pair<int, double>> found;
  thread_local Samples samples;
  thread_local std::vector<int> sample_patch;
  thread_local std::vector<Vec3> from;
  thread_local std::vector<unsigned char> seen;
  far.clear();
  samples.clear();
  sample_patch.clear();
  Rgb h(0.0);
  const double flat = 1e-9 * diagonal;  // heights within this of x's plane count as on it
  stack.assign(1, 0);
  while (!stack.empty()) {
    const int c = stack.back();
    stack.pop_back();
    const ClusterTree::Cluster& cl = clusters.cluster(c);
    const double reach = cluster_reach[static_cast<size_t>(c)];
    const double d = glm::length(cl.centre - x);
    // The heights of its box's corners over x's tangent plane (points on
    // the plane send x nothing: a box standing on the floor under x is
    // wholly in front of it).
    const Box3& box = cluster_box[static_cast<size_t>(c)];
    double low = INFINITY, high = -INFINITY;
    for (int k = 0; k < 8; ++k) {
      const Vec3 corner((k & 1) ? box.hi.x : box.lo.x, (k & 2) ? box.hi.y : box.lo.y, (k & 4) ? box.hi.z : box.lo.z);
      const double hk = glm::dot(corner - x, n);
      low = std::min(low, hk);
      high = std::max(high, hk);
    }
    if (high <= flat) continue;  // wholly behind x's tangent plane, or in it
    if (low >= -flat && reach <= kClusterOpening * d && clusters.straddle(c, x, 0.0) <= kClusterStraddle * cl.area) {
      ++report.gather_clusters;
      found.clear();
      clusters.form_factors(c, x, n, 1.0, found);
      Far t;
      for (const auto& [g, f] : found) {
        t.f += f;
        t.send += f * group_reflected[static_cast<size_t>(-2 - g)];
      }
      if (!(t.f > 0.0)) continue;
      if (visibility) {
        // Area-stratified points of the cluster's patches, each weighed by
        // the point form factor's kernel there, their rays cast below. A
        // point where the kernel is 0 (on a patch facing away from x: the
        // far sides of boxes) is drawn again, up to kDrawTries times, since a
        // cluster whose points all fall there gives nothing though its
        // groups facing x send light. As many points as rays_for gives, and
        // at least rays_per_node: a cluster's groups differ in radiosity and
        // kernel (a box's lit top, its dim sides), and the few points of a
        // small share, taken by area, would stand for the groups by area
        // instead of by kernel.
        SplitMix rng(pair_seed(pair_seed(id, uint64_t{1} << 40), static_cast<uint64_t>(c)));
        const int k = std::max(rays_per_node, rays_for(max3(t.send), full));
        t.begin = samples.to.size();
        for (int j = 0; j < k; ++j)
          internal::draw_facing(rng, (j + rng.uniform()) / k, [&](double at) {
            const int root = clusters.root_at(clusters.position_at_area(c, at));
            // A patch facing away is told by its plane alone, before its
            // triangles are read.
            const glm::dvec4& plane = cluster_plane[static_cast<size_t>(root)];
            if (!(glm::dot(Vec3(plane), x) + plane.w > 0.0)) return false;
            const size_t q = static_cast<size_t>(cluster_patch[static_cast<size_t>(root)]);
            const SourceTree& s = sources[q];
            const double u = rng.uniform(), a = rng.uniform(), b = rng.uniform();
            int tri = -1;
            const Vec3 y = s.sample(0, static_cast<int>(s.triangle.size()), u, a, b, tri);
            const double w = point_kernel(x, n, y, s.normal);
            if (!(w > 0.0)) return false;
            t.weight += w;
            samples.add(y, w, s.reflected[static_cast<size_t>(tri)]);
            sample_patch.push_back(static_cast<int>(q));
            return true;
          });
        t.end = samples.to.size();
        report.rays_cast += k;
      }
      far.push_back(t);
      continue;
    }
    for (const int child : clusters.children(c)) {
      if (child <= -2)
        stack.push_back(ClusterTree::index(child));
      else
        h += gather_patch(static_cast<size_t>(cluster_patch[static_cast<size_t>(child)]), x, n, patch, id, full,
                          report);
    }
  }
  if (!visibility) {
    for (const Far& t : far) h += t.send;
    return h;
  }
  seen.assign(samples.to.size(), 1);
  if (!samples.to.empty()) {
    from.assign(samples.to.size(), x);
    visibility->visible_each(from.data(), samples.to.data(), samples.to.size(), patch, sample_patch.data(), seen.data());
  }
  for (const Far& t : far) h += t.f * sampled_mean(samples, t.begin, t.end, seen.data(), t.weight);
  return h;
}

}  // namespace radmesh
