// Angles given in degrees in scene files (a JSON scene's rotate_deg, MGF's
// xf -rx/-ry/-rz): exact at multiples of 90, so that a quarter turn of a
// box leaves its coordinates exact.
#pragma once

#include <cmath>

namespace radmesh::internal {

// cos and sin of an angle in degrees.
inline void cos_sin_degrees(double deg, double* c, double* s) {
  const double r = std::fmod(deg, 360.0);
  if (r == std::trunc(r) && std::fmod(r, 90.0) == 0.0) {
    const int q = ((static_cast<int>(r) / 90) % 4 + 4) % 4;
    static const double cs[4][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
    *c = cs[q][0];
    *s = cs[q][1];
    return;
  }
  const double rad = r * (3.14159265358979323846 / 180.0);
  *c = std::cos(rad);
  *s = std::sin(rad);
}

}  // namespace radmesh::internal
