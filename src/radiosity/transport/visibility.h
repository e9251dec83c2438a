// Visibility between points of the scene, answered by Embree shadow rays.
// Embree types stay inside visibility_embree.cpp.
#pragma once

#include "radmesh/geometry.h"
#include "radmesh/scene.h"

#include <memory>

namespace radmesh {

class Visibility {
public:
  // Builds an Embree scene of the patches (their coarsest triangulation:
  // fewer triangles than the mesh, same surfaces). Hits on the patches named
  // in a query are ignored: a planar patch cannot block a segment that starts
  // or ends on it.
  explicit Visibility(const Scene& scene);
  ~Visibility();
  Visibility(const Visibility&) = delete;
  Visibility& operator=(const Visibility&) = delete;

  // Whether each open segment (from[i], to[i]) is unobstructed by every
  // patch but `ignore_a` and `ignore_b` (-1: none), into seen[i], the first
  // and last 1e-6 of it left out: one call to Embree, which traces nearby
  // rays together. Thread-safe.
  void visible(const Vec3* from, const Vec3* to, size_t n, int ignore_a, int ignore_b, unsigned char* seen) const;
  // The same with a patch of its own ignored per segment: ignore_each[i]
  // for segment i (its far end's patch), besides ignore_a for all.
  void visible_each(const Vec3* from, const Vec3* to, size_t n, int ignore_a, const int* ignore_each,
                    unsigned char* seen) const;

  // Segments between points on two surfaces: from[i] on one facing
  // from_normal, to[i] on one facing to_normal (unit normals). Each end is
  // lifted off its surface along its normal by kLift times the scene's
  // diagonal, and the whole segment between the lifted ends is tested. A
  // patch standing on either surface next to an end (a box's wall on the
  // floor) thus blocks the segment however near the end it stands; the open
  // segment of visible() starts 1e-6 of its length past the end, so a floor
  // point nearer than that to a wall would see under the wall.
  static constexpr double kLift = 1e-6;
  void visible_off_surfaces(const Vec3* from, const Vec3& from_normal, const Vec3* to, const Vec3& to_normal, size_t n,
                            int ignore_a, int ignore_b, unsigned char* seen) const;
  bool visible_off_surfaces(const Vec3& from, const Vec3& from_normal, const Vec3& to, const Vec3& to_normal,
                            int ignore_a, int ignore_b) const;
  // The same with surfaces of its own per segment: from[i] on one facing
  // from_normal[i], to[i] on one facing to_normal[i], hits on ignore_a[i]
  // and ignore_b[i] ignored. One call to Embree for all n.
  void visible_off_surfaces_each(const Vec3* from, const Vec3* from_normal, const Vec3* to, const Vec3* to_normal,
                                 const int* ignore_a, const int* ignore_b, size_t n, unsigned char* seen) const;

  // The patch first hit by the ray from `from` along `direction` (any
  // length) between 1e-7 and 1 times `reach` times the direction's length
  // (a patch lying on `from` is not hit), ignoring patch `ignore`; -1 when
  // it hits nothing. Thread-safe.
  int first_hit(const Vec3& from, const Vec3& direction, double reach, int ignore) const;

  // Where a ray from x (on patch `ignore`) along d ends: nowhere (it leaves
  // the scene), on the front of a patch, or on the back of one (or edge on).
  enum class RayEnd { nowhere, front, back };
  RayEnd ray_end(const Vec3& x, const Vec3& d, int ignore) const;
  // Whether x (on patch `ignore`, facing `normal`) is enclosed: each of
  // kEnclosureRays cosine-distributed rays from it (stratified, drawn from
  // `seed`) meets the front of a patch, none open sky or the back of a
  // one-sided patch. There its row of form factors sums to 1.
  static constexpr int kEnclosureRays = 64;
  bool enclosed(const Vec3& x, const Vec3& normal, int ignore, uint64_t seed) const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace radmesh
