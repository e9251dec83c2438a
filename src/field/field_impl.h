// The display field's evaluator, shared by its two files: field.cpp (the
// evaluator, the gather over every patch and the field over a mesh) and
// field_clusters.cpp (the clustered gather). This header owns the source
// trees over each reflecting patch's triangles, the redraw of points where
// the kernel is 0, and the evaluator's state (FieldEvaluator::Impl).
// Internal to the field module.

#pragma once

#include "radmesh/field.h"

#include "core/box_tree.h"
#include "core/snap.h"
#include "radiosity/transport/clusters.h"
#include "radmesh/form_factor.h"
#include "radiosity/transport/gather_node.h"
#include "radiosity/transport/occlusion.h"
#include "radiosity/transport/sampling.h"
#include "radiosity/transport/transport.h"
#include "radiosity/transport/visibility.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

namespace radmesh::internal {

// Per display vertex of `field` over `mesh`: its patch (where a group
// spans coplanar patches of one material, the one with the most area around
// the vertex) and the direction into that patch's triangles around it.
void display_sides(const Mesh& mesh, const NodalField& field, std::vector<int>& patch, std::vector<Vec3>& inward);

// Adds the counts of one evaluation's report to `to`.
void add_counts(FieldReport& to, const FieldReport& from);

// A box tree over a mesh's triangles (item t: triangle t), for finding the
// triangle a point lies on (probes, the refined display's elements).
BoxTree triangle_boxes(const Mesh& mesh);
// Whether p, in the plane of triangle (a, b, c), lies in it: its
// barycentric coordinates all at least -tol. False for a zero-area triangle.
bool inside_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, double tol);

// How many times a point of a source is drawn before it is given up, where
// every draw so far fell where the kernel is 0 (facing away from the point,
// or behind its tangent plane).
constexpr int kDrawTries = 8;

// Calls try_at(u), then try_at with a fresh uniform from `rng` while it
// returns false (its point fell where the kernel is 0), kDrawTries calls
// at most.
template <class TryAt>
void draw_facing(SplitMix& rng, double u, TryAt&& try_at) {
  for (int tries = 1; !try_at(u) && tries < kDrawTries; ++tries) u = rng.uniform();
}

// A source patch's tree over its triangles.
struct SourceTree {
  struct Node : internal::GatherNode {
    int begin = 0, end = 0;  // range of triangles (in node order once built)
    int left = -1, right = -1;
  };
  Vec3 normal{0.0};
  std::vector<std::vector<Vec3>> loops;  // outline, then holes
  std::vector<Triangle> triangle;        // the patch's triangles of positive area, in node order once built
  std::vector<Rgb> reflected;            // per triangle: B - E
  std::vector<int> order;                // while building: triangle indices, in node order
  std::vector<Vec3> key;                 // while building: per triangle, its centroid (internal::snapped_keys)
  std::vector<double> cumulative;        // area of triangles [0 .. i), size + 1
  std::vector<Node> nodes;               // nodes[0] is the root

  int build(int begin, int end) {
    std::vector<const Triangle*> t;
    std::vector<Rgb> refl;
    Vec3 lo(INFINITY), hi(-INFINITY);
    for (int i = begin; i < end; ++i) {
      const size_t k = static_cast<size_t>(order[static_cast<size_t>(i)]);
      t.push_back(&triangle[k]);
      refl.push_back(reflected[k]);
      lo = glm::min(lo, key[k]);
      hi = glm::max(hi, key[k]);
    }
    Node n;
    static_cast<internal::GatherNode&>(n) = internal::gather_node(t, refl, normal);
    n.begin = begin;
    n.end = end;
    const int id = static_cast<int>(nodes.size());
    nodes.push_back(n);
    if (end - begin > 2) {
      const Vec3 ext = hi - lo;
      const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
      const int mid = (begin + end) / 2;
      std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end, [&](int a, int b) {
        const double ka = key[static_cast<size_t>(a)][axis], kb = key[static_cast<size_t>(b)][axis];
        return ka < kb || (ka == kb && a < b);
      });
      const int l = build(begin, mid);
      const int r = build(mid, end);
      nodes[static_cast<size_t>(id)].left = l;
      nodes[static_cast<size_t>(id)].right = r;
    }
    return id;
  }

  // A point of triangles [begin .. end), area-uniform for u in [0, 1), and
  // its triangle.
  Vec3 sample(int begin, int end, double u, double a, double b, int& triangle_index) const {
    const double target = cumulative[static_cast<size_t>(begin)] +
                          u * (cumulative[static_cast<size_t>(end)] - cumulative[static_cast<size_t>(begin)]);
    const size_t i = static_cast<size_t>(area_index(cumulative.data(), begin, end, target, u));
    triangle_index = static_cast<int>(i);
    const Triangle& t = triangle[i];
    return triangle_point(t.v[0], t.v[1], t.v[2], a, b);
  }
};

}  // namespace radmesh::internal

namespace radmesh {

struct FieldEvaluator::Impl {
  // The scene as the evaluator sees it: in units of its size, snapped
  // (internal::SnappedFrame), and every point given to the evaluator with
  // it. A scene scaled or moved then gives the same numbers, and its
  // decisions (a point on a plane, a source behind it, a ray grazing a
  // block's foot) the same answers; form factors are the same in any unit.
  internal::SnappedFrame frame;
  Scene local;
  const Scene& scene = local;
  double diagonal = 0.0;  // the scene's, once (Scene::diagonal visits every vertex)
  int rays_per_node = 1;  // options.rays / 4, at least 1
  DirectIllumination direct;
  Occlusion occlusion;
  std::unique_ptr<Visibility> visibility;
  std::vector<internal::SourceTree> sources;  // per patch (empty tree: reflects nothing)
  // The clustered gather (see FieldEvaluator): a cluster tree whose roots
  // stand for the reflecting patches (empty: every patch is visited).
  ClusterTree clusters;
  std::vector<int> cluster_patch;       // per root: its patch
  std::vector<glm::dvec4> cluster_plane;  // per root: its patch's plane (unit normal, offset)
  std::vector<double> cluster_reach;    // per cluster: a sphere about its centre holding its patches
  std::vector<Box3> cluster_box;        // per cluster: the box of its patches
  std::vector<Rgb> group_reflected;     // per group: the area mean of B - E

  Impl(const Scene& s, const SolveOptions& o)
      : frame(s.vertices),
        local(snapped(s, frame)),
        diagonal(local.diagonal()),
        rays_per_node(std::max(1, o.rays / 4)),
        direct(local),
        occlusion(local) {}
  static Scene snapped(const Scene& s, const internal::SnappedFrame& frame) {
    Scene out = s;
    for (Vec3& v : out.vertices) v = frame.to_local(v);
    for (Patch& p : out.patches) p.normal = internal::SnappedFrame::direction(p.normal);
    return out;
  }

  // Sample points of a source seen from one point: where each lies, its
  // weight (the point form factor's kernel there) and the reflected
  // radiosity of its triangle.
  struct Samples {
    std::vector<Vec3> to;
    std::vector<double> w;
    std::vector<Rgb> reflected;
    void clear() {
      to.clear();
      w.clear();
      reflected.clear();
    }
    void add(const Vec3& y, double weight, const Rgb& r) {
      to.push_back(y);
      w.push_back(weight);
      reflected.push_back(r);
    }
  };
  // Area-uniform stratified points y of triangles [begin .. end) of a
  // source, for the mean of V(x, y) R(y) seen from x (normal n): appended
  // to `batch`; returns the sum of their weights. Visibility and the
  // reflected radiosity are sampled together: where the hidden part of a
  // source is also its dark part (the floor at a block's foot seen from the
  // ceiling), the mean visibility times the mean radiosity would come out
  // low. A point where the kernel is 0 (behind x's tangent plane) is drawn
  // again, at most kDrawTries times in all (see gather_clustered).
  double draw(const Vec3& x, const Vec3& n, const internal::SourceTree& tree, int begin, int end, uint64_t seed,
              int k, Samples& batch) const {
    SplitMix rng(seed);
    double weight = 0.0;
    for (int s = 0; s < k; ++s)
      internal::draw_facing(rng, (s + rng.uniform()) / k, [&](double u) {
        const double a = rng.uniform(), b = rng.uniform();
        int t = -1;
        const Vec3 y = tree.sample(begin, end, u, a, b, t);
        const double ws = point_kernel(x, n, y, tree.normal);  // a sample's weight
        if (!(ws > 0.0)) return false;
        weight += ws;
        batch.add(y, ws, tree.reflected[static_cast<size_t>(t)]);
        return true;
      });
    return weight;
  }
  // The weighted mean of R over samples [begin .. end) of `batch` whose
  // segment from x got through (seen; null: all of them).
  static Rgb sampled_mean(const Samples& batch, size_t begin, size_t end, const unsigned char* seen, double weight) {
    Rgb sum(0.0);
    for (size_t i = begin; i < end; ++i)
      if (!seen || seen[i]) sum += batch.w[i] * batch.reflected[i];
    return weight > 0.0 ? sum / weight : Rgb(0.0);
  }

  // The shadow rays for a part of a source that sends x about `light`
  // (its form factor x its brightest channel): in proportion to it, the
  // split of a point's rays that makes the variance of its sum least
  // (a part's variance grows as its light squared over its rays), with
  // rays_per_node for each `full` of light (kRayShare of what the solve
  // says the point gathers), at least one and at most twice
  // rays_per_node. Where nothing says how much the point gathers (full 0),
  // rays_per_node. A part that sends nothing casts none: what it adds is 0
  // whatever its rays say (its form factor still counts in the patch's sum).
  int rays_for(double light, double full) const {
    if (!(light > 0.0)) return 0;
    if (!(full > 0.0)) return rays_per_node;
    const double k = std::ceil(rays_per_node * light / full);
    return k >= 2 * rays_per_node ? 2 * rays_per_node : std::max(1, static_cast<int>(k));
  }
  // FieldEvaluator::evaluation_point in the frame's units.
  Vec3 evaluation_point(const Vec3& x, int patch, const Vec3& inward, FieldReport& report) const;
  Rgb gather_patch(size_t q, const Vec3& x, const Vec3& n, int patch, uint64_t id, double full,
                   FieldReport& report) const;
  Rgb gather_clustered(const Vec3& x, const Vec3& n, int patch, uint64_t id, double full, FieldReport& report) const;
  void build_clusters();
};

}  // namespace radmesh
