// The triangle mesh: flat arrays, plain types.
#pragma once

#include "radmesh/discontinuity.h"
#include "radmesh/geometry.h"
#include "radmesh/options.h"
#include "radmesh/scene.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace radmesh {

struct Mesh {
  std::vector<Vec3> positions;                 // welded: patches sharing an edge share its vertices
  std::vector<std::array<int, 3>> triangles;   // counter-clockwise around the patch normal
  std::vector<int> patch;                      // per triangle: index into Scene::patches
  // Edges inside a patch that lie on a discontinuity line (vertex pairs, the
  // smaller index first): per-vertex values are not averaged across them.
  std::vector<std::array<int, 2>> feature_edges;

  int triangle_count() const { return static_cast<int>(triangles.size()); }
  double area(int t) const;
  Vec3 centroid(int t) const;
  // Zero area up to rounding (area at most 1e-12 of the longest edge
  // squared): the zero-area triangles that close T-vertices of a hierarchical
  // mesh, whose middle vertex lies on the long edge only up to rounding.
  bool zero_area(int t) const;
};

// An edge (a, b) as one number, the same for (b, a).
inline uint64_t undirected_edge_key(int a, int b) {
  return (static_cast<uint64_t>(static_cast<uint32_t>(std::min(a, b))) << 32) | static_cast<uint32_t>(std::max(a, b));
}

// Whether a vertex pair, in either order, is one of a mesh's feature edges
// (a sorted copy of them, searched).
class FeatureEdges {
public:
  explicit FeatureEdges(const Mesh& mesh);
  bool contains(int a, int b) const;

private:
  std::vector<uint64_t> keys_;
};

struct MeshingOptions {
  // Longest edge allowed in the mesh, in scene units. 0 picks
  // scene diagonal / 12, so that the default mesh does not depend on the unit.
  double max_edge = 0.0;
  // Smallest angle wanted in every triangle, degrees. CGAL's Delaunay mesher is
  // guaranteed to terminate up to about 20.7 degrees; we accept up to 30.
  double min_angle = 20.0;
  // Discontinuity lines made mesh edges before refinement (see discontinuity.h).
  // Full (contacts and shadow boundaries) gives the best time to error for
  // a method that does not refine by itself (docs/accuracy.md).
  DiscontinuityMode discontinuity = DiscontinuityMode::full;
  ShadowOptions shadow;  // used with DiscontinuityMode::full
  // ShadowOptions::min_separation = this x max_edge (when min_separation is
  // 0); triangles with an edge shorter than this x max_edge are not refined
  // for their angle (small angles between input lines cannot be removed).
  double min_separation_fraction = 0.02;
  // A bound on the work: a max_edge that would make more elements than this
  // (estimated from the patch areas, before any meshing) is refused with a
  // message naming the size that fits, instead of meshing for hours.
  double max_elements = 2e7;
  // Where two edges or lines of a patch run side by side far closer than
  // max_edge (a carpet's edge 1 mm up a 4 m wall), CGAL's mesher may cut
  // both about their gap apart along them. false (for methods that refine
  // by themselves): a patch whose refinement makes more than 15 x the
  // points its size and edges ask for is left as the triangulation of its
  // outline and lines, with a warning. true (the matrix method, whose
  // elements are its unknowns): it is cut so.
  bool refine_narrow_strips = false;
};

struct MeshReport {
  int boundary_rounds = 0;     // rounds needed to agree on shared boundary vertices
  int contact_segments = 0;    // D0 segments inserted as constraints
  int shadow_segments = 0;     // D1/D2 segments inserted as constraints
  int crossings = 0;           // exact crossings between lines, where both were split
  int rounding_crossings = 0;  // crossings CGAL still found after rounding (0 expected)
  // Faces left as their outline's triangulation: narrower than the
  // separation floor, or refined too densely (MeshingOptions::refine_narrow_strips).
  int thin_faces_unrefined = 0;
  // Every meshing warning: per face left unrefined for a narrow gap (not a
  // sliver), where and why; then the shadow pass's (shadow.warnings).
  std::vector<std::string> warnings;
  ShadowReport shadow;         // what the shadow-line pass did and skipped
  std::vector<DiscontinuitySegment> discontinuities;  // the lines inserted, for export
};

// Meshes every patch with a CGAL constrained Delaunay triangulation in its
// plane, refined by CGAL's Delaunay mesher. Holes and concave polygons are
// supported; vertices on a patch's boundary edges are shared with every
// patch that touches that edge, so meshing creates no T-vertex.
Mesh mesh_scene(const Scene& scene, const MeshingOptions& options, MeshReport* report = nullptr);

// The coarsest triangulation of every patch: its constrained Delaunay
// triangulation with no point added (holes and concave outlines respected).
// Shared edges are not made conforming. Used for visibility.
Mesh triangulate_patches(const Scene& scene);

// The options a user sets (max_edge, min_angle, discontinuity,
// max_shadow_lines: shadow.max_lines_per_receiver), with their ranges: the
// radmesh program's flags and the checks of resolve_meshing_options.
const OptionTable<MeshingOptions>& meshing_option_table();

// Resolves MeshingOptions::max_edge = 0 to its scene-relative default and
// checks the options; throws InputError when out of range.
MeshingOptions resolve_meshing_options(const Scene& scene, MeshingOptions options);

// Per-triangle quality.
struct TriangleQuality {
  std::vector<double> min_angle;     // degrees
  std::vector<double> max_angle;     // degrees
  std::vector<double> aspect_ratio;  // longest edge / (2 sqrt(3) inradius): 1 for equilateral
  std::vector<char> zero_area;       // Mesh::zero_area, once per triangle
};
// A zero-area triangle (Mesh::zero_area) gets 0 and 180 degrees and aspect
// ratio 0: it has no shape worth the name, and never inf or NaN in a file.
TriangleQuality compute_quality(const Mesh& mesh);

// Nearest-rank percentile (q in [0, 1]) of the finite values; 0 when none.
double percentile(std::vector<double> values, double q);

// Quality of one patch's triangles (or of all: patch = -1), for mesh studies.
struct PatchQuality {
  int patch = -1;
  int triangles = 0;
  double min_angle = 0.0, max_angle = 0.0;                    // degrees, extremes
  double aspect_p50 = 0.0, aspect_p95 = 0.0, aspect_max = 0.0;
  int contact_segments = 0;  // D0 constraint segments on the patch
  int d1_segments = 0;       // D1 shadow-boundary segments
  int d2_segments = 0;       // D2 shadow-boundary segments
  int zero_area = 0;         // triangles of zero area (Mesh::zero_area); angles and aspect ratios are over the others
};
// One row per patch (patch ids 0 .. patch_count - 1), then the total (patch = -1).
std::vector<PatchQuality> patch_quality(int patch_count, const Mesh& mesh, const TriangleQuality& quality,
                                        const std::vector<DiscontinuitySegment>& discontinuities);

}  // namespace radmesh
