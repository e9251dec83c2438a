// Which patches can block the light between two others: a conservative shaft
// test, so that shadow rays are cast only where something can be in the way.
#pragma once

#include "meshing/scene.h"
#include "radiosity/form_factor.h"

#include <vector>

namespace radmesh {

class Occlusion {
public:
  explicit Occlusion(const Scene& scene);

  // Every patch lies on or in front of every other patch's plane: the scene
  // is one convex enclosure (or part of one) and nothing occludes anything.
  bool convex_enclosure() const { return convex_; }

  // Patches that may lie between patches p and q (shaft test), p != q order-free.
  const std::vector<int>& candidates(int p, int q) const;

  // Patch q has a point strictly in front of patch p's plane and p one in
  // front of q's: they can exchange light.
  bool facing(int p, int q) const;

  // Lower bound of the distance from x to patch p (its outline; holes ignored).
  double distance(int p, const Vec3& x) const;

  // Whether some patch may lie between elements a (of patch pa) and b (of pb).
  bool may_occlude(int pa, int pb, const Triangle& a, const Triangle& b) const;

private:
  struct Poly {
    std::vector<Vec3> v;
    Vec3 normal;
    Vec3 lo, hi;
  };
  std::vector<Poly> polys_;
  std::vector<std::vector<int>> cand_;  // np * np, filled for p < q
  double eps_ = 0.0;
  bool convex_ = false;
};

}  // namespace radmesh
