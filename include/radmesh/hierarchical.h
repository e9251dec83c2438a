// Hierarchical radiosity (Hanrahan, Salzman & Aupperle 1991) on the element
// hierarchy of hierarchy.h: links between nodes at any level, made
// by recursive refinement with an oracle on the transported light, solved by
// gathering over links and pulling radiosity up through the hierarchy. The
// receiver side gathers at leaf resolution (each leaf over its own and its
// ancestors' links, at its own points) rather than pushing one average down:
// rows then sum to 1 in a closed scene, which keeps reflectance near 1 stable.
#pragma once

#include "radmesh/hierarchy.h"
#include "radmesh/solve.h"

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace radmesh {

// Vertex values where a leaf's vertex lies on a neighbour's unsplit edge.
enum class TVertexMode {
  anchor,  // the unsplit edge's linear interpolant: Gouraud shading has no jump there
  free,    // what the finer side's elements give it (shading may jump along the edge)
  split,   // no T-vertices: neighbours are split until none is left (the conventional way)
};

// "anchor", "free", "split"; InputError naming the value otherwise.
TVertexMode parse_tvertex_mode(const std::string& name);
const char* to_string(TVertexMode mode);

// What sits above the initial mesh's triangles (the roots).
enum class ClusterMode {
  off,     // nothing: every pair of roots is linked (O(k^2) links in k roots)
  volume,  // a box hierarchy of clusters (Smits-Arvo-Greenberg, Sillion), each
           // with a few oriented normal groups: linking starts from the root
           // cluster's self-link, so links grow about linearly
  shape,   // Tanaka and Noma's hierarchical shape approximation (octree vertex
           // clustering) as the hierarchy, with the same groups and linking
};
// "off", "volume", "shape"; InputError naming the value otherwise.
ClusterMode parse_cluster_mode(const std::string& name);
const char* to_string(ClusterMode mode);

struct HierarchicalOptions {
  // Oracle: the link receiver p <- source q is refined while its error
  // estimate exceeds epsilon x the largest emission and one of the two may
  // still be split (epsilon is relative to the largest emission for the first
  // linking, then to the largest reflected radiosity B - E of the last
  // solve). The estimate is rho_p * B_q * (the largest difference
  // between the point form factor to q at p's corners and centroid and the
  // link's form factor), plus rho_p * B_q * F when the link is partly visible
  // (some shadow rays blocked): links across shadow boundaries go first.
  double epsilon = 1e-3;
  // The oracle's error for a receiver smaller than the mean root (initial
  // triangle) is weighted by (its area / the mean root's)^area_weight: 0 =
  // off (a radiosity error, the same threshold at every size), 1 = the
  // transported power's error below the mean root's size. Small receivers
  // are then linked more coarsely: object means move little, single small
  // faces more (docs/decisions.md).
  double area_weight = 0.0;
  // Elements are not split below this area; 0 = (scene diagonal / 150)^2 / 2.
  // An input triangle (or a cluster of them) smaller than it weighs its
  // oracle error by its area / min_area: a mesh cut finer than this floor
  // asks for fewer links per triangle the finer it is.
  double min_area = 0.0;
  // Refinement rounds after the first solve (each: refine links where the
  // current radiosity says it matters, then solve again). Stops earlier when
  // no link is refined or the leaf radiosity changes less than the tolerance.
  int max_rounds = 6;
  // After the first refinement round, a round is made for the links the
  // oracle would refine only where one of them is over its threshold by
  // more than this factor; otherwise they stay as they are, and the
  // solution's skips say how many: a late round refines few links, each by
  // little, at the cost of a pass over all of them (docs/decisions.md).
  // 1 = refine every link over the threshold.
  double marginal_refinement = 2.0;
  // free by default: the vertex field is closer to the reference than
  // anchored, and the jump it leaves is far below the field's error
  // (docs/decisions.md).
  TVertexMode tvertex = TVertexMode::free;
  // Baum's a-posteriori criterion, after each solve: split a leaf whose
  // vertex values differ by more than baum x the largest reflected
  // radiosity (B - E) and by more than baum_absolute, down to min_area / 4
  // (its children gather over its links: no new links). 0 = off. On by
  // default: the gather field is exact at every vertex, so what is left of
  // its error is mostly the linear interpolation between vertices, and
  // these splits put vertices where the field bends (docs/decisions.md).
  double baum = 0.02;
  double baum_absolute = 0.0;
  // volume by default: as accurate as off at equal time on small scenes,
  // and many times faster on scenes of thousands of input triangles
  // (docs/decisions.md).
  ClusterMode clusters = ClusterMode::volume;
  // Copy the links into the solution at the end (links, cluster_links;
  // the radmesh program writes them to links.vtu). Off by default: the
  // copy costs time and memory in proportion to the links.
  bool export_links = false;
};

// The options a user sets, with their ranges (the radmesh program's flags,
// the checks of HierarchicalSolver and radmesh::solve).
const OptionTable<HierarchicalOptions>& hierarchical_option_table();

struct HierarchicalStats {
  int rounds = 0;                 // solves done (the first one included)
  double min_area = 0.0;          // the smallest element area used (the option or its default)
  long long links = 0;            // links at the end
  long long links_examined = 0;   // oracle calls
  long long rays_cast = 0;
  long long rays_skipped = 0;        // not cast: no occluder can lie between the two nodes
  long long pairs_unoccludable = 0;  // node pairs examined with nothing that can occlude them
  int leaves = 0;
  int zero_area_triangles = 0;    // in the conforming output mesh
  int sweeps = 0;                 // gather + push-pull sweeps, all rounds
  double seconds_link = 0.0, seconds_solve = 0.0;
  std::vector<long long> links_per_round;
  int clusters = 0;                // cluster nodes above the roots (ClusterMode volume or shape)
  int cluster_groups = 0;          // their normal groups
  long long cluster_links = 0;     // links with a cluster at one end or both (in `links`)
  std::vector<int> leaves_per_round;
  double last_change = 0.0;       // largest relative change of a leaf between the last two rounds
  // Per leaf, the sum of F x visibility over the links of its path to the
  // root: about 1 in a closed scene. Smallest and largest.
  double row_sum_min = 0.0, row_sum_max = 0.0;
  long long leaf_terms = 0;       // (leaf, source) terms gathered per sweep, last round
  int conforming_splits = 0;      // splits made to remove T-vertices (TVertexMode::split)
  int baum_splits = 0;            // splits made by Baum's criterion
  // Largest difference, relative to the largest radiosity, between a
  // T-vertex's value from its finer side and the unsplit edge's
  // interpolant: the shading jump `free` leaves (anchor removes it).
  double max_tvertex_jump = 0.0;
};

// A link as published: the receiver node gathers from `source` with form
// factor F x visibility (the link's level; leaves re-evaluate F at their own
// points), `visible` the fraction of its shadow rays that got through.
struct HierarchicalLink {
  int source = -1;
  double form_factor = 0.0;
  double visible = 1.0;
};

// A link with a cluster at one end or both (ClusterMode volume or shape): centres
// of its two ends, the element node at an end that is one (-1 for a
// cluster), the cluster at an end that is one (-1 for an element), F x
// visibility from the two centres (the cluster's area over pi d^2), the
// visible fraction, and rho_receiver x F x V x B_source (largest channel,
// the largest reflectance of a receiving cluster, its mean radiosity for a
// source cluster).
struct HierarchicalClusterLink {
  Vec3 receiver{0.0}, source{0.0};
  int receiver_node = -1, source_node = -1;
  int receiver_cluster = -1, source_cluster = -1;
  double form_factor = 0.0, visible = 1.0, transport = 0.0;
};

struct HierarchicalSolution {
  ElementTree tree;
  std::vector<Rgb> node_radiosity;  // per tree node (inner nodes: area-weighted mean of children)
  std::vector<int> node_links;      // per tree node: links it gathers over
  // Per receiver node, filled at the end (not in on_round) with export_links.
  std::vector<std::vector<HierarchicalLink>> links;
  std::vector<HierarchicalClusterLink> cluster_links;  // the same; links = these + `links`
  Mesh mesh;                        // conforming mesh: leaves, then zero-area fans
  std::vector<int> leaf_of;         // per mesh triangle: its leaf, or -1 (zero-area)
  Solution solution;                // per mesh triangle (zero-area: the leaf owning the edge) and per vertex
  HierarchicalStats stats;
};

// Hierarchical radiosity with its state: the element tree, the links and the
// radiosity live between calls. The constructor links the initial mesh's
// roots and solves once; each refine() is one refinement round (links
// refined where the current radiosity says it matters, then solved again).
// Every call runs in its own TBB arena of options.threads workers. `scene`
// must outlive the solver.
class HierarchicalSolver {
public:
  // `progress` (may be empty) is called from the calling thread with the
  // phase ("link", "solve", "refine") and, while linking, the fraction done;
  // it must outlive the solver.
  HierarchicalSolver(const Scene& scene, const Mesh& initial, const SolveOptions& options,
                     const HierarchicalOptions& hopt, const ProgressFn& progress = {});
  ~HierarchicalSolver();
  HierarchicalSolver(const HierarchicalSolver&) = delete;
  HierarchicalSolver& operator=(const HierarchicalSolver&) = delete;

  // False, changing nothing, once the stopping rule is met (max_rounds, a
  // change below the tolerance, nothing left to refine).
  bool refine();
  // The solution as it stands (links included).
  const HierarchicalSolution& solution() const;
  // The solution moved out (links included); the solver is spent after it.
  HierarchicalSolution take_solution();
  int rounds() const;  // solves done

private:
  friend HierarchicalSolution solve_hierarchical(const Scene&, const Mesh&, const SolveOptions&,
                                                 const HierarchicalOptions&,
                                                 const std::function<void(const HierarchicalSolution&, int)>&,
                                                 const ProgressFn&);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The one-off form: refines until the stopping rule. `on_round(solution,
// round)` is called after every solve (for a series of files).
HierarchicalSolution solve_hierarchical(
    const Scene& scene, const Mesh& initial, const SolveOptions& options, const HierarchicalOptions& hopt,
    const std::function<void(const HierarchicalSolution&, int round)>& on_round = {},
    const ProgressFn& progress = {});

}  // namespace radmesh
