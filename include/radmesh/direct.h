// Exact direct illumination with shadows: the reference that meshing error
// is measured against, apart from any solver error.
#pragma once

#include "radmesh/geometry.h"
#include "radmesh/mesh.h"
#include "radmesh/scene.h"
#include "radmesh/solution.h"

#include <memory>
#include <vector>

namespace radmesh {

// What the direct pass did, per (point, emitter) pair.
struct DirectCounts {
  long long behind = 0;      // x behind the emitter, or the emitter behind x's tangent plane: zero
  long long unoccluded = 0;  // the shaft test cleared every occluder: Lambert's formula
  long long clipped = 0;     // exact clip of the occluders the test could not clear
  long long dark = 0;        // ... of which wholly hidden
  long long hidden = 0;      // one convex occluder hides the whole emitter: zero, without a clip
  DirectCounts& operator+=(const DirectCounts& o) {
    behind += o.behind;
    unoccluded += o.unoccluded;
    clipped += o.clipped;
    dark += o.dark;
    hidden += o.hidden;
    return *this;
  }
};

// For a point x on a receiver, every emitter polygon is clipped against the
// occluders as seen from x: each occluder (a whole patch where it is convex,
// without holes and exactly planar, else each of its triangles) is clipped
// to the pyramid from x over the emitter and to the slab between x and the emitter plane,
// projected from x into the emitter's plane, and the union of these shadows
// is subtracted from the emitter polygon (2-D Boolean operations by Clipper,
// exact in integers on a fine grid in the emitter's plane). Lambert's contour
// formula applied to what is left gives the unoccluded-part form factor.
// Rounding happens where the shadows' corners are projected (in double
// precision, in homogeneous coordinates, a shared corner alike for both
// shadows; in exact arithmetic where an occluder comes near x), where they
// are put on the grid, and where the visible polygon is turned
// back into doubles for that formula: results agree with closed forms to
// 1e-15 (tests).
class DirectIllumination {
public:
  explicit DirectIllumination(const Scene& scene);
  ~DirectIllumination();
  DirectIllumination(const DirectIllumination&) = delete;
  DirectIllumination& operator=(const DirectIllumination&) = delete;

  // Form factor from a differential area at x (unit normal n, on patch
  // `receiver`, whose own triangles are not occluders) to the part of emitter
  // patch `emitter` that x sees.
  double visible_form_factor(const Vec3& x, const Vec3& n, int receiver, int emitter) const;

  // The same with nothing occluding (Lambert's closed form for the polygon).
  double unoccluded_form_factor(const Vec3& x, const Vec3& n, int emitter) const;

  // Direct radiosity reflected at x on `patch`: rho * sum over emitters of
  // E_emitter * the visible form factor (per channel). Emission of `patch`
  // itself is not included. Takes the cheapest exact path per emitter: zero
  // when x is behind it or it is behind x's tangent plane; Lambert's formula
  // when a separating-axis test (double precision, with a margin far above
  // rounding) clears every occluder triangle of the pyramid from x over the
  // emitter; zero when the segments from x to every corner of the emitter
  // cross one convex occluder inside its outline; otherwise the exact clip
  // of only the triangles the test could not clear. Adds what it did to
  // `counts` when given.
  Rgb reflected(const Vec3& x, int patch, DirectCounts* counts = nullptr) const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The direct field of a mesh as a per-vertex linear interpolant: the exact
// reflected direct radiosity at every triangle corner (taken a hair inside
// the triangle, so a corner on a contact line gets the value of its own
// side). Per triangle, three corners. Runs in parallel.
std::vector<std::array<Rgb, 3>> direct_corner_values(const DirectIllumination& direct, const Mesh& mesh);

// The same as a field over the mesh: one display vertex per triangle corner
// (so a value may jump across any edge), for interpolate_nodal.
NodalField direct_field(const DirectIllumination& direct, const Mesh& mesh);

}  // namespace radmesh
