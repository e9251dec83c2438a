// Numbers snapped to a coarse binary grid, so that a scene scaled by any
// factor or moved gives the same numbers where it gave numbers a few ulps
// apart: decisions that break ties by them (CGAL's cocircular points, a
// cluster tree's median split) then come out the same.
#pragma once

#include "radmesh/geometry.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace radmesh::internal {

// x (of order 1: a coordinate in units of the thing's size) to the nearest
// multiple of 2^-33, in two steps: first to 2^-39, which takes off what
// rounding left on it (a scene moved by 10^6 has 3e-13 of the Cornell box's
// size) and so gives back exactly a value halfway between two grid points
// (a midpoint of snapped points) or a quarter of the way; then that exact
// value to 2^-33, ties to even: the same grid point whether it came
// through a scaled scene's rounding or not.
inline double snap_unit(double x) {
  const double fine = std::nearbyint(x * 0x1p39) * 0x1p-39;
  return std::nearbyint(fine * 0x1p33) * 0x1p-33;
}

// A set of points in units of its largest extent from its lowest corner,
// snapped (snap_unit): what a scene scaled or moved puts a few ulps apart
// lands on the same numbers, so that a point on a plane stays on it.
// Directions (unit vectors) are snapped the same way and made unit again.
struct SnappedFrame {
  Vec3 lo{0.0};
  double size = 1.0;
  bool sized = false;  // the points span a finite, positive extent (else lo 0, size 1)

  SnappedFrame() = default;
  explicit SnappedFrame(const std::vector<Vec3>& points) {
    Vec3 hi(-std::numeric_limits<double>::infinity());
    lo = Vec3(std::numeric_limits<double>::infinity());
    for (const Vec3& p : points) {
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
    size = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
    sized = size > 0.0 && std::isfinite(size);
    if (!sized) {
      lo = Vec3(0.0);
      size = 1.0;
    }
  }
  Vec3 to_local(const Vec3& p) const {
    return Vec3(snap_unit((p.x - lo.x) / size), snap_unit((p.y - lo.y) / size), snap_unit((p.z - lo.z) / size));
  }
  Vec3 to_scene(const Vec3& p) const { return lo + p * size; }
  static Vec3 direction(const Vec3& d) {
    const Vec3 s(snap_unit(d.x), snap_unit(d.y), snap_unit(d.z));
    const double length = glm::length(s);
    return length > 0.0 ? s / length : d;
  }
};

// Points as keys for splits that compare them: each in units of the set's
// largest extent from its lowest corner, snapped (SnappedFrame). A tie
// among the points (a regular mesh's centroids in rows, a square's equal
// sides) is then a tie in a scaled or moved scene as well.
inline std::vector<Vec3> snapped_keys(const std::vector<Vec3>& points) {
  const SnappedFrame frame(points);
  if (!frame.sized) return points;
  std::vector<Vec3> keys(points.size());
  for (size_t i = 0; i < points.size(); ++i) keys[i] = frame.to_local(points[i]);
  return keys;
}

}  // namespace radmesh::internal
