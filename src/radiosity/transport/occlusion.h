// Which patches can block the light between two others: a conservative shaft
// test, so that shadow rays are cast only where something can be in the way.
// The patches that may lie in a shaft are found by a box tree over the
// patches (O(log P + hits) per query, nothing stored per pair of patches);
// a shaft with more than kMaxTests boxes in it is taken as occludable
// without further tests (shadow rays are cheaper than the tests then). A
// clear shaft's rays get through, so the cap moves time, and results only
// where single-precision rays graze.
#pragma once

#include "core/box_tree.h"
#include "radmesh/scene.h"
#include "radmesh/form_factor.h"

#include <array>
#include <atomic>
#include <memory>
#include <vector>

namespace radmesh {

class Occlusion {
public:
  explicit Occlusion(const Scene& scene);

  // Every patch lies on or in front of every other patch's plane: the scene
  // is one convex enclosure (or part of one) and nothing occludes anything.
  bool convex_enclosure() const { return convex_; }

  // Some patch may lie between patches p and q (shaft test), order-free.
  // Remembered per pair where the scene has at most kCachedPatches patches.
  bool may_occlude(int p, int q) const;

  // Patch q has a point strictly in front of patch p's plane and p one in
  // front of q's: they can exchange light.
  bool facing(int p, int q) const;

  // Lower bound of the distance from x to patch p (its outline; holes ignored).
  double distance(int p, const Vec3& x) const;
  // Into `out`, in increasing order: every patch whose bounding box lies
  // within r of x on each axis (among them every patch within distance r).
  void patches_near(const Vec3& x, double r, std::vector<int>& out) const;

  // Whether some patch may lie between elements a (of patch pa) and b (of pb).
  bool may_occlude(int pa, int pb, const Triangle& a, const Triangle& b) const;

  // Whether some patch may lie between the point x (on patch px, normal nx)
  // and the convex planar polygon b (of patch pb, normal nb).
  bool may_occlude(int px, const Vec3& x, const Vec3& nx, int pb, const std::array<Vec3, 4>& b, const Vec3& nb) const;
  bool may_occlude(int px, const Vec3& x, const Vec3& nx, int pb, const Triangle& b) const;

  // The patches that may lie between the point x (on patch px, normal nx)
  // and any part of patch pb: those whose boxes meet the shaft from x to
  // pb's outline and which no supporting plane of that shaft separates
  // from it. A patch separated from the whole shaft is separated from the
  // shaft to any part of pb (its points are points of pb), so a part's
  // shaft need test only these. `all` where there were more than
  // kMaxTests (or more than 4 x kMaxTests boxes met): then the parts are
  // tested as may_occlude does.
  static constexpr int kMaxTests = 8;
  struct Candidates {
    std::array<int, kMaxTests> k{};
    int count = 0;
    bool all = false;
  };
  Candidates candidates(int px, const Vec3& x, const Vec3& nx, int pb) const;
  // may_occlude(px, x, nx, pb, b, nb) for a part b of pb, testing only c.
  bool may_occlude(const Candidates& c, int px, const Vec3& x, const Vec3& nx, int pb, const std::array<Vec3, 4>& b,
                   const Vec3& nb) const;
  bool may_occlude(const Candidates& c, int px, const Vec3& x, const Vec3& nx, int pb, const Triangle& b) const;

  static constexpr size_t kCachedPatches = 4096;

private:
  struct Poly {
    std::vector<Vec3> v;
    Vec3 normal;
    Box3 box;
  };
  // A patch other than pa and pb, with its box in `shaft`, that may lie
  // between the convex polygons a and b (normals na, nb).
  template <class A, class B>
  bool shaft_blocked(int pa, int pb, const A& a, const B& b, const Vec3& na, const Vec3& nb) const;
  // The shaft from the point x to the convex polygon b, after the patches'.
  template <class B>
  bool point_shaft(int px, const Vec3& x, const Vec3& nx, int pb, const B& b, const Vec3& nb) const;
  template <class B>
  bool candidate_shaft(const Candidates& c, int px, const Vec3& x, const Vec3& nx, int pb, const B& b,
                       const Vec3& nb) const;
  std::vector<Poly> polys_;
  BoxTree tree_;
  // Per pair p < q when the scene is small: 0 unknown, 1 clear, 2 may occlude.
  std::unique_ptr<std::atomic<unsigned char>[]> pair_;
  double eps_ = 0.0;
  bool convex_ = false;
};

}  // namespace radmesh
