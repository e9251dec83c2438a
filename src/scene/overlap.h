// Faces that lie in one plane and face the same way: cut out of the face
// they lie in, or refused where they overlap otherwise.
#pragma once

#include "radmesh/mesh.h"
#include "radmesh/scene.h"

#include <utility>
#include <vector>

namespace radmesh {

// Faces within this fraction of the scene diagonal of one plane cannot be
// told apart by the solve: it is the distance its rays and the field step
// off a surface.
constexpr double kCoplanarOverlapTolerance = 1e-5;

// Faces that lie in one plane (within kCoplanarOverlapTolerance of the
// scene diagonal) facing the same way, found through a box tree over the
// patches, as build_scene leaves them:
// - A face without holes lying wholly inside a larger one, clear of its
//   edges and holes by more than the tolerance (a lamp lying in an uncut
//   ceiling, a rug on the floor), is cut out of it: its outline becomes a
//   hole of the smallest such face whose plane it lies in within
//   planarity_tolerance of that face's size (as build_scene wants holes
//   to), since what lies under a face is hidden. Faces without holes
//   joined along shared edges (a rug of tiles, a row of lamp panels) are
//   cut as one, by their joined outline, where that is one loop enclosing
//   just their area (not a ring of tiles: its middle would be an island).
//   Largest first, so a face with holes of its own (a ring: the floor
//   shows through) is not cut.
// - Two convex faces without holes that overlap otherwise by more than the
//   tolerance across are refused with an InputError naming both and a point
//   of the overlap: which one is lit is not defined, and the light would
//   count the area twice.
// - Other pairs (non-convex, holed) go to Scene::coplanar_pairs, for
//   refuse_coplanar_overlaps to test through their triangles.
// Faces that meet along an edge, or facing opposite ways (a block's bottom
// on the floor, a two-sided panel), pass. Returns the cuts as (inner patch,
// outer patch), largest inner face first.
std::vector<std::pair<int, int>> settle_coplanar_faces(Scene& scene, double planarity_tolerance);

// The same refusal for Scene::coplanar_pairs, through the triangles of
// `mesh` (mesh_scene calls it): nothing to do, and no cost, when the list
// is empty.
void refuse_coplanar_overlaps(const Scene& scene, const Mesh& mesh);

}  // namespace radmesh
