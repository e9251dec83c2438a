// Numbers snapped to a coarse binary grid, so that a scene scaled by any
// factor or moved gives the same numbers where it gave numbers a few ulps
// apart: decisions that break ties by them (CGAL's cocircular points, a
// cluster tree's median split) then come out the same.
#pragma once

#include <cmath>

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

}  // namespace radmesh::internal
