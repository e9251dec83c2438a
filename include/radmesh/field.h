// The field users see: radiosity at the vertices of the display mesh, made
// from what a solver returns. `gather` evaluates every vertex anew: its
// emission, the exact direct light (direct.h) and the indirect
// light gathered from the solved element radiosity; `fit` and `mean` are
// made from the element values alone (compute_nodal).
#pragma once

#include "radmesh/mesh.h"
#include "radmesh/progress.h"
#include "radmesh/scene.h"
#include "radmesh/direct.h"
#include "radmesh/solution.h"
#include "radmesh/solve.h"

#include <memory>
#include <string>
#include <vector>

namespace radmesh {

// What the field pass did (gather only; fit and mean leave it zero).
struct FieldReport {
  FieldMode mode = FieldMode::gather;  // the mode used (automatic resolved)
  std::string own_field;               // FieldMode::own: the method's name for its field (Method::own_field)
  std::string why;                     // why automatic did not gather ("" otherwise)
  long long display_vertices = 0;
  DirectCounts direct;             // per (vertex, emitter) pair
  long long on_other_surface = 0;  // vertices on another patch (a contact), taken a hair to their own side
  long long gather_sources = 0;    // (vertex, source patch) pairs gathered
  long long gather_nodes = 0;      // source nodes taken whole (their angular size within the bound)
  long long gather_clusters = 0;   // clusters of patches taken whole (the clustered gather)
  bool clustered = false;          // the gather went by clusters of patches
  long long gather_triangles = 0;  // source triangles taken one by one (Lambert's exact formula)
  long long rays_cast = 0;
  double seconds_direct = 0.0;
  double seconds_gather = 0.0;
  // refine_display: its rounds, the midpoints it evaluated, the triangles it split.
  int display_rounds = 0;
  long long display_midpoints = 0;
  long long display_splits = 0;
};

// Evaluates B = E + rho (direct + indirect irradiance) at points of the
// scene's surfaces from a solution's element radiosity.
//
// Direct: DirectIllumination::reflected, exact.
// Indirect: the reflected part of the solution, R_j = B_j - E_j, gathered
// from every source patch q the point can see. Per source patch, a binary
// tree over its triangles (split at the median centroid along the longest
// axis) decides how finely the patch is taken: a node is taken whole when
// its bounding sphere (radius r, centre at distance d) subtends
// r / d <= kOpening (then it is integrated by its moments, the point form
// factor's kernel expanded about its centroid: node_term in
// radiosity/transport/gather_node.h, error O((r/d)^3)), otherwise its children are; at most two
// triangles are taken one by one with Lambert's exact formula. The node
// form factors are only weights
// within the patch: their sum is scaled to the exact form factor to the
// whole patch (Lambert's formula on its outline and holes), so a uniform
// source is gathered exactly, and in a closed scene the form factors at a
// point sum to 1 whatever the tree. Visibility: stratified shadow rays per
// node or triangle taken, in proportion to the light it sends x (options.rays
// / 4 for each kRayShare of what the solve says x gathers; at least 1, at
// most options.rays / 2: FieldEvaluator::Impl::rays_for; a point drawn where
// the kernel is 0 is drawn again, up to 8 times), cast only where the
// shaft from x to the node's rectangle (or the triangle) may hold another
// patch, of those that the shaft from x to the whole source may hold (found
// once per point and source whose cut has 8 parts or more, which casts far
// fewer rays than testing each part's shaft alone); each ray also samples
// the source's radiosity where it lands, weighted by the point form
// factor's kernel there (visibility and radiosity are correlated: the part
// of a source hidden from x is often its dark part). One random stream per
// (point, node), so results do not depend on the thread count.
//
// Past the budget below (scenes of many patches), the gather does not visit
// every patch: a cluster tree over the patches (ClusterTree::volume, one
// root per reflecting patch) is walked from its top, and a cluster is taken
// whole where its patches lie within a sphere of radius at most
// kClusterOpening x its distance from x, wholly in front of x's tangent
// plane, and its normal groups straddle the direction to x by at most
// kClusterStraddle of its area (ClusterTree::straddle): its groups' form
// factors (each a point form factor at the group's centroid) times the
// kernel-weighted mean of the visible reflected radiosity over
// area-stratified points of its patches (as many as for a node sending as
// much, at least options.rays / 4; one on a patch facing away from x is
// drawn again), their rays cast
// together. Other clusters are opened; the patches reached are gathered as
// above. The clusters' form factors are not scaled to an exact sum, so a
// point's row is exact only to the far clusters' error, about
// (kClusterOpening)^2 of what they send.
//
// The evaluator works on a copy of the scene and of the mesh's triangles in
// units of the scene's size from its lowest corner, snapped to 2^-33 of it,
// and snaps every point it is given the same way: a scene scaled or moved
// gives the same values (a point on a floor stays on its plane through a
// moved scene's rounding), each within 1e-10 of its value for the scene as
// given.
enum class GatherSources {
  automatic,    // every patch within kGatherBudget, clusters past it
  every_patch,  // every patch
  clustered,    // the cluster tree (with fewer than two reflecting patches: every patch)
};
class FieldEvaluator {
public:
  FieldEvaluator(const Scene& scene, const Mesh& mesh, const std::vector<Rgb>& element, const SolveOptions& options,
                 GatherSources how = GatherSources::automatic);
  ~FieldEvaluator();
  FieldEvaluator(const FieldEvaluator&) = delete;
  FieldEvaluator& operator=(const FieldEvaluator&) = delete;

  // Where the value of a vertex at x on `patch` is taken: x itself, or,
  // where x lies on another patch (a contact line, where the light jumps:
  // the floor at a block's foot is lit outside and dark under it), a hair
  // towards `inward`, which points into the part of the
  // surface the value belongs to. Counts the move in `report`. The hair is
  // 1e-5 of the scene's diagonal (at most a tenth of `inward`): the shadow
  // rays are single precision, and must start on the right side.
  Vec3 evaluation_point(const Vec3& x, int patch, const Vec3& inward, FieldReport& report) const;
  // B at x on `patch`: E + direct + indirect. `id` seeds the point's random
  // streams. Thread-safe, like the two parts below.
  Rgb radiosity(const Vec3& x, int patch, uint64_t id, FieldReport& report) const;
  // The reflected direct light (exact) and the reflected gathered light.
  // `solved`: what the solve puts at x, B - E over the reflectance in the
  // brightest channel (the scale each part's share of the shadow rays is
  // taken against); 0 where unknown: every part gets options.rays / 4.
  Rgb direct(const Vec3& x, int patch, FieldReport& report) const;
  Rgb indirect(const Vec3& x, int patch, uint64_t id, FieldReport& report, double solved = 0.0) const;

  // Whether the gather goes by the cluster tree over the patches.
  bool clustered() const;

  static constexpr double kOpening = 0.25;
  static constexpr double kClusterOpening = 0.2;
  static constexpr double kClusterStraddle = 0.05;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The automatic field's budget: (display vertices) x (patches) at most this
// many pairs for the gather. Both of its passes visit every patch per
// vertex (the direct pass every occluder in the light's shaft): past this
// the field would take several times the solve's time (docs/decisions.md).
inline constexpr double kGatherBudget = 2e7;
// Past that budget the gather goes by clusters of patches (FieldEvaluator):
// a vertex visits a few hundred clusters and patches on large rooms, each
// dearer than a patch of the plain gather (rays to every far cluster), taken
// as kClusterCut pairs; the direct pass still visits every emitter. The
// automatic field also gathers while (mesh vertices) x (kClusterCut +
// emitters) is within the budget.
inline constexpr double kClusterCut = 400;
// Whether the gather visits every patch for each of `vertices` vertices
// (else it goes by clusters).
inline bool gather_every_patch(double vertices, double patches) { return vertices * patches <= kGatherBudget; }
// Whether the automatic field gathers over `vertices` vertices.
bool gather_within_budget(const Scene& scene, double vertices);

// `requested`, or for FieldMode::automatic gather or fit by the budget
// (with the reason in *why when it is fit).
FieldMode resolve_field_mode(FieldMode requested, const Scene& scene, const Mesh& mesh, std::string* why = nullptr);

// The display field of `mode` over `mesh` (see compute_nodal for how
// display vertices are made). gather: every display vertex evaluated by a
// FieldEvaluator, in parallel, a vertex on a contact line on its own side.
NodalField compute_field(const Scene& scene, const Mesh& mesh, const std::vector<Rgb>& element,
                         const SolveOptions& options, FieldReport* report = nullptr,
                         const ProgressFn& progress = {});

// The gather field on a display of its own (SolveOptions::display_tolerance
// > 0): `initial` (the mesh the solver started from, with its
// discontinuity lines) refined by the field's own interpolation error.
// `mesh` and `element` (the solver's, which the field gathers from) are
// replaced by the display's, each display triangle taking the radiosity of
// the solver's element its centroid lies in, whose index goes to `origin`.
// Rounds: every display vertex gets its value (once); the field is
// evaluated at the midpoints of the edges of every display triangle not yet
// at kDisplayLevels; the triangles where a midpoint's value differs from
// the mean of its edge's ends by more than the tolerance are split in four,
// until none is. Triangles whose midpoints were evaluated carry their mean
// by the midpoints (NodalField::triangle_mean).
NodalField refine_display(const Scene& scene, const Mesh& initial, Mesh& mesh, std::vector<Rgb>& element,
                          std::vector<int>& origin, const SolveOptions& options, FieldReport* report = nullptr,
                          const ProgressFn& progress = {});
inline constexpr int kDisplayLevels = 8;

// Per patch: the mean of the per-vertex linear field over the patch (its
// integral over the patch's triangles divided by their area). The summary's
// patch means.
std::vector<Rgb> patch_mean_radiosity(const Scene& scene, const Mesh& mesh, const NodalField& field);
// Per patch: the area-weighted mean of the element radiosity (what the
// solver itself computed).
std::vector<Rgb> patch_mean_radiosity(const Scene& scene, const Mesh& mesh, const std::vector<Rgb>& element);
// The solver's per-patch element means: solution.element_patch_mean, or
// computed over `mesh` where that is empty.
std::vector<Rgb> element_patch_means(const Scene& scene, const Mesh& mesh, const Solution& solution);

}  // namespace radmesh
