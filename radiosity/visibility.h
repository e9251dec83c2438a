// Visibility between points of the scene, answered by Embree shadow rays.
// Embree types stay inside visibility_embree.cpp.
#pragma once

#include "meshing/geometry.h"
#include "meshing/scene.h"

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

  // True when the open segment (from, to) is unobstructed by every patch but
  // `ignore_a` and `ignore_b` (-1: none). Thread-safe.
  bool visible(const Vec3& from, const Vec3& to, int ignore_a, int ignore_b) const;
  // The same for n segments (from[i], to[i]) at once, into seen[i]: one
  // call to Embree, which traces nearby rays together. Thread-safe.
  void visible(const Vec3* from, const Vec3* to, size_t n, int ignore_a, int ignore_b, unsigned char* seen) const;

  // The patch first hit by the ray from `from` along `direction` (any
  // length) between 1e-7 and 1 times `reach` times the direction's length
  // (a patch lying on `from` is not hit), ignoring patch `ignore`; -1 when
  // it hits nothing. Thread-safe.
  int first_hit(const Vec3& from, const Vec3& direction, double reach, int ignore) const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace radmesh
