// Lines where radiosity is discontinuous, known from the geometry alone.
// First kind implemented: contacts (D0), where a patch touches or passes
// through another. Shadow boundaries (D1/D2) come later.
#pragma once

#include "meshing/geometry.h"
#include "meshing/scene.h"

#include <string>
#include <vector>

namespace radmesh {

enum class DiscontinuityMode { off, contacts };

// "off" | "contacts"; throws InputError naming the value otherwise.
DiscontinuityMode parse_discontinuity_mode(const std::string& text);
const char* to_string(DiscontinuityMode mode);

struct DiscontinuitySegment {
  int patch = -1;  // the patch the segment lies on (it becomes a constraint there)
  int other = -1;  // the patch that causes it
  int kind = 0;    // 0 = D0 (contact)
  Vec3 a{0.0}, b{0.0};
};

// Contact segments: for every pair of non-coplanar patches, the part of one
// patch that lies in or crosses the other's plane, clipped to the other's
// polygon (holes respected), minus what runs along that polygon's boundary
// (such lines are mesh edges already). Crossing points are constructed with
// exact arithmetic (CGAL Epeck) and rounded to double once; points within
// 1e-9 of the scene diagonal of a plane count as on it.
std::vector<DiscontinuitySegment> contact_segments(const Scene& scene);

}  // namespace radmesh
