// Clusters above the roots of an element hierarchy (ClusterMode of
// hierarchical.h), each with up to kGroups oriented normal groups:
//   volume  a binary box hierarchy over the root triangles (median splits of
//           their centroids on the longest axis);
//   shape   Tanaka and Noma's hierarchical shape approximation: the roots'
//           vertices clustered by an octree, one clustering per level, and
//           every triangle hung under the coarser triangle it maps to.
// The hierarchical solver links and gathers over it; this file knows only
// geometry and the groups' radiosity.
#pragma once

#include "radmesh/form_factor.h"

#include <span>
#include <utility>
#include <vector>

namespace radmesh {

class ClusterTree {
public:
  // Groups a cluster keeps: its children's groups (a root is one group),
  // merged greedily, the two with the closest mean normals first.
  static constexpr int kGroups = 8;

  struct Cluster {
    int child_begin = 0, child_end = 0;  // into the children (children(c))
    int begin = 0, end = 0;      // its roots: root_at(begin .. end - 1)
    Vec3 centre{0.0};            // area-weighted centroid
    double radius = 0.0;         // of a sphere about the centre holding every member
    double area = 0.0;
    double weight = 0.0;         // the largest per-root weight below it (the oracle's reflectance)
    int group_begin = 0, group_end = 0;
    int member_begin = 0, member_end = 0;  // into the members of its groups
  };
  // Light leaving a group towards direction w is B max(0, s . w) / pi per
  // steradian: exact while its members' normals all face w or all face
  // away (a flat wall is one group).
  struct Group {
    Vec3 s{0.0};  // sum over members of area x unit normal
    Vec3 centroid{0.0};
    double area = 0.0;
    int up = -1;  // the group of the parent cluster it belongs to (-1 at the top)
    // Half-angle of a cone about s holding every member's normal (pi when
    // s is 0): 0 for a flat group, and the group's light is exact for every
    // w further than it from the plane perpendicular to s.
    float cone = 0.0f;
    int cluster = -1;  // the cluster it is a group of
  };

  static constexpr int code(int c) { return -2 - c; }
  static constexpr int index(int code) { return -2 - code; }

  ClusterTree() = default;
  // Both builders: over `roots` (at least two; fewer give an empty tree),
  // with one weight per root; cluster 0 is the top, and every cluster's
  // children have larger numbers than it.
  //
  // Median splits of the roots' centroids on the longest axis: binary.
  static ClusterTree volume(const std::vector<Triangle>& roots, const std::vector<double>& weights);
  // Octree vertex clustering (Rossignac and Borrel), as Tanaka and Noma
  // build their hierarchy from it. The roots' corners are put in cells of
  // an octree over the scene, from the finest level at which the shortest
  // root edge has its ends in different cells up to the whole scene. Going
  // one level up, a node (a root, or a coarser triangle standing for the
  // nodes under it) maps to the cells its three corners fall in: three
  // different cells make a triangle, and every node mapping to it hangs
  // under it; two make a segment and one a point, and such a node hangs
  // under a triangle of that level having that segment as an edge (or, for
  // a point or failing that, either end as a corner). A node that finds no
  // such triangle keeps its own place and tries again a level up. A
  // triangle with a single node under it is that node. What is left when
  // the octree runs out of levels hangs under the top cluster. So a
  // cluster made at a level is a piece of surface about that level's cell
  // in size (a cap of a sphere, the side of a statue), with the small
  // objects that collapsed into its corners' cells.
  static ClusterTree shape(const std::vector<Triangle>& roots, const std::vector<double>& weights);

  // Bytes `clusters` clusters with `groups` groups take here and in the
  // solver's per-group arrays (radiosity, gathering, form factor sums).
  static double bytes(double clusters, double groups);

  bool empty() const { return clusters_.empty(); }
  size_t size() const { return clusters_.size(); }
  size_t group_count() const { return groups_.size(); }
  const Cluster& cluster(int c) const { return clusters_[static_cast<size_t>(c)]; }
  const Group& group(int g) const { return groups_[static_cast<size_t>(g)]; }
  int members(int c) const { return cluster(c).end - cluster(c).begin; }
  // Node codes of cluster c's children: a root (>= 0) or a cluster (code(c) <= -2).
  std::span<const int> children(int c) const {
    const Cluster& cl = cluster(c);
    return {children_.data() + cl.child_begin, static_cast<size_t>(cl.child_end - cl.child_begin)};
  }
  // The i-th root in cluster order (cluster c's roots are root_at(begin .. end - 1)).
  int root_at(int i) const { return order_[static_cast<size_t>(i)]; }
  // The group of its parent cluster root r belongs to.
  int root_group(int r) const { return root_group_[static_cast<size_t>(r)]; }

  // Group radiosity (area means over members) from the roots' radiosity
  // (root_radiosity[r] for root r), children first. With weights, the
  // means weigh a member by its area times its weight (root_weight[r] for
  // root r, group_weight[g] for a child group g); a group whose members
  // all weigh 0 takes the plain area mean.
  void radiosity(const std::vector<Rgb>& root_radiosity, std::vector<Rgb>& group_radiosity,
                 const std::vector<double>* root_weight = nullptr,
                 const std::vector<double>* group_weight = nullptr) const;
  // The area-mean radiosity of cluster c from its groups'.
  Rgb mean(int c, const std::vector<Rgb>& group_radiosity) const;

  // Form factors from point x with normal n to the groups of cluster c
  // (max(0, s . r) max(0, -n . r) / (pi |r|^4) each), times `visible`,
  // appended as (-2 - group, F). With n = s / area of
  // a receiving group, area x F is the same both ways between two groups.
  // With `per_group`, group g of c is seen through per_group[g - first
  // group of c] instead of `visible`.
  void form_factors(int c, const Vec3& x, const Vec3& n, double visible, std::vector<std::pair<int, double>>& out,
                    const float* per_group = nullptr) const;

  // A bound on how far the groups of cluster c get their light towards a
  // sphere about x of radius `rx` wrong, as projected area: where a group's
  // normal cone straddles the direction's perpendicular plane, max(0, s . w)
  // takes the members facing away off those facing w (or gives 0 for
  // those facing w), at most area x the cosine of the cone's far edge. The
  // sum over c's groups; 0 for groups that are flat or face w, or away, whole.
  double straddle(int c, const Vec3& x, double rx) const;

  // The position (root_at(position)) of the root of cluster c holding
  // area fraction u in [0, 1) of it.
  int position_at_area(int c, double u) const;
  // The root of group g holding area fraction u in [0, 1) of it (through
  // its child groups, by their members' areas).
  int root_at_area(int g, double u) const;

private:
  // Lays out the clusters of `tree` (children lists of node codes, -2 - t
  // for tree node t; node 0 the top) in preorder, then computes the
  // clusters' geometry and groups.
  void finish(const std::vector<std::vector<int>>& tree, const std::vector<Triangle>& roots,
              const std::vector<double>& weights);
  int lay_out(int t, const std::vector<std::vector<int>>& tree);
  struct Member {  // of a group: a root (>= 0) or a child group (-2 - g), with its area
    int from;
    double area;
    int group;
  };
  std::vector<Cluster> clusters_;
  std::vector<int> children_;
  std::vector<Group> groups_;
  std::vector<Member> members_;
  std::vector<int> order_;           // roots in cluster order
  std::vector<double> cumulative_;   // area of order_'s first i roots
  std::vector<int> root_group_;
};

}  // namespace radmesh
