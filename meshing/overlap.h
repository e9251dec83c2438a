// Faces that lie in one plane and face the same way: cut out of the face
// they lie in, or refused where they overlap otherwise.
#pragma once

#include "meshing/mesh.h"
#include "meshing/scene.h"

#include <utility>
#include <vector>

namespace radmesh {

// Faces within this fraction of the scene diagonal of one plane cannot be
// told apart by the solve: it is the distance its rays and the field step
// off a surface.
constexpr double kCoplanarOverlapTolerance = 1e-5;

// A face without holes that lies wholly inside another face of its plane,
// facing the same way and clear of that face's edges and holes by more than
// the tolerance (a lamp lying in an uncut ceiling, a rug on the floor), is
// cut out of it: its outline becomes a hole of the other (of the smallest
// such face whose plane it lies in within planarity_tolerance of that
// face's size, as build_scene wants holes to), since what lies under a face
// is hidden from the room. A face with holes of its own (a ring: the floor
// shows through) is not cut. Returns the cuts as (inner patch, outer
// patch), largest inner face first. build_scene calls it.
std::vector<std::pair<int, int>> cut_contained_coplanar_faces(Scene& scene, double planarity_tolerance);

// Two patches that lie in one plane, face the same way and overlap by more
// than the tolerance across, what the cut above leaves (a rug over the
// floor's edge, two rugs over one another): which one is lit is not
// defined and the light counts the area twice, so mesh_scene refuses them
// with an InputError naming both faces and a point of the overlap. Faces
// that meet along an edge, or facing opposite ways (a block's bottom on the
// floor, a two-sided panel), pass. Candidates come from a box tree over the
// patches; convex outlines are tested whole, others through their
// triangles in `mesh`: O(n log n).
void refuse_coplanar_overlaps(const Scene& scene, const Mesh& mesh);

}  // namespace radmesh
